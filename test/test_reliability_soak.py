"""Soak, short version: susp_sim_node in real time for 20 s with inputs at 100 Hz and recording on
(``benchmarks/bench_soak.py`` runs the same for 5 minutes). Asserted: RSS growth after the 5 s warm-up
under 5 MB, no deadline miss that a host stall does not explain (a plain sleeping-thread probe runs
beside the node: this VM stalls every thread, the probe's too, by 10-17 ms now and then, or takes its CPUs
away in many short slices; a miss the host did not cause fails the test as before), no rejected
input, a clean exit on SIGINT, and a complete recording (every input sent is recorded, no 10 ms tick
missing on the /sim topics, no sequence gap, finalised)."""
from __future__ import annotations

import importlib.util
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]


def _bench():
    spec = importlib.util.spec_from_file_location("bench_soak", ROOT / "benchmarks" / "bench_soak.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_soak_20_seconds(tmp_path):
    res = _bench().run_soak(duration=20.0, warmup=5.0, out_dir=tmp_path)
    print(f"\nsoak 20 s: RSS {res['rss_after_warmup_mb']:.1f} MB after warm-up, growth "
          f"{res['rss_growth_after_warmup_mb']:.3f} MB; {res['deadline_misses']} deadline misses "
          f"({res['misses_unexplained']} not explained by host stalls, host stall max "
          f"{res['host_stall_max_ms']:.1f} ms) in {res['ticks']} ticks (jitter p99 {res['jitter_p99_ms']:.2f} ms, "
          f"max {res['jitter_max_ms']:.2f} ms); "
          f"sent {res['published_inputs']}, recorded {res['recorded_inputs']}, /sim {res['recorded_sim']}, "
          f"gaps {res['sim_gaps']}, exit {res['node_exit_code']}")
    assert res["node_exit_code"] == 0
    assert res["rss_growth_after_warmup_mb"] < 5.0
    assert res["misses_unexplained"] == 0 and res["ticks"] >= 1900, (
        f"misses at {res['misses_at']}; explained by host stalls {res['misses_by_host']}; "
        f"not explained: {res['misses_not_by_host']}; "
        f"other real-time threads busy meanwhile: {res['other_realtime_busy']}; "
        f"machine busy (others) max {res['machine_busy_other_max']:.2f}, steal max {res['steal_max']:.3f}")
    assert res["rejected_inputs"] == 0
    assert res["recorded_inputs"] == res["published_inputs"] and res["published_inputs"]["/vehicle/speed"] >= 1900
    assert res["sim_gaps"] == 0 and not any(res["sequence_gaps"].values()) and res["finalised"]
    assert res["recorded_sim"]["/sim/imu/data"] >= res["node_published_samples"] >= 1900
    assert res["recording_complete"]
