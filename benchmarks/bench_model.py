"""Model speed: single-vehicle real-time factor, batch throughput, and the CommonRoad peer.

- ``rtf_single``: one vehicle, 1 ms step, the paper's sine steer stretched to 10 s, ``full`` friction
  model; simulated seconds per wall second (compile excluded; best of 5).
- ``batch_vehicle_seconds_per_s``: vehicle-seconds simulated per wall second for 1, 100 and 10,000
  parameter sets (oil levels and friction variants spread over the batch), same maneuver, pitch/roll/yaw
  rates recorded at 100 Hz.
- ``peer_rtf``: the CommonRoad multi-body model (``commonroad-vehicle-models``, 29 states, pure Python,
  scipy ``odeint``) on the same 10 s sine steer, when installed; else null.

Usage: ``python benchmarks/bench_model.py [--json] [--batch 1,100,10000]``
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time

import susp_sim_ros  # noqa: F401  before numpy: idle worker threads sleep (susp_sim_ros/idle_threads.py)
import numpy as np

from susp_sim_ros.model import Model, simulate, simulate_batch
from susp_sim_ros.model.layout import P_INDEX
from susp_sim_ros.model.maneuvers import sine_steer

DT = 0.001
DURATION = 10.0


def bench_single(model, man) -> float:
    U = man.to_inputs(DT)
    simulate(model, U[:10], dt=DT, road=man.road)  # compile / load
    best = math.inf
    for _ in range(5):
        t = time.perf_counter()
        res = simulate(model, U, dt=DT, road=man.road, outputs=["ROLL_RATE", "PITCH_RATE", "YAW_RATE"])
        best = min(best, time.perf_counter() - t)
        assert res.ok
    return DURATION / best


def bench_batch(model, man, n: int) -> float:
    U = man.to_inputs(DT)
    rng = np.random.default_rng(0)
    P = np.tile(model.params(), (n, 1))
    k = P_INDEX["OIL"]
    P[:, k:k + 4] = rng.uniform(0.0, 1.0, (n, 4))
    for flag in ("USE_V", "USE_OIL", "USE_H"):
        P[:, P_INDEX[flag]] = rng.integers(0, 2, n)
    simulate_batch(model, P[:2], U[:10], dt=DT, roads=[man.road])  # compile / load
    best = math.inf
    for _ in range(1 if n >= 10000 else 3):
        t = time.perf_counter()
        res = simulate_batch(model, P, U, dt=DT, roads=[man.road], decim=10,
                             outputs=["ROLL_RATE", "PITCH_RATE", "YAW_RATE"])
        done = res.steps_done
        best = min(best, time.perf_counter() - t)
        assert np.all(done == U.shape[0])
    return n * DURATION / best


def bench_peer(man) -> float | None:
    try:
        from scipy.integrate import odeint
        from vehiclemodels.init_mb import init_mb
        from vehiclemodels.parameters_vehicle2 import parameters_vehicle2
        from vehiclemodels.vehicle_dynamics_mb import vehicle_dynamics_mb
    except ImportError:
        print("peer: commonroad-vehicle-models is not installed (pip install -e '.[bench]'); peer_rtf is null",
              file=sys.stderr)
        return None
    p = parameters_vehicle2()
    ratio = 15.5
    amp, f, t0, per = man.steer_amplitude / ratio, man.steer_frequency, man.steer_start, man.steer_periods

    def steer_rate(t):  # the MB model takes the road-wheel steering velocity as input
        on = t0 <= t <= t0 + per / f
        return amp * 2 * np.pi * f * np.cos(2 * np.pi * f * (t - t0)) if on else 0.0

    x0 = init_mb([0.0, 0.0, 0.0, man.speed, 0.0, 0.0, 0.0], p)
    t = np.arange(0.0, DURATION + DT / 2, DT)
    start = time.perf_counter()
    odeint(lambda x, tt: vehicle_dynamics_mb(x, [steer_rate(tt), 0.0], p), x0, t)
    return DURATION / (time.perf_counter() - start)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--batch", default="1,100,10000")
    ap.add_argument("--no-peer", action="store_true")
    args = ap.parse_args(argv)
    model = Model("passat_b8_like", "full")
    man = sine_steer(duration=DURATION)
    out = {"rtf_single": bench_single(model, man), "batch_vehicle_seconds_per_s": {}}
    for n in (int(x) for x in args.batch.split(",")):
        out["batch_vehicle_seconds_per_s"][str(n)] = bench_batch(model, man, n)
        print(f"batch {n}: {out['batch_vehicle_seconds_per_s'][str(n)]:.0f} vehicle-s/s", file=sys.stderr)
    out["peer_rtf"] = None if args.no_peer else bench_peer(man)
    out["machine"] = f"{platform.machine()} {os.cpu_count()} cores, Python {platform.python_version()}"
    out["date"] = time.strftime("%Y-%m-%d")
    if args.json:
        print(json.dumps(out))
    else:
        print(f"single vehicle: {out['rtf_single']:.0f}x real time (1 ms step, full friction model)")
        for n, v in out["batch_vehicle_seconds_per_s"].items():
            print(f"batch of {n:>6}: {v:,.0f} vehicle-seconds per wall-second")
        if out["peer_rtf"] is not None:
            print(f"CommonRoad multi-body model: {out['peer_rtf']:.1f}x real time "
                  f"(ours {out['rtf_single'] / out['peer_rtf']:.0f}x faster)")
        print(out["machine"], out["date"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
