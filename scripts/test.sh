#!/usr/bin/env bash
# Set up .venv (idempotent, see scripts/setup_venv.sh) and run pytest in it.
# Usage: scripts/test.sh [PYTEST_ARGS...]   (default: test/ -q)
set -euo pipefail

# Anything that starts DDS (rclpy nodes in tests) must stay on this host.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
# Don't inherit the ros_wheels_bootstrapper guard from another venv's process.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

bash "$ROOT/scripts/setup_venv.sh"

if [ "$#" -eq 0 ]; then
    set -- test/ -q
fi
exec "$ROOT/.venv/bin/python" -m pytest "$@"
