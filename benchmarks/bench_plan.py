#!/usr/bin/env python3
"""
The planner: how long it plans, how fast its motions are, how exact.

On the robot of doc/programs/drives.yaml (ball-screw drives, friction, a
5 kg payload) with the force limits of doc/programs/drives_limits.yaml
(160, 250, 520 N):

- plan time (CPU, median of ``--repeat``) per program and per gridpoint:
  the contour of doc/programs/contour.nc, a circle of 400 poses (a dense
  polyline, as a nav_msgs/Path brings it), the same circle as one G-code
  arc;
- cycle time against a kinematic planner (a CNC's: one Cartesian
  acceleration limit per axis, the largest that keeps every force within
  its limit on the same program, found by bisection; its time law by
  phase-plane integration, :mod:`orthoglide_testing.phase_plane`),
  printed as a ratio;
- what jerk limits cost in cycle time;
- ``--acceptance``: every sample of the contour re-solved with the
  independent Lagrange model (test/mechanics_reference.py) and the friction
  law, its distance to the programmed path, and its duration against an
  independent optimum (phase-plane integration, friction exact, on
  coefficients of the Lagrange model); the 400-pose circle's distance to
  the circle and duration against the exact circle's optimum. Slow (a few
  minutes: the Lagrange model takes about 70 ms a sample).

- ``--node``: the ``planner`` node as a process, a 400-pose circle sent
  ``--repeat`` times (at least 10): its planning time (its diagnostics)
  and the time from publishing the path to receiving the motion.

Usage: python benchmarks/bench_plan.py [--repeat N] [--acceptance] [--node]
"""

import argparse
import math
import os
import sys
import time

import numpy as np

from orthoglide_ros.formats.params_file import load_robot
from orthoglide_testing import phase_plane, use_checkout
from orthoglide_ros.model import mechanics
from orthoglide_ros.planning import gcode, parametrization
from orthoglide_ros.planning.limits import load_limits
from orthoglide_ros.planning.path import from_moves, from_waypoints
from orthoglide_ros.planning.programs import read_program

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
use_checkout(ROOT)
PROGRAMS = os.path.join(ROOT, 'doc', 'programs')
RATE = 1000.0
CIRCLE_RADIUS = 0.1                        # m
CIRCLE_CENTRE = np.array([0.0, 0.05, -0.05])
CIRCLE_POSES = 400


def circle_poses(count=CIRCLE_POSES):
    """``count`` poses of a full circle, the first and last the same."""
    angles = np.linspace(0.0, 2.0 * math.pi, count)
    return CIRCLE_CENTRE + CIRCLE_RADIUS * np.stack(
        (np.cos(angles), np.sin(angles), np.zeros(count)), 1)


def circle_arc():
    """Return the same circle as one G-code arc from its first pose."""
    start = circle_poses()[0]
    text = f'G21 G90 F1e6\nG3 X{start[0] * 1e3:.9f} Y{start[1] * 1e3:.9f} ' \
        f'I{-CIRCLE_RADIUS * 1e3:.9f} J0'
    return from_moves(gcode.read_gcode(text.replace('F1e6', 'F1000000'),
                                       start), 1e-5)


def programs():
    contour = read_program(os.path.join(PROGRAMS, 'contour.nc'),
                           (0.0, 0.0, 0.0), 1e-5)
    poses = circle_poses()
    polyline = from_waypoints(poses, None, list(range(1, len(poses) + 1)),
                              1e-5)
    return {'contour (doc/programs/contour.nc)': contour,
            f'circle of {CIRCLE_POSES} poses': polyline,
            'circle as one arc': circle_arc()}


def plan_times(robot, limits, repeat):
    print('Plan time (CPU, median of %d)' % repeat)
    print(f'{"program":<36}{"pieces":>8}{"grid":>8}{"plan ms":>10}'
          f'{"us/point":>10}{"duration s":>12}')
    for name, path in programs().items():
        times = []
        for _ in range(repeat):
            start = time.process_time()
            motion = parametrization.plan(robot, path, limits, RATE)
            times.append(time.process_time() - start)
        median = float(np.median(times))
        print(f'{name:<36}{len(path.pieces):>8}{motion.gridpoints:>8}'
              f'{median * 1e3:>10.1f}{median * 1e6 / motion.gridpoints:>10.1f}'
              f'{motion.duration:>12.4f}')


