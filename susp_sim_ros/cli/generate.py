"""``susp generate``: write the synthetic reference test drives (the bundled ``bags/``).

The drives come from :mod:`susp_sim_ros.analysis.synthetic`: the model plus hidden physics (amplitude-
dependent friction, small parameter differences) measured through a realistic IMU, reproducible from
``--seed``. Their metadata says ``source: synthetic:...`` and lists the hidden physics.
"""
from __future__ import annotations


from ..analysis import synthetic


def add_arguments(p) -> None:
    p.add_argument("--out", required=True, help="output directory (created if missing), e.g. bags/")
    p.add_argument("--seed", type=int, default=synthetic.DEFAULT_SEED,
                   help=f"random seed of IMU noise, bias and jitter (default {synthetic.DEFAULT_SEED})")
    p.add_argument("--overwrite", action="store_true", help="replace existing drives of the same name")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def run(args) -> dict:
    files = synthetic.generate_bundle(args.out, seed=args.seed, overwrite=args.overwrite,
                                      progress=not args.no_progress)
    total = sum(f["bytes"] for f in files)
    lines = [f"{len(files)} synthetic drives ({synthetic.SOURCE}, seed {args.seed}) in {args.out}, "
             f"{total / 1e6:.2f} MB:"]
    lines += [f"  {f['file']}  {f['bytes'] / 1e3:.0f} kB, {f['duration_s']:.2f} s" for f in files]
    return {"out": str(args.out), "seed": args.seed, "source": synthetic.SOURCE,
            "hidden_physics": synthetic.HiddenPhysics.reference().describe(), "files": files, "total_bytes": total,
            "summary": "\n".join(lines)}
