#!/usr/bin/env bash
# The README's demo: the feedforward node on the paper's trajectory, eq. (6).
# Sets up .venv, keeps DDS on this host, picks a ROS domain (see
# scripts/ros_env.sh) and runs scripts/demo.py (--help for options).
#
# Usage: scripts/demo.sh [--input trajectory|topics] [--rate HZ]
#                        [--duration S] [--plot FILE] [--csv FILE]
# Env:   ORTHOGLIDE_DEMO_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
source "$(dirname "${BASH_SOURCE[0]}")/ros_env.sh" demo ORTHOGLIDE_DEMO_DOMAIN_ID

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/demo.py" "$@"
