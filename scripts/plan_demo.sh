#!/usr/bin/env bash
# The planner's demo: a spiral of 1000 chords planned as the curve they
# sample and as lines (--chords-only: that alone, no DDS); then a contour
# program planned (orthoglide plan's core), tracked on the simulated robot
# in MuJoCo with the drives' force limits, against the same path timed
# kinematically for the same duration.
# Sets up .venv, keeps DDS on this host, picks a ROS domain (see
# scripts/ros_env.sh) and runs scripts/plan_demo.py (--help for options;
# about a minute).
#
# Usage: scripts/plan_demo.sh [--engine mujoco|builtin] [--plot FILE]
#                              [--chords-plot FILE] [--chords-only]
# Env:   ORTHOGLIDE_DEMO_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
source "$(dirname "${BASH_SOURCE[0]}")/ros_env.sh" plan_demo \
    ORTHOGLIDE_DEMO_DOMAIN_ID

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/plan_demo.py" "$@"
