"""Writes test/data/passive_reference.npz: passive-damper outputs of the code before the semi-active
damper (commit db28f86), for test_semiactive_damper.py (bit-for-bit).
Run: python test/data/make_passive_reference.py OUT.npz"""
import numpy as np
import sys
from susp_sim_ros.model import Model
from susp_sim_ros.model.maneuvers import paper_maneuver, vehicle_state
from susp_sim_ros.model.vehicle import simulate
from susp_sim_ros.runtime.lockstep import maneuver_drive, run_lockstep
COLS = ["ROLL_RATE","PITCH_RATE","YAW_RATE","AX_SF","AY_SF","AZ_SF","DEFL_FL","DEFL_FR","DEFL_RL","DEFL_RR",
        "F_DAMPER_FL","F_DAMPER_FR","F_DAMPER_RL","F_DAMPER_RR","F_FRICTION_FL","F_FRICTION_RR","F_Z_FL","F_Z_RR"]
m = Model("passat_b8_like", "full")
out = {}
man = paper_maneuver("bump_crossing")
d = maneuver_drive(man, vehicle_state("rear_empty"), rate_hz=1000.0)
r = run_lockstep(d, model=m, oil=vehicle_state("rear_empty"))
out["lockstep_bump_rear_empty"] = np.stack([r[c] for c in COLS], 1)
man2 = paper_maneuver("sine_steer")
res = simulate(m, man2.to_inputs(0.001), dt=0.001, road=None, oil=vehicle_state("front_empty"), decim=50, outputs=COLS)
out["simulate_sine_front_empty"] = res.y
np.savez_compressed(sys.argv[1], columns=np.array(COLS), **out)
print({k: v.shape for k, v in out.items()})
