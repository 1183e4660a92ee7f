"""What a candidate's values may mean as physics: the extra-damping law's exponent is shape, not effect;
a term is named only at values its physics can take (issue 24)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import susp_sim_ros.analysis.discrepancy.finder as fm
from susp_sim_ros.analysis.discrepancy.candidates import BY_NAME
from susp_sim_ros.analysis.discrepancy.engine import Structure

VISC = BY_NAME["extra_viscous_damping"]


def test_the_exponent_shapes_the_law_and_has_no_effect_of_its_own():
    assert [p.name for p in VISC.params] == ["c_front", "c_rear", "exponent"]
    assert [p.shape for p in VISC.params] == [False, False, True]
    # an exponent far from linear (8 steps) does not make a negative rear damping the dominant sign's
    # exception: the gains decide
    assert not VISC.physical(np.array([5.0, -150.0, 1.8]))
    assert VISC.physical(np.array([-5.0, 150.0, 0.3]))
    # both gains' intervals hold zero: no effect, whatever the exponent's interval says
    lo, hi = np.array([-50.0, -20.0, 1.3]), np.array([60.0, 90.0, 1.7])
    assert VISC.effect_in_interval(lo, hi)
    assert not VISC.effect_in_interval(np.array([10.0, -20.0, 0.9]), np.array([60.0, 90.0, 1.1]))


def _fit(names, x, bic, rss):
    st = Structure(names)
    return SimpleNamespace(structure=st, x=np.asarray(x, float), bic=bic, rss=rss, n=4000)


def test_a_term_at_values_its_physics_cannot_take_is_not_named(monkeypatch):
    """Negative extra damping lowers the criterion as a damper weaker than its curve would: the
    calibration's business. It is refused before the decoys (the evaluator is never asked) and kept as
    clear in the drives (for the competition with calibration values, which skips it as unphysical)."""
    cur = _fit([], [], 100.0, 5000.0)
    weaker = _fit(["extra_viscous_damping"], [-20.0, -300.0, 1.0], 40.0, 4000.0)
    ok, in_sample, checks = fm.DiscrepancyFinder()._passes(None, cur, weaker, {}, 1)
    assert (ok, in_sample) == (False, True) and checks == {"unphysical": ["extra_viscous_damping"]}
    # the same gain positive goes on to the decoys
    monkeypatch.setattr(fm.DiscrepancyFinder, "_decoy_check", staticmethod(lambda ev, a, b: {"decoys_beaten": False}))
    stronger = _fit(["extra_viscous_damping"], [-20.0, 300.0, 0.7], 40.0, 4000.0)
    ok, in_sample, checks = fm.DiscrepancyFinder()._passes(None, cur, stronger, {}, 1)
    assert (ok, in_sample) == (False, True) and checks == {"decoys_beaten": False}


@pytest.mark.parametrize("fixed", [[], [2], [0, 3]])
def test_a_covariance_conditioned_on_shape_parameters(fixed):
    """The covariance with some parameters held: the inverse of the others' information, zero for the
    held ones; with none held, the plain inverse."""
    rng = np.random.default_rng(3)
    a = rng.normal(size=(40, 4))
    info = a.T @ a
    cov = fm._conditioned_on(info, fixed)
    keep = [j for j in range(4) if j not in fixed]
    np.testing.assert_allclose(cov[np.ix_(keep, keep)], np.linalg.inv(info[np.ix_(keep, keep)]), rtol=1e-9)
    assert np.all(cov[fixed, :] == 0.0) and np.all(cov[:, fixed] == 0.0)
