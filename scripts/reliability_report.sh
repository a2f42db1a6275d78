#!/usr/bin/env bash
# Issue 4's reliability report: set up .venv (idempotent, see
# scripts/setup_venv.sh), keep DDS on this host, pick a ROS domain and run
# scripts/reliability_report.py (--help for options; about 5 minutes plus
# the fuzz tests).
#
# Usage: scripts/reliability_report.sh [--duration S] [--cycles N]
#                                      [--seed N] [--skip-fuzz] ...
# Env:   ORTHOGLIDE_TEST_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
set -euo pipefail

# Anything that starts DDS must stay on this host.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
# Don't inherit the ros_wheels_bootstrapper guard from another venv's process.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE
# The runs measure Fast DDS defaults and config/fastdds_discovery.xml
# themselves: no profile from the caller.
unset FASTRTPS_DEFAULT_PROFILES_FILE

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

bash "$ROOT/scripts/setup_venv.sh" >&2

DOMAIN="${ORTHOGLIDE_TEST_DOMAIN_ID:-$(( 1 + $$ % 232 ))}"
case "$DOMAIN" in
    ''|*[!0-9]*)
        echo "reliability_report: error: ORTHOGLIDE_TEST_DOMAIN_ID must be" \
             "a number, got '$DOMAIN'" >&2
        exit 2 ;;
esac
# One domain for the runs and for the fuzz tests' pytest (test/conftest.py).
export ROS_DOMAIN_ID="$DOMAIN" ORTHOGLIDE_TEST_DOMAIN_ID="$DOMAIN"

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/reliability_report.py" "$@"
