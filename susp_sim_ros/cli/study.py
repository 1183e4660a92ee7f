"""``susp study``: a parameter study from ``config/studies/*.yaml``, or batch validation of a folder of
recorded drives, on Dask.

    susp study config/studies/bump_oil_inspection.yaml --out results/inspection [--json]
    susp study config/studies/X.yaml --out DIR --scheduler tcp://host:8786     # an existing cluster
    susp study --drives bags --out results/drives [--diagnose]                 # one task per drive

A local cluster (``--workers N`` single-threaded worker processes) by default; ``--scheduler inprocess``
runs without Dask. Finished chunks stream to ``DIR/chunks/``; running the same command again after a kill
resumes without redoing them (``--fresh`` starts over). Progress bar on stderr (runs/s, ETA).
"""
from __future__ import annotations

from ..analysis.sweep import drives_study, load_study, make_executor, run_study
from ..errors import SuspInputError
from ..model.paper import VARIANTS


def add_arguments(p) -> None:
    p.add_argument("study", nargs="?", help="study YAML (config/studies/*.yaml)")
    p.add_argument("--drives", metavar="DIR", help="batch validation over every *.mcap in DIR instead")
    p.add_argument("--diagnose", action="store_true",
                   help="with --drives: also run the discrepancy finder on each drive (against the first variant)")
    p.add_argument("--variants", default=",".join(VARIANTS),
                   help="friction variants of --drives (comma-separated)")
    p.add_argument("--out", required=True, metavar="DIR", help="result directory (table, plots, chunks)")
    p.add_argument("--scheduler", default="local",
                   help="'local' (default: a local Dask cluster), 'inprocess' (no Dask), or the address "
                        "of an existing Dask scheduler, e.g. tcp://10.0.0.5:8786")
    p.add_argument("--connect-timeout", type=float, default=10.0, metavar="S",
                   help="seconds to wait for --scheduler ADDRESS (default 10)")
    p.add_argument("--workers", type=int, default=None,
                   help="workers of the local cluster (default 1; each gets cores/workers kernel threads)")
    p.add_argument("--threads", action="store_true",
                   help="local cluster of threads in this process instead of worker processes")
    p.add_argument("--fresh", action="store_true", help="discard results in --out instead of resuming")
    p.add_argument("--no-plot", action="store_true", help="no PNG figure")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def run(args) -> dict:
    if bool(args.study) == bool(args.drives):
        raise SuspInputError("give a study YAML or --drives DIR (one of them)")
    if args.drives:
        variants = [v.strip() for v in args.variants.split(",") if v.strip()]
        if not variants:
            raise SuspInputError("--variants: give at least one friction variant")
        spec = drives_study(args.drives, variants, diagnose=args.diagnose)
    else:
        if args.diagnose:
            raise SuspInputError("--diagnose goes with --drives DIR (or 'diagnose: true' in a drives study)")
        spec = load_study(args.study)
    if args.workers is not None and args.workers < 1:
        raise SuspInputError(f"--workers: expected at least 1, got {args.workers}")
    workers = args.workers
    if workers is None and spec.kind == "roc":  # its tasks run one car at a time: one worker per core
        workers = spec.data["roc"].get("local_workers")
    executor = make_executor(args.scheduler, workers, processes=not args.threads,
                             connect_timeout_s=args.connect_timeout)
    try:
        return run_study(spec, args.out, executor, progress=not args.no_progress, fresh=args.fresh,
                         plot=not args.no_plot)
    finally:
        executor.close()
