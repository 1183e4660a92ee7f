"""Backward elimination and the terms accepted in a pair (issue 24: false discoveries controlled).

A pair of physics terms is accepted when the two together pass the step's tests; when one of them is later
dropped as redundant, the other must earn its place alone (``DiscrepancyFinder._partner_alone``): on the blind
``gas/isothermal_charge_front`` #2 the amplitude friction and an extra damping were accepted as a pair, the
friction dropped later, and the damping stayed, named for a gas spring.

The fits are stand-ins (``fit_structure`` and the held-out test monkeypatched): each structure's criterion is
set by which physics terms it holds, so the test follows the selection logic alone.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from susp_sim_ros.analysis.discrepancy import finder as fm
from susp_sim_ros.analysis.discrepancy.engine import Structure
from susp_sim_ros.analysis.discrepancy.fit import FitResult

AMP, VISC, GAS = "friction_amplitude", "extra_viscous_damping", "damper_gas_preload"


def _run(monkeypatch, bic: dict, passes: dict, names: list[str], accepted: list[dict]):
    """``_backward`` on a structure of ``names`` (beside a time offset) whose fits have the criterion
    ``bic[frozenset(physics terms)]``; the held-out test of a term passes as ``passes[term]``."""
    def fit(ev, st, x0, idx, max_nfev=None, **kw):
        phys = frozenset(n for n in st.names if n != "time_offset")
        return FitResult(st, np.zeros(st.n_params), 1.0, 100, 0, bic[phys], True, "", 0, np.zeros(1), np.zeros((1, 1)))

    def heldout(self, ev, cur, new):
        (added,) = set(new.structure.names) - set(cur.structure.names)
        return {"passed": passes[added], "heldout_gain_fraction_of_excess": 0.1 if passes[added] else -0.5}

    monkeypatch.setattr(fm, "fit_structure", fit)
    monkeypatch.setattr(fm.DiscrepancyFinder, "_heldout_check", heldout)
    f = fm.DiscrepancyFinder.__new__(fm.DiscrepancyFinder)
    cur = fit(None, Structure(["time_offset", *names]), None, ())
    path: list[dict] = []
    out = f._backward(SimpleNamespace(cases=[0, 1, 2]), cur, path, accepted)
    return [n for n in out.structure.names if n != "time_offset"], path, [a["name"] for a in accepted]


def _pair(*extra: dict) -> list[dict]:
    return [{"name": AMP, "with": [AMP, VISC]}, {"name": VISC, "with": [AMP, VISC]}, *extra]


def test_a_partner_that_does_not_earn_its_place_alone_is_dropped_with_the_redundant_term(monkeypatch):
    # removing the friction costs 5 BIC (redundant); the damping alone then 3: it goes too
    bic = {frozenset({AMP, VISC}): 100.0, frozenset({VISC}): 105.0, frozenset(): 108.0}
    kept, path, accepted = _run(monkeypatch, bic, {VISC: True}, [AMP, VISC], _pair())
    assert kept == [] and accepted == []
    assert [p["removed"] for p in path] == [AMP, VISC]
    assert path[1]["why"].startswith(f"accepted in a pair with {AMP} only")
    assert path[1]["delta_bic"] == pytest.approx(-3.0)


def test_a_partner_the_held_out_drives_refuse_alone_is_dropped(monkeypatch):
    bic = {frozenset({AMP, VISC}): 100.0, frozenset({VISC}): 105.0, frozenset(): 150.0}
    kept, path, _ = _run(monkeypatch, bic, {VISC: False}, [AMP, VISC], _pair())
    assert kept == [] and path[-1]["removed"] == VISC and path[-1]["heldout_gain_fraction_of_excess"] == -0.5


def test_a_partner_that_earns_its_place_alone_stays(monkeypatch):
    bic = {frozenset({AMP, VISC}): 100.0, frozenset({VISC}): 105.0, frozenset(): 150.0}
    kept, path, accepted = _run(monkeypatch, bic, {VISC: True}, [AMP, VISC], _pair())
    assert kept == [VISC] and accepted == [VISC] and [p["removed"] for p in path] == [AMP]


def test_a_term_accepted_alone_is_not_judged_again_when_another_is_dropped(monkeypatch):
    # the gas preload accepted on its own step: the friction's drop leaves it as the backward pass judges it
    bic = {frozenset({AMP, GAS}): 100.0, frozenset({GAS}): 105.0, frozenset({AMP}): 130.0, frozenset(): 150.0}
    accepted = [{"name": AMP, "with": [AMP]}, {"name": GAS, "with": [GAS]}]
    kept, path, names = _run(monkeypatch, bic, {GAS: False}, [AMP, GAS], accepted)
    assert kept == [GAS] and names == [GAS] and [p["removed"] for p in path] == [AMP]
