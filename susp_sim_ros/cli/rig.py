"""``susp rig``: the paper's test-rig procedures on the model (half hysteresis width, force-velocity) and
the workshop's wheel-plate bench (EUSAMA % and phase-shift angle per wheel)."""
from __future__ import annotations

from ..errors import SuspInputError
from ..model import Model, rigs
from ..model.linear import plate_resonance_hz
from ..model.rigs import WHEELS, axle_rig, damper_rig, plot_loops
from ..model.params import DEFAULT_VEHICLE


def add_arguments(p) -> None:
    p.add_argument("rig", choices=["axle", "damper", "eusama"],
                   help="axle friction rig, damper hydropulser, or EUSAMA/phase-shift wheel-plate bench")
    p.add_argument("--axle", choices=["front", "rear"], default=None, help="axle and damper rigs: which axle")
    p.add_argument("--fx", type=float, default=0.0, help="axle rig: quasi-static longitudinal force [N]")
    p.add_argument("--fy", type=float, default=0.0, help="axle rig: quasi-static lateral force [N]")
    p.add_argument("--oil", default=None,
                   help="damper rig: oil level 1 intact .. 0 empty (default 1); eusama: FL,FR,RL,RR "
                        "(default 1,1,1,1)")
    p.add_argument("--plate-amplitude", type=float, default=None,
                   help="eusama: plate amplitude [m] instead of config/rigs.yaml eusama.plate_amplitude")
    p.add_argument("--variant", default="full", help="friction variant name or YAML path")
    p.add_argument("--config", default=DEFAULT_VEHICLE, help="vehicle parameter set name or YAML path")
    p.add_argument("--plot", default=None, help="write the hysteresis loop (eusama: force and phase "
                                                "over frequency) as a PNG here")


def _oil_levels(text: str | None, n: int) -> list[float]:
    if text is None:
        return [1.0] * n
    try:
        vals = [float(x) for x in str(text).split(",")]
    except ValueError:
        vals = []
    if len(vals) != n or not all(0.0 <= v <= 1.0 for v in vals):
        want = "one oil level" if n == 1 else "four oil levels FL,FR,RL,RR"
        raise SuspInputError(f"--oil: expected {want} in [0, 1], got {text!r}")
    return vals


def run(args) -> dict:
    if args.rig == "eusama":
        return _run_eusama(args)
    if args.axle is None:
        raise SuspInputError(f"--axle front|rear is required for the {args.rig} rig")
    oil = _oil_levels(args.oil, 1)[0]
    model = Model(args.config, args.variant)
    if args.rig == "axle":
        r = axle_rig(model, args.axle, args.fx, args.fy)
        label = f"{args.axle} axle, Fx {args.fx:.0f} N, Fy {args.fy:.0f} N"
        out = {"half_hysteresis_N": r.half_hysteresis_N, "rig": "axle", "axle": args.axle,
               "fx_N": args.fx, "fy_N": args.fy}
    else:
        if args.fx or args.fy:
            raise SuspInputError("--fx/--fy apply to the axle rig only (the hydropulser is side-force free)")
        r = damper_rig(model, args.axle, oil)
        label = f"{args.axle} damper, oil {oil:.2f}"
        out = {"half_hysteresis_N": r.half_hysteresis_N, "rig": "damper", "axle": args.axle,
               "oil": oil, "force_velocity": r.force_velocity}
    out["variant"] = model.variant.name
    if args.plot:
        plot_loops({label: r}, args.plot, f"{args.rig} rig, 1 mm/s ramp, {model.vehicle.name}")
        out["plot"] = args.plot
    out["summary"] = f"{label}: half hysteresis width at zero deflection {r.half_hysteresis_N:.2f} N"
    return out


def _run_eusama(args) -> dict:
    oil = _oil_levels(args.oil, 4)
    if args.fx or args.fy:
        raise SuspInputError("--fx/--fy apply to the axle rig only")
    cfg = rigs._rig_config("eusama")
    if args.plate_amplitude is not None:
        if not 0.0 < args.plate_amplitude <= 0.02:
            raise SuspInputError(f"--plate-amplitude: expected (0, 0.02] m, got {args.plate_amplitude}")
        cfg["plate_amplitude"] = args.plate_amplitude
    model = Model(args.config, args.variant)
    res = rigs.eusama_bench(model, oil, plate=rigs.eusama_plate_motion(cfg))
    out = {"eusama_percent": {w: r.eusama_percent for w, r in res.items()},
           "phase_shift_min_deg": {w: r.phase_min_deg for w, r in res.items()},
           "resonance_hz": {w: r.resonance_hz for w, r in res.items()},
           "resonance_linear_model_hz": {w: plate_resonance_hz(model.vehicle, i) for i, w in enumerate(WHEELS)},
           "static_load_N": {w: r.static_load_N for w, r in res.items()},
           "oil": dict(zip(WHEELS, oil)), "rig": "eusama", "variant": model.variant.name,
           "plate": {"amplitude_m": cfg["plate_amplitude"], "start_hz": cfg["start_frequency"],
                     "end_hz": cfg["end_frequency"], "sweep_s": cfg["sweep_duration"],
                     "settle_s": cfg["settle_duration"], "one_wheel_at_a_time": True}}
    if args.plot:
        rigs.plot_eusama(res, args.plot, f"EUSAMA bench, oil {','.join(f'{o:g}' for o in oil)}, "
                                         f"{model.vehicle.name}")
        out["plot"] = args.plot
    lines = [f"EUSAMA bench ({1e3 * cfg['plate_amplitude']:.1f} mm plate, {cfg['start_frequency']:g} -> "
             f"{cfg['end_frequency']:g} Hz, one wheel at a time), oil {','.join(f'{o:g}' for o in oil)}:"]
    for w, r in res.items():
        lines.append(f"  {w}: EUSAMA {r.eusama_percent:5.1f} %  min phase {r.phase_min_deg:5.1f} deg  "
                     f"resonance {r.resonance_hz:5.2f} Hz")
    out["summary"] = "\n".join(lines)
    return out
