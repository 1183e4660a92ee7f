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
  .venv/bin/pip install -q --disable-pip-version-check -e ".[test,bench,import]"
  echo "$want" >"$stamp"
fi
# Foxglove's own message parser and CDR reader for test/test_foxglove_schemas.py (pinned in
# test/foxglove/package-lock.json; that test is skipped, saying why, where node/npm are missing).
fox=test/foxglove
if command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1; then
  want_fox=$(cat "$fox/package.json" "$fox/package-lock.json" | sha256sum | cut -c1-16)
  if [[ "$(cat "$fox/node_modules/.susp-setup" 2>/dev/null)" != "$want_fox" ]]; then
    (cd "$fox" && npm ci --no-audit --no-fund --loglevel=error)
    echo "$want_fox" >"$fox/node_modules/.susp-setup"
  fi
else
  echo "node/npm not found: test/test_foxglove_schemas.py will be skipped" >&2
fi
echo "susp_sim_ros set up in $(pwd)/.venv" >&2
