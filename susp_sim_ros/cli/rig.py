"""``susp rig``: the paper's test-rig procedures on the model (half hysteresis width, force-velocity)."""
from __future__ import annotations

from ..errors import SuspInputError
from ..model import Model
from ..model.rigs import axle_rig, damper_rig, plot_loops


def add_arguments(p) -> None:
    p.add_argument("rig", choices=["axle", "damper"], help="axle friction rig or damper hydropulser")
    p.add_argument("--axle", choices=["front", "rear"], required=True)
    p.add_argument("--fx", type=float, default=0.0, help="axle rig: quasi-static longitudinal force [N]")
    p.add_argument("--fy", type=float, default=0.0, help="axle rig: quasi-static lateral force [N]")
    p.add_argument("--oil", type=float, default=1.0, help="damper rig: oil level, 1 intact .. 0 empty")
    p.add_argument("--variant", default="full", help="friction variant name or YAML path")
    p.add_argument("--config", default="passat_b8_like", help="vehicle parameter set name or YAML path")
    p.add_argument("--plot", default=None, help="write the hysteresis loop as a PNG here")


def run(args) -> dict:
    if not 0.0 <= args.oil <= 1.0:
        raise SuspInputError(f"--oil: expected an oil level in [0, 1], got {args.oil}")
    model = Model(args.config, args.variant)
    if args.rig == "axle":
        r = axle_rig(model, args.axle, args.fx, args.fy)
        label = f"{args.axle} axle, Fx {args.fx:.0f} N, Fy {args.fy:.0f} N"
        out = {"half_hysteresis_N": r.half_hysteresis_N, "rig": "axle", "axle": args.axle,
               "fx_N": args.fx, "fy_N": args.fy}
    else:
        if args.fx or args.fy:
            raise SuspInputError("--fx/--fy apply to the axle rig only (the hydropulser is side-force free)")
        r = damper_rig(model, args.axle, args.oil)
        label = f"{args.axle} damper, oil {args.oil:.2f}"
        out = {"half_hysteresis_N": r.half_hysteresis_N, "rig": "damper", "axle": args.axle,
               "oil": args.oil, "force_velocity": r.force_velocity}
    out["variant"] = model.variant.name
    if args.plot:
        plot_loops({label: r}, args.plot, f"{args.rig} rig, 1 mm/s ramp, {model.vehicle.name}")
        out["plot"] = args.plot
    out["summary"] = f"{label}: half hysteresis width at zero deflection {r.half_hysteresis_N:.2f} N"
    return out
