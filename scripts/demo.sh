#!/usr/bin/env bash
# The README's demo: the feedforward node on the paper's trajectory, eq. (6).
# Sets up .venv (idempotent, see scripts/setup_venv.sh), keeps DDS on this
# host, picks a ROS domain and runs scripts/demo.py (--help for options).
#
# Usage: scripts/demo.sh [--input trajectory|topics] [--rate HZ]
#                        [--duration S] [--plot FILE] [--csv FILE]
# Env:   ORTHOGLIDE_DEMO_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
set -euo pipefail

# Anything that starts DDS must stay on this host.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
# Don't inherit the ros_wheels_bootstrapper guard from another venv's process.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

bash "$ROOT/scripts/setup_venv.sh"

DOMAIN="${ORTHOGLIDE_DEMO_DOMAIN_ID:-$(( 1 + $$ % 232 ))}"
case "$DOMAIN" in
    ''|*[!0-9]*)
        echo "demo: error: ORTHOGLIDE_DEMO_DOMAIN_ID must be a number," \
             "got '$DOMAIN'" >&2
        exit 2 ;;
esac
export ROS_DOMAIN_ID="$DOMAIN"

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/demo.py" "$@"
