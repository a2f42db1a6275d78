#!/usr/bin/env python3
"""
Benchmark and accuracy of the URDF and the mechanism state publisher's core.

Measures, without ROS:

- the core's work per joint state (``MechanismState.joint_state``: the
  sliders by name, the forward kinematics, every joint), positions only and
  with velocities, each call timed after a warm-up: median and p99 (us);
- how far the URDF's cuts are from closing with those joint states, by
  yourdfpy's forward kinematics, over random configurations within the
  margin on the home branch (the worst distance, m, and angle, rad);
- the worst relative difference between the forces of Pinocchio's RNEA on
  the URDF (projected by virtual work, as test/test_urdf_dynamics.py does)
  and ``mechanics.solve``, on the paper's trajectory and a fast one without
  gravity;
- the time of ``orthoglide urdf`` (the URDF with its joint limits).

Needs the test dependencies (yourdfpy, pin). Usage:
python benchmarks/bench_mechanism_state.py [--calls N] [--configurations N]
"""

import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, 'test'))

from orthoglide_ros.model import trajectory  # noqa: E402
from orthoglide_ros.model import mechanics  # noqa: E402
from orthoglide_ros.cores.mechanism_state_publisher import (  # noqa: E402
    joint_state, MechanismState, PARAMETERS)
from orthoglide_ros.model.robot import Robot  # noqa: E402
from orthoglide_ros.model.urdf import urdf  # noqa: E402

NAMES = ['slider_a', 'slider_b', 'slider_c']


def timing(calls):
    """Median and p99 (us) of the core's joint_state, without/with rates."""
    core = MechanismState(PARAMETERS.parse({}))
    s = mechanics.solve(Robot(), (0.05, 0.1, -0.2), (0.1, -0.1, 0.2))
    rows = []
    for label, rates in (('positions only', []),
                         ('with velocities', list(s.lambdadot))):
        for _ in range(200):
            core.joint_state(NAMES, list(s.lambda_), rates, 0.0)
        times = []
        for _ in range(calls):
            start = time.perf_counter_ns()
            core.joint_state(NAMES, list(s.lambda_), rates, 0.0)
            times.append(time.perf_counter_ns() - start)
        times = np.array(times) / 1e3
        rows.append((label, np.median(times), np.percentile(times, 99)))
    return rows


def closure(count):
    """Worst distance (m) and angle (rad) of the cuts, yourdfpy's FK."""
    from mechanics_reference import leg_geometry, LEGS
    from urdf_harness import COMMITTED_URDF, cut_errors, load
    robot = Robot()
    model = load(COMMITTED_URDF.read_text())
    rng = np.random.default_rng(1)
    points = rng.uniform(-0.6 * robot.l3, 0.6 * robot.l3, (40 * count, 3))
    points = points[mechanics.workspace_status(robot, points).ok]
    lam = mechanics.solve_batch(robot, points).lambda_
    back, found = mechanics.forward_kinematics_rows(robot, lam)
    home = found & (np.abs(back - points).max(-1) < 1e-9)
    worst = [0.0, 0.0]
    for position, sliders in list(zip(points[home], lam[home]))[:count]:
        state = joint_state(robot, NAMES, sliders)
        phi32 = np.arcsin([leg_geometry(robot, leg, position).sin32
                           for leg in LEGS])
        errors = cut_errors(model, state.names, state.position, position,
                            phi32)
        worst = [max(w, e) for w, e in zip(worst, errors)]
    return worst


def dynamics():
    """Worst relative force difference, RNEA vs mechanics.solve."""
    import test_urdf_dynamics as check
    from urdf_harness import COMMITTED_URDF
    import pinocchio
    model = pinocchio.buildModelFromXML(COMMITTED_URDF.read_text())
    rows = []
    cases = (('paper trajectory, gravity', Robot(),
              trajectory.paper_batch(trajectory.paper_times(41))),
             ('fast, no gravity', Robot(gravity=(0.0, 0.0, 0.0)),
              trajectory.paper_batch(np.linspace(0.0, 0.785, 41),
                                     (0.15, 0.15, 0.15), 8.0)))
    for label, robot, samples in cases:
        worst = 0.0
        for p, v, a in zip(*samples):
            want = np.array(mechanics.solve(robot, p, v, a).force)
            got = check.urdf_forces(model, robot, p, v, a)
            worst = max(worst, np.abs(got - want).max() / np.abs(want).max())
        rows.append((label, worst))
    return rows


def main():
    """Run the measurements; print them."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--calls', type=int, default=5000)
    parser.add_argument('--configurations', type=int, default=200)
    args = parser.parse_args()
    for label, median, p99 in timing(args.calls):
        print(f'joint_state, {label:16}: median {median:7.1f} us, p99 '
              f'{p99:7.1f} us')
    distance, angle = closure(args.configurations)
    print(f'cuts over {args.configurations} configurations: worst '
          f'{distance:.2g} m, {angle:.2g} rad')
    for label, worst in dynamics():
        print(f'RNEA vs mechanics.solve, {label}: worst {worst:.2g} relative')
    start = time.perf_counter()
    urdf(Robot())
    print(f'urdf(Robot()): {time.perf_counter() - start:.2f} s')


if __name__ == '__main__':
    main()
