#!/usr/bin/env bash
# Run the project's tests in .venv (after scripts/setup.sh), isolated from other ROS 2 traffic.
set -euo pipefail
cd "$(dirname "$0")/.."
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-$(( (RANDOM % 90) + 5 ))}
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_LOG_DIR=${ROS_LOG_DIR:-$(mktemp -d)}
export AMENT_PREFIX_PATH=$(pwd)/.venv
# gates: lint (ruff.toml) and types of the pure layers (setup.cfg [mypy]) before the tests
.venv/bin/ruff check --quiet .
.venv/bin/mypy
exec .venv/bin/python -m pytest -q -p no:cacheprovider "$@" test
