#!/usr/bin/env bash
# The README's closed-loop demo: PD alone against PD + feedforward on a
# simulated Orthoglide. Sets up .venv, keeps DDS on this host, picks a ROS
# domain (see scripts/ros_env.sh) and runs scripts/closed_loop_demo.py
# (--help for options; about a minute).
#
# Usage: scripts/closed_loop_demo.sh [--mode stream|trajectory]
#                                    [--loop-rate HZ] [--plant-rate HZ]
#                                    [--trajectories paper,fast] [--plot FILE]
# Env:   ORTHOGLIDE_DEMO_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
source "$(dirname "${BASH_SOURCE[0]}")/ros_env.sh" closed_loop_demo \
    ORTHOGLIDE_DEMO_DOMAIN_ID

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/closed_loop_demo.py" "$@"
