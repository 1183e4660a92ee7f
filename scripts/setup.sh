#!/usr/bin/env bash
# Set up everything on a fresh Debian/Python 3.11 machine: a venv (.venv) with the ROS 2 Jazzy wheels
# from PyPI (see ../shared/stack.md) and this package installed editable with its test extras.
# Idempotent: re-running only installs what changed.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [[ ! -x .venv/bin/python ]]; then
  "$PY" -m venv .venv
fi
stamp=.venv/.susp-setup
want=$(cat setup.py scripts/setup.sh | sha256sum | cut -c1-16)
if [[ "$(cat "$stamp" 2>/dev/null)" != "$want" ]]; then
  .venv/bin/pip install -q --disable-pip-version-check \
    "ros-jazzy-rclpy[fastrtps]==7.1.6" ros-jazzy-common-interfaces==5.3.6 ros-jazzy-rmw-fastrtps-cpp==8.4.3
  .venv/bin/pip install -q --disable-pip-version-check -e ".[test,bench]"
  echo "$want" >"$stamp"
fi
echo "susp_sim_ros set up in $(pwd)/.venv" >&2
