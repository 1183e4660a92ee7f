"""How the process's worker threads wait between calls: they sleep at once instead of spinning.

The simulation kernel runs vehicles in parallel on numba's threads (its OpenMP layer where GNU OpenMP is
there), and the fits' linear algebra (numpy's and scipy's OpenBLAS) on OpenBLAS's own threads; a
diagnosis alternates between the two thousands of times. By default both libraries keep their threads
busy-waiting after a call (OpenBLAS for 2^28 cycles, GNU OpenMP for 300 000 spins), so on a machine
with as many cores as threads each pool took cores from the other: the trust-region solver's SVD of a
19 000 x 27 Jacobian took 45-58 ms after a kernel call and 13 ms alone, and the kernel ran at about half
its speed after an SVD. Idle threads that sleep at once give the diagnosis of the bundled drives from
``dahl_only`` in 56-60 s instead of 88 s, from ``full`` in 46 s instead of 77 s (benchmarks/RESULTS.md,
"Diagnosis run time", 2026-12-07 15:16-15:42). Only the waiting changes: the thread counts, the work each
thread does and so every number stay the same bit for bit (the diagnosis's JSON output is identical).

The settings are environment variables the libraries read when they load: :func:`apply` sets those the
user has not set and must run before numpy is imported (OpenBLAS reads its variable then) and before the
kernel's first parallel call (GNU OpenMP's). ``import susp_sim_ros`` runs it, so the ``susp`` command,
the node, the benchmarks and the tests, which import the package before numpy, get it; a program that
imports numpy first keeps OpenBLAS's default (set ``OPENBLAS_THREAD_TIMEOUT=4`` in its environment).
"""
from __future__ import annotations

import os
from collections.abc import MutableMapping

#: variable -> value. ``OPENBLAS_THREAD_TIMEOUT``: an idle OpenBLAS thread sleeps after 2^4 cycles (4 is
#: the smallest value OpenBLAS accepts; its default is 28). ``OMP_WAIT_POLICY``: OpenMP threads wait
#: passively (sleep) between parallel regions.
IDLE_WAIT = {"OPENBLAS_THREAD_TIMEOUT": "4", "OMP_WAIT_POLICY": "PASSIVE"}


def apply(environ: MutableMapping[str, str] | None = None) -> dict[str, str]:
    """Set each :data:`IDLE_WAIT` variable the environment (default ``os.environ``) does not have;
    returns the ones set (a value the user chose is kept)."""
    env = os.environ if environ is None else environ
    set_now = {k: v for k, v in IDLE_WAIT.items() if k not in env}
    env.update(set_now)
    return set_now
