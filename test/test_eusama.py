"""The virtual EUSAMA / phase-shift wheel-plate bench (issue 14): plausible figures on the reference car,
one wheel at a time, resonance against the linear model, CLI keys and bad input."""
import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, strategies as st

from susp_sim_ros.cli.rig import _oil_levels
from susp_sim_ros.errors import SuspInputError
from susp_sim_ros.model import rigs
from susp_sim_ros.model.linear import plate_resonance_hz


@pytest.fixture(scope="module")
def bench(model_full):
    cache = {}

    def run(oil):
        if oil not in cache:
            cache[oil] = rigs.eusama_bench(model_full, oil)
        return cache[oil]
    return run


def test_plate_motion_is_the_documented_input():
    cfg = rigs._rig_config("eusama")
    pm = rigs.eusama_plate_motion()
    sweep = pm.z[pm.sweep_start:]
    assert np.max(np.abs(sweep)) == pytest.approx(cfg["plate_amplitude"], rel=1e-3)
    assert pm.frequency_hz[pm.sweep_start] == pytest.approx(cfg["start_frequency"])
    assert pm.frequency_hz[-1] == pytest.approx(cfg["end_frequency"], rel=0.01)
    assert np.all(np.diff(pm.frequency_hz) <= 0)  # swept downwards through the wheel resonance


def test_intact_well_above_40_and_oil_empty_well_below(bench):
    intact = bench((1.0, 1.0, 1.0, 1.0))
    for w, r in intact.items():
        assert r.eusama_percent > 50.0, w   # the usual limit is 40 %
    empty_rl = bench((1.0, 1.0, 0.0, 1.0))["RL"]
    empty_fl = bench((0.0, 1.0, 1.0, 1.0))["FL"]
    assert empty_rl.eusama_percent < 25.0 and empty_fl.eusama_percent < 30.0
    # the phase-shift angle drops with the damping too
    assert empty_rl.phase_min_deg < intact["RL"].phase_min_deg - 30
    assert empty_fl.phase_min_deg < intact["FL"].phase_min_deg - 30


def test_eusama_falls_with_oil_loss_and_only_on_the_excited_wheel(bench):
    vals = [bench((o, 1.0, 1.0, 1.0))["FL"].eusama_percent for o in (1.0, 0.5, 0.0)]
    assert vals[0] > vals[1] > vals[2]
    # wheels are excited one at a time: an empty FL leaves the FR and rear readings alone
    a, b = bench((1.0, 1.0, 1.0, 1.0)), bench((0.0, 1.0, 1.0, 1.0))
    for w in ("FR", "RL", "RR"):
        assert b[w].eusama_percent == pytest.approx(a[w].eusama_percent, abs=1.0), w


def test_resonance_matches_linear_model(model_full):
    """With the friction levels at zero, oil-empty dampers (only the empty curve's small viscous slope)
    and a small plate amplitude (no lift-off), the bench is nearly linear: its resonance must be the
    linear model's. 3 %: the downward sweep (1.4 Hz/s) and the per-cycle frequency resolution."""
    P = model_full.params((0.0, 0.0, 0.0, 0.0))
    for term in ("axle_friction", "damper_friction"):
        P[model_full.term_param_slice(term, "level")] = 0.0
    cfg = rigs._rig_config("eusama")
    cfg["plate_amplitude"] = 0.0005
    res = rigs.eusama_bench(model_full, (0.0, 0.0, 0.0, 0.0), P=P, plate=rigs.eusama_plate_motion(cfg))
    for i, w in enumerate(rigs.WHEELS):
        assert res[w].resonance_hz == pytest.approx(plate_resonance_hz(model_full.vehicle, i), rel=0.03), w


def _susp(*args):
    r = subprocess.run([sys.executable, "-m", "susp_sim_ros.cli.main", *args], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def test_cli_json_keys_and_bad_oil():
    rc, out, err = _susp("rig", "eusama", "--oil", "1,1,0,1", "--json")
    assert rc == 0, err
    d = json.loads(out)
    for key in ("eusama_percent", "phase_shift_min_deg", "resonance_hz"):
        assert set(d[key]) == {"FL", "FR", "RL", "RR"}
    assert d["eusama_percent"]["FL"] > 40 and d["eusama_percent"]["RL"] < d["eusama_percent"]["RR"] - 10
    for bad in ("1,1,2,1", "1,1,1", "a,b,c,d"):
        rc, _, err = _susp("rig", "eusama", "--oil", bad)
        assert rc == 2 and "--oil" in err and "Traceback" not in err


@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=6))
def test_oil_parser_accepts_exactly_four_fractions(vals):
    text = ",".join(repr(v) for v in vals)
    ok = len(vals) == 4 and all(0.0 <= v <= 1.0 for v in vals)
    if ok:
        assert _oil_levels(text, 4) == pytest.approx(vals)
    else:
        with pytest.raises(SuspInputError):
            _oil_levels(text, 4)
