#!/usr/bin/env bash
# The reliability report: set up .venv, keep DDS on this host, pick a
# ROS domain (see scripts/ros_env.sh) and run scripts/reliability_report.py
# (--help for options; about 7 minutes plus the fuzz tests;
# --hostile-only: the hostile peers and stalls alone, about 2 minutes).
#
# Usage: scripts/reliability_report.sh [--duration S] [--cycles N]
#                                      [--seed N] [--skip-fuzz] ...
# Env:   ORTHOGLIDE_TEST_DOMAIN_ID=N   ROS_DOMAIN_ID to use (default: one in
#                                      1..232 drawn from the process id)
source "$(dirname "${BASH_SOURCE[0]}")/ros_env.sh" reliability_report \
    ORTHOGLIDE_TEST_DOMAIN_ID

# The runs measure Fast DDS defaults and config/fastdds_one_host.xml (in a
# network namespace, as root) themselves: no profile from the caller.
unset FASTRTPS_DEFAULT_PROFILES_FILE
# One domain for the runs and for the fuzz tests' pytest (test/conftest.py).
export ORTHOGLIDE_TEST_DOMAIN_ID="$ROS_DOMAIN_ID"

exec "$ROOT/.venv/bin/python" "$ROOT/scripts/reliability_report.py" "$@"
