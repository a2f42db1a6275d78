#!/usr/bin/env bash
# Set up .venv (idempotent, see scripts/setup_venv.sh) and run pytest in it:
# first on every core (pytest-xdist) without the tests marked `serial`,
# then those alone (timing verdicts kept off a parallel neighbour, each
# marked with its reason in a comment by it), only if the selection holds any.
# Usage: scripts/test.sh [PYTEST_ARGS...]   (default: test/ -q)
#        -n N among the arguments (-n 0: one process) runs pytest once, as given.
# Env:   ORTHOGLIDE_TEST_WORKERS=N   workers (default: the cores, at most 4)
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
PYTEST=("$ROOT/.venv/bin/python" -m pytest)
CORES="$(nproc)"
WORKERS="${ORTHOGLIDE_TEST_WORKERS:-$(( CORES < 4 ? CORES : 4 ))}"
for arg in "$@"; do
    case "$arg" in -n*|--numprocesses*|no:xdist) WORKERS=given ;; esac
done
if [ "$WORKERS" = given ] || [ "$WORKERS" -le 1 ]; then
    exec "${PYTEST[@]}" "$@"
fi

COUNT="$(mktemp)"
trap 'rm -f "$COUNT"' EXIT
code=0
ORTHOGLIDE_TEST_PHASE=parallel ORTHOGLIDE_SERIAL_COUNT="$COUNT" \
    "${PYTEST[@]}" -n "$WORKERS" --dist worksteal "$@" || code=$?
# 2: interrupted, or a collection error: the serial phase would not help.
[ "$code" = 2 ] && exit 2
# 5: no test selected in that phase.
if [ "$(cat "$COUNT")" != 0 ] && [ "$(cat "$COUNT")" != "" ]; then
    echo "test.sh: the $(cat "$COUNT") serial test(s), alone"
    serial=0
    ORTHOGLIDE_TEST_PHASE=serial "${PYTEST[@]}" "$@" || serial=$?
    if [ "$code" = 5 ] || { [ "$code" = 0 ] && [ "$serial" != 5 ]; }; then
        code=$serial
    fi
fi
exit "$code"
