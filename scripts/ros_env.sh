# Sourced by the scripts that start DDS (demos, reliability report): set up
# .venv (idempotent, see scripts/setup_venv.sh; its output on stderr), keep
# DDS on this host and choose the ROS domain. Sets ROOT.
#
# Usage: source scripts/ros_env.sh TOOL DOMAIN_VARIABLE
#   TOOL names the caller in errors; the environment variable named by
#   DOMAIN_VARIABLE, if set, is the ROS_DOMAIN_ID to use (default: one in
#   1..232 drawn from the process id).
set -euo pipefail

# Anything that starts DDS must stay on this host.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
# Don't inherit the ros_wheels_bootstrapper guard from another venv's process.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

bash "$ROOT/scripts/setup_venv.sh" >&2

DOMAIN="${!2:-$(( 1 + $$ % 232 ))}"
case "$DOMAIN" in
    ''|*[!0-9]*)
        echo "$1: error: $2 must be a number, got '$DOMAIN'" >&2
        exit 2 ;;
esac
export ROS_DOMAIN_ID="$DOMAIN"