def kinematic(robot, path, limits):
    """
    Return the CNC-style planner's largest Cartesian acceleration limit.

    Returns ``(acceleration, duration)``: the largest per-axis limit
    (m/s^2) whose motion keeps every force within ``limits.effort``.
    """
    kinematic_motion = phase_plane.kinematic_planner(path, RATE)

    def motion(acceleration):
        t, p, v, a = kinematic_motion(acceleration)
        force = mechanics.solve_batch(robot, p, v, a).force
        return float(t[-1]), float((np.abs(force) / limits.effort).max())

    low, high = 0.1, 200.0
    for _ in range(40):
        middle = math.sqrt(low * high)
        if motion(middle)[1] <= 1.0:
            low = middle
        else:
            high = middle
    return low, motion(low)[0]


def cycle_times(robot, limits):
    print('\nCycle time against a kinematic planner (one Cartesian '
          'acceleration limit per axis, the largest within the force limits)')
    print(f'{"program":<36}{"planner s":>11}{"A m/s^2":>9}{"kinematic s":>13}'
          f'{"ratio":>8}')
    for name, path in programs().items():
        ours = parametrization.plan(robot, path, limits, RATE).duration
        acceleration, theirs = kinematic(robot, path, limits)
        print(f'{name:<36}{ours:>11.4f}{acceleration:>9.3g}{theirs:>13.4f}'
              f'{theirs / ours:>8.3f}')


def jerk_cost(robot, limits):
    from orthoglide_ros.planning.limits import Limits
    path = programs()['contour (doc/programs/contour.nc)']
    free = parametrization.plan(robot, path, limits, RATE).duration
    print('\nJerk limits on the contour: what they cost in cycle time')
    print(f'{"max_jerk m/s^3":<16}{"duration s":>12}{"cost":>8}{"CPU ms":>9}')
    print(f'{"none":<16}{free:>12.4f}{"":>8}')
    for jerk in (20000.0, 5000.0, 2000.0, 500.0):
        bounded = Limits(limits.velocity, limits.acceleration,
                         limits.deceleration, np.full(3, jerk),
                         limits.effort, limits.position, limits.names)
        start = time.process_time()
        duration = parametrization.plan(robot, path, bounded, RATE).duration
        cpu = time.process_time() - start
        print(f'{jerk:<16g}{duration:>12.4f}{duration / free - 1:>8.1%}'
              f'{cpu * 1e3:>9.0f}')


def acceptance(robot, limits):
    """Independent checks: Lagrange on every sample, an independent optimum."""
    sys.path.insert(0, os.path.join(ROOT, 'test'))
    import mechanics_reference as reference
    from planning_checks import (friction_reference, lagrange_check,
                                 path_distance)
    print('\nAcceptance (independent model: test/mechanics_reference.py)')
    cases = programs()
    for name, optimum_path, reference_line in (
            ('contour (doc/programs/contour.nc)', None, None),
            (f'circle of {CIRCLE_POSES} poses', cases['circle as one arc'],
             None)):
        path = cases[name]
        start = time.process_time()
        motion = parametrization.plan(robot, path, limits, RATE)
        cpu = time.process_time() - start
        worst = lagrange_check(robot, motion, limits, range(len(motion.t)))
        if optimum_path is None:
            index, w, _, _ = phase_plane.fine_grid(path, 20000)
            dense = path.evaluate(index, w)[0]
            distance = path_distance(motion.position, dense).max()
            what = 'the programmed path'
        else:
            offset = motion.position - CIRCLE_CENTRE
            distance = np.abs(np.hypot(offset[:, 0], offset[:, 1])
                              - CIRCLE_RADIUS).max()
            distance = max(distance, np.abs(offset[:, 2]).max())
            what = 'the circle'
        optimum = independent_optimum(robot, optimum_path or path, limits,
                                      reference, friction_reference)
        print(f'{name}: {len(motion.t)} samples, planned in {cpu:.3f} s CPU')
        print('  worst share of each limit (Lagrange + friction law): '
              + ', '.join(f'{k} {v:.5f}' for k, v in worst.items()))
        print(f'  largest distance to {what}: {distance * 1e6:.2f} um')
        print(f'  duration {motion.duration:.4f} s, independent optimum '
              f'{optimum:.4f} s: {motion.duration / optimum - 1:+.2%}')


