#!/usr/bin/env bash
# The calibration demo: a simulated machine whose legs are off the drawing,
# measured at the positions orthoglide calibration-poses designs (its
# platform/pose plus 10 um of noise as the instrument), calibrated by
# orthoglide calibrate, then the same motion tracked before (the drawing)
# and after (the calibrated file). Sets up .venv, keeps DDS on this host,
# picks a ROS domain (see scripts/ros_env.sh) and runs
# scripts/calibration_demo.py (--help for options; about a minute and a
# half).
#
# Usage: scripts/calibration_demo.sh [--count N] [--noise M] [--seed N] [--move S]
#                                    [--hold S] [--out DIR] [--realtime] [--load N]
# Env:   ORTHOGLIDE_DEMO_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
source "$(dirname "${BASH_SOURCE[0]}")/ros_env.sh" calibration_demo \
    ORTHOGLIDE_DEMO_DOMAIN_ID

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/calibration_demo.py" "$@"
