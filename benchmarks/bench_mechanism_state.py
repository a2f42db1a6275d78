#!/usr/bin/env python3
"""
Benchmark and accuracy of the URDF and the mechanism state publisher's core.

Measures, without ROS:

- the core's work per joint state (``MechanismState.joint_state``: the
  sliders by name, the forward kinematics, every joint), positions only and
  with velocities, each call timed after a warm-up: median and p99 (us);
- the time of ``orthoglide urdf`` (the URDF with its joint limits);

each for the paper's robot and for a robot as built
(``robots_as_built.BUILT``: each leg's joint limits its own).

How closely the URDF's cuts close (yourdfpy) and its dynamics agree with
the model (Pinocchio's RNEA) are the tests' (``test/test_urdf.py``,
``test/test_urdf_dynamics.py``; ``pytest -s`` prints the worst force
difference). Usage: python benchmarks/bench_mechanism_state.py [--calls N]
"""

import argparse
import time

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.cores.mechanism_state_publisher import (
    MechanismState, PARAMETERS)
from orthoglide_ros.model.urdf import urdf
from orthoglide_testing.robots_as_built import BUILT

NAMES = ['slider_a', 'slider_b', 'slider_c']
# The robots measured: their robot.* parameters.
ROBOTS = {'drawing': {}, 'as built': {f'robot.{name}': list(value)
                                      for name, value in BUILT.items()}}


def timing(calls, parameters):
    """Median and p99 (us) of the core's joint_state, without/with rates."""
    core = MechanismState(PARAMETERS.parse(parameters))
    s = mechanics.solve(core.settings.robot, (0.05, 0.1, -0.2),
                        (0.1, -0.1, 0.2))
    rows = []
    for label, rates in (('positions only', []),
                         ('with velocities', list(s.lambdadot))):
        for _ in range(200):
            core.joint_state((1, 0), '', NAMES, list(s.lambda_), rates, (), 0.0)
        times = []
        for _ in range(calls):
            start = time.perf_counter_ns()
            core.joint_state((1, 0), '', NAMES, list(s.lambda_), rates, (), 0.0)
            times.append(time.perf_counter_ns() - start)
        times = np.array(times) / 1e3
        rows.append((label, np.median(times), np.percentile(times, 99)))
    return rows


def main():
    """Run the measurements; print them."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--calls', type=int, default=5000)
    args = parser.parse_args()
    for robot, parameters in ROBOTS.items():
        for label, median, p99 in timing(args.calls, parameters):
            print(f'{robot:8}, joint_state, {label:16}: median {median:7.1f} '
                  f'us, p99 {p99:7.1f} us')
    for robot, parameters in ROBOTS.items():
        start = time.perf_counter()
        urdf(PARAMETERS.parse(parameters).robot)
        print(f'{robot:8}, urdf: {time.perf_counter() - start:.2f} s')


if __name__ == '__main__':
    main()