def independent_optimum(robot, path, limits, reference, friction):
    """
    Return the phase-plane optimum on the Lagrange model, friction exact.

    The model's a, b, c (forces per u, per x, at rest) and lambda' at
    about one point per millimetre, interpolated along each piece onto a
    grid of 20 points per millimetre.
    """
    index, w, s, stops = phase_plane.fine_grid(path, 20000)
    coarse_index, coarse_w, _, _ = phase_plane.fine_grid(path, 1000)
    p, d1, d2 = path.evaluate(coarse_index, coarse_w)
    frictionless = robot.frictionless()
    inertia = frictionless.replace(gravity=(0.0, 0.0, 0.0))
    a, b, c, lam1 = [], [], [], []
    zero = np.zeros(3)
    for q, v, acc in zip(p, d1, d2):
        c.append(reference.lagrange_forces(frictionless, q, zero, zero).force)
        a.append(reference.lagrange_forces(inertia, q, zero, v).force)
        b.append(reference.lagrange_forces(inertia, q, v, acc).force)
        lam1.append(reference.lambda_jacobian(robot, q) @ v)
    values = [np.array(v) for v in (a, b, c, lam1)]
    fine = []
    for table in values:
        out = np.empty((len(index), 3))
        for k in range(len(path.pieces)):
            at, near = index == k, coarse_index == k
            for j in range(3):
                out[at, j] = np.interp(w[at], coarse_w[near], table[near, j])
        fine.append(out)
    a, b, c, lam1 = fine
    bound = np.broadcast_to(limits.effort, a.shape)
    feed = np.array([path.pieces[k].feed for k in index])
    speed = np.linalg.norm(path.evaluate(index, w)[1], axis=1)
    cap = np.where(stops, 0.0, np.minimum((feed / speed) ** 2, 1e8))
    with np.errstate(divide='ignore'):
        cap = np.minimum(cap, ((limits.velocity / np.abs(lam1)) ** 2).min(1))
    rows = phase_plane.Rows(
        s, a, b, c, -bound, bound, cap,
        lambda i, x: friction(robot, lam1[i] * np.sqrt(
            np.asarray(x))[..., None]))
    return phase_plane.optimal_duration(rows)


def node(repeat):
    """Time the planner node: a 400-pose circle, path in to motion out."""
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.setdefault('ROS_DOMAIN_ID', str(1 + os.getpid() % 232))
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path
    from trajectory_msgs.msg import MultiDOFJointTrajectory
    from orthoglide_testing.hostile import Nodes, Peer
    message = Path()
    message.header.frame_id = 'base_link'
    for point in circle_poses():
        pose = PoseStamped()
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = (
            float(c) for c in point)
        message.poses.append(pose)
    with Nodes() as nodes, Peer() as peer:
        nodes.start('planner')
        pub = peer.publisher(Path, 'path')
        out = peer.record('cartesian_trajectory', MultiDOFJointTrajectory)
        peer.wait(lambda: pub.get_subscription_count() > 0, 30.0)
        peer.wait(lambda: pub.publish(message) or len(out) > 0, 30.0)
        time.sleep(1.0)
        rounds, planning = [], []
        for _ in range(repeat):
            before = len(out)
            start = time.monotonic()
            pub.publish(message)
            peer.wait(lambda: len(out) > before, 30.0)
            rounds.append(out[-1][0] - start)
            status = peer.status('planner', timeout=3.0)
            planning.append(float(status[2]['last planning time (s)']))
    print(f'\nThe planner node, a circle of {CIRCLE_POSES} poses (paper '
          f'robot, config/orthoglide.yaml\'s limits), {repeat} paths:')
    print(f'  planning (the node\'s own clock): median '
          f'{np.median(planning) * 1e3:.1f} ms, max {max(planning) * 1e3:.1f}'
          f' ms; path published to motion received: median '
          f'{np.median(rounds) * 1e3:.1f} ms, max {max(rounds) * 1e3:.1f} ms')


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--repeat', type=int, default=5)
    parser.add_argument('--acceptance', action='store_true')
    parser.add_argument('--node', action='store_true',
                        help='also time the planner node (starts DDS)')
    args = parser.parse_args()
    robot = load_robot(os.path.join(PROGRAMS, 'drives.yaml'))
    limits = load_limits(os.path.join(PROGRAMS, 'drives_limits.yaml'))
    print(f'Robot: doc/programs/drives.yaml; limits {limits.effort} N')
    plan_times(robot, limits, args.repeat)
    cycle_times(robot, limits)
    jerk_cost(robot, limits)
    if args.acceptance:
        acceptance(robot, limits)
    if args.node:
        node(max(args.repeat, 10))


if __name__ == '__main__':
    main()
