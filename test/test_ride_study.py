"""The semi-active controller study (``kind: ride``, issue 15): validation, a run on Dask that resumes
after an interrupt with the same table as a plain run, the benefit table and the figure."""
import csv
import json

import pytest

from _cli_helpers import Interrupt, stop_after
from susp_sim_ros.analysis.sweep import InProcessExecutor, load_study, make_executor, run_study, study_from_dict
from susp_sim_ros.errors import ConfigError

SMALL = {"name": "ride_small", "kind": "ride", "speed_kmh": 80, "duration_s": 5, "seed": 7,
         "parameters": {"controller": ["passive", "skyhook"], "oil": [[1, 1, 1, 1], [1, 1, 0, 0]],
                        "road_class": ["C"], "variant": ["full"]}}


def test_bundled_study_expands_to_the_full_grid():
    spec = load_study("config/studies/semiactive.yaml")
    assert spec.kind == "ride" and spec.n_runs == 6 * 3 * 3 * 2 == len(spec.chunks)
    assert {r["variant"] for r in spec.runs} == {"full", "dahl_only"}
    assert {r["oil"] for r in spec.runs} == {"1,1,1,1", "1,1,0.5,0.5", "1,1,0,0"}


@pytest.mark.parametrize("bad", [
    {"parameters": {"controller": ["bogus"]}},
    {"parameters": {"oil": [[1, 1, 1]]}},
    {"parameters": {"road_class": ["Z"]}},
    {"parameters": {"variant": ["nope"]}},
    {"speed_kmh": -3},
    {"seed": 1.5},
    {"maneuver": "bump_crossing"},
])
def test_bad_ride_study_is_a_clear_config_error(bad):
    data = {**json.loads(json.dumps(SMALL)), **bad}
    with pytest.raises(ConfigError):
        study_from_dict(data, "bad.yaml")


def _table(path):
    return path.read_text()


def test_ride_study_on_dask_resumes_and_equals_a_plain_run(tmp_path):
    spec = study_from_dict(json.loads(json.dumps(SMALL)), "small.yaml")
    plain = run_study(spec, tmp_path / "plain", InProcessExecutor(), progress=False)
    out = tmp_path / "out"
    ex = make_executor("local", 1)
    try:
        with pytest.raises(Interrupt):
            run_study(spec, out, ex, progress=False, on_chunk=stop_after(2))
        assert len(list((out / "chunks").glob("d*.json"))) == 2 and not (out / "ride.csv").exists()
        res = run_study(spec, out, ex, progress=False)
    finally:
        ex.close()
    assert res["chunks_resumed"] == 2 and res["chunks_computed"] == 2 and res["runs_ok"] == 4
    assert _table(out / "ride.csv") == _table(tmp_path / "plain" / "ride.csv")
    rows = list(csv.DictReader(open(out / "ride_benefit.csv")))
    assert {(r["controller"], r["oil"]) for r in rows} == {("skyhook", "1,1,1,1"), ("skyhook", "1,1,0,0")}
    assert all(float(r["comfort_change"]) < 0 for r in rows)  # skyhook improves comfort in both states
    assert plain["plots"] and (tmp_path / "plain" / "ride_small.png").stat().st_size > 10_000
