#!/usr/bin/env bash
# The identification demo: excite a simulated Orthoglide whose masses and
# friction the feedforward does not know, record it (orthoglide record),
# identify it (orthoglide identify) and track with the identified model.
# Sets up .venv, keeps DDS on this host, picks a ROS domain (see
# scripts/ros_env.sh) and runs scripts/identification_demo.py (--help for
# options; about two minutes).
#
# Usage: scripts/identification_demo.sh [--seed N] [--period S] [--passes K] [--repeats R]
#                                       [--trajectories paper,fast] [--out DIR]
# Env:   ORTHOGLIDE_DEMO_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
source "$(dirname "${BASH_SOURCE[0]}")/ros_env.sh" identification_demo \
    ORTHOGLIDE_DEMO_DOMAIN_ID

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/identification_demo.py" "$@"
