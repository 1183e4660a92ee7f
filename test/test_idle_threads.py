"""Idle worker threads sleep (susp_sim_ros/idle_threads.py): set on import, before numpy, never over the user's."""
import os
import subprocess
import sys

from susp_sim_ros import idle_threads

PROBE = ("import os, susp_sim_ros, numpy; "
         "print(os.environ.get('OPENBLAS_THREAD_TIMEOUT'), os.environ.get('OMP_WAIT_POLICY'))")


def _clean_env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in idle_threads.IDLE_WAIT}
    env.update(extra)
    return env


def test_apply_sets_what_is_missing_and_keeps_what_the_user_chose():
    env = {"OMP_WAIT_POLICY": "ACTIVE", "PATH": "/bin"}
    assert idle_threads.apply(env) == {"OPENBLAS_THREAD_TIMEOUT": "4"}
    assert env == {"OMP_WAIT_POLICY": "ACTIVE", "PATH": "/bin", "OPENBLAS_THREAD_TIMEOUT": "4"}
    assert idle_threads.apply(env) == {}


def test_importing_the_package_sets_them_in_a_fresh_process():
    out = subprocess.run([sys.executable, "-c", PROBE], env=_clean_env(), capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["4", "PASSIVE"]


def test_a_value_the_user_set_is_kept():
    out = subprocess.run([sys.executable, "-c", PROBE], env=_clean_env(OPENBLAS_THREAD_TIMEOUT="28"),
                         capture_output=True, text=True, check=True).stdout.split()
    assert out == ["28", "PASSIVE"]
