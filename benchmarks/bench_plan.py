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

- chords as CAM writes them: a 3D loop of 95 chords under plain G64
  against toppra's optimum along the true curve (``--acceptance``: and
  the Lagrange model on every sample), its distance to that curve, its
  points' to the path; the spiral of LinuxCNC's ``nc_files/spiral.ngc``
  (:mod:`orthoglide_testing.chord_programs` reconstructs it; ``--spiral
  FILE`` plans a copy of the file itself too, as plain G64) at the
  default tolerance, at 1 mm and as lines blended within 10 um (the
  planner before chords were fitted); the cost of planning it as 1000 to
  30,000 chords (CPU, median of ``--repeat``, at most 3).
- ``--node``: the ``planner`` node as a process, a 400-pose circle sent
  ``--repeat`` times (at least 10): its planning time (its diagnostics)
  and the time from publishing the path to receiving the motion.
- ``--memory``: the peak memory (resident set, ``VmHWM``) and CPU
  time of ``orthoglide plan`` (paper robot, default limits) and of the
  node's core, each case in a process of its own: programs and Paths the
  largest each bound accepts, and those it refuses, against the stated
  bound (the interpreter's own, plus MOVE_BYTES a move or pose,
  GRIDPOINT_BYTES a gridpoint and SAMPLE_BYTES a sample).

Usage: python benchmarks/bench_plan.py [--repeat N] [--acceptance] [--node]
       [--memory] [--spiral FILE]
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from orthoglide_ros.formats.params_file import load_robot
from orthoglide_testing import chord_programs, phase_plane, use_checkout
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
    reference, check = checks()
    friction_reference, lagrange_check, path_distance = (
        check.friction_reference, check.lagrange_check, check.path_distance)
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


def checks():
    """Return the modules of test/: the independent model and checks."""
    sys.path.insert(0, os.path.join(ROOT, 'test'))
    import mechanics_reference
    import planning_checks
    return mechanics_reference, planning_checks


def chord_loop(robot, limits, lagrange):
    """
    Print how fast a 3D loop of 95 chords is against its curve.

    Plain G64, 1 m/s, on the robot without friction (toppra's problem):
    the plan against toppra's optimum along the true curve (8000
    intervals), the motion's distance to that curve, the points' to the
    path, the same chords as lines (G64 P0.01); ``lagrange``: every sample
    re-solved.
    """
    _, check = checks()
    robot = robot.frictionless()
    text, start = chord_programs.loop_program(feed=60000.0)
    moves = gcode.read_gcode(text, start)
    begin = time.process_time()
    path = from_moves(moves, 1e-5)
    motion = parametrization.plan(robot, path, limits, RATE)
    cpu = time.process_time() - begin
    curve = check.CurvePath(chord_programs.loop_point, 0.0, 2 * math.pi,
                            chord_programs.LOOP_RADIUS, 1.0)
    optimum = check.toppra_duration(robot, curve, limits, intervals=8000)
    lines = parametrization.plan(robot, from_moves(gcode.read_gcode(
        text.replace('G64', 'G64 P0.01'), start), 1e-5), limits, RATE)
    points = np.array([m.end for m in moves])
    print('\nChords: a 3D loop of 95 chords (60 mm, 15 mm sin 2 phi high; '
          'sagitta up to 52 um), plain G64, 1 m/s, --tolerance 1e-5 m, the '
          'robot without friction')
    print(f'  planned {motion.duration:.4f} s in {cpu * 1e3:.0f} ms CPU; '
          f'toppra along the true curve {optimum:.4f} s: '
          f'{motion.duration / optimum - 1:+.2%}; as lines (G64 P0.01) '
          f'{lines.duration:.4f} s ({lines.duration / motion.duration - 1:+.1%})')
    print(f'  motion to the true curve: '
          f'{check.distance_to_path(curve, motion.position).max() * 1e6:.2f}'
          f' um at most; programmed points to the path: '
          f'{check.distance_to_path(path, points).max() * 1e6:.2f} um at '
          'most')
    if lagrange:
        worst = check.lagrange_check(robot, motion, limits,
                                     range(len(motion.t)))
        print(f'  every one of {len(motion.t)} samples, the Lagrange model: '
              + ', '.join(f'{k} {v:.5f}' for k, v in worst.items()))


def chord_spiral(robot, limits, spiral):
    """
    Print the spiral: the default tolerance against 1 mm, against lines.

    ``spiral``: a copy of LinuxCNC's file (read as plain G64), or None:
    the reconstruction. All of it (1000 chords, 5.1 mm to 0.05 mm) and its
    first 484 chords (5.1 to 2.6 mm: what the issue that asked for this
    measured).
    """
    _, check = checks()
    if spiral is None:
        text, name = chord_programs.spiral_program(), 'reconstructed'
    else:
        with open(spiral) as stream:
            text, name = 'G64 ' + stream.read(), spiral
    feed = chord_programs.SPIRAL_FEED * 0.0254 / 60.0
    print(f'\nChords: the spiral of LinuxCNC\'s nc_files/spiral.ngc '
          f'({name}), plain G64 (G20, F999: {feed:.4f} m/s)')
    print(f'{"chords":<7}{"how":<28}{"duration s":>11}{"CPU ms":>8}'
          f'{"points um":>11}{"least speed":>13}{"at feed":>9}')
    for count, program in (('1000', text), ('484', first_chords(text, 484))):
        results = {}
        for how, words, tolerance in (
                ('fitted, tolerance 10 um', 'G64', 1e-5),
                ('fitted, tolerance 1 mm', 'G64', 1e-3),
                ('lines blended within 10 um', 'G64 P0.000394', 1e-5),
                ('lines blended within 1 mm', 'G64 P0.0394', 1e-5)):
            moves = gcode.read_gcode(program.replace('G64', words, 1))
            begin = time.process_time()
            path = from_moves(moves, tolerance)
            motion = parametrization.plan(robot, path, limits, RATE)
            cpu = time.process_time() - begin
            points = np.array([m.end for m in moves])
            near = check.distance_to_path(path, points).max()
            speed = np.linalg.norm(motion.velocity, axis=1)
            inner = slice(len(speed) // 10, -len(speed) // 10)
            print(f'{count:<7}{how:<28}{motion.duration:>11.4f}'
                  f'{cpu * 1e3:>8.0f}{near * 1e6:>11.2f}'
                  f'{speed[inner].min() / feed:>12.0%}'
                  f'{(speed >= 0.99 * feed).mean():>9.0%}')
            results[how] = motion.duration
        fitted = results['fitted, tolerance 10 um']
        print(f'  {count} chords: the default tolerance against 1 mm '
              f'{fitted / results["fitted, tolerance 1 mm"] - 1:+.2%}, '
              f'against lines within 1 mm (the planner before) '
              f'{fitted / results["lines blended within 1 mm"] - 1:+.2%}')
    print('  (least speed: of the feed, in the middle 80 % of the motion; at'
          ' feed: the share of samples within 1 % of it)')


def first_chords(text, count):
    """Return the program ``text`` up to its ``count``-th chord (G1 after G1)."""
    out, seen = [], 0
    for line in text.splitlines():
        if line.strip().lower().startswith('g1'):
            seen += 1
            if seen > count + 1:        # the first G1 comes from home
                break
        out.append(line)
    return '\n'.join(out + ['M2', ''])


def chord_cost(robot, limits, repeat):
    """CPU of reading and planning the spiral as 1000 to 30,000 chords."""
    print('\nChords: the cost, the spiral sampled more densely (read, fitted,'
          f' planned; CPU, median of {repeat})')
    print(f'{"chords":>8}{"pieces":>8}{"grid":>8}{"CPU s":>8}'
          f'{"us a chord":>12}')
    with tempfile.TemporaryDirectory() as directory:
        for chords in (1000, 3000, 10000, 30000):
            name = os.path.join(directory, 'spiral.nc')
            with open(name, 'w') as stream:
                stream.write(chord_programs.spiral_program(chords))
            times = []
            for _ in range(repeat):
                begin = time.process_time()
                path = read_program(name, (0.0, 0.0, 0.0), 1e-5)
                motion = parametrization.plan(robot, path, limits, RATE)
                times.append(time.process_time() - begin)
            cpu = float(np.median(times))
            print(f'{chords:>8}{len(path.pieces):>8}{motion.gridpoints:>8}'
                  f'{cpu:>8.2f}{cpu / chords * 1e6:>12.1f}')


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


# The memory cases: (name, kind, argument). ``cli``: orthoglide plan on a
# program written by :func:`memory_program`; ``node``: the planner's core
# on a Path of :func:`node_poses`.
MEMORY_CASES = (
    ('5,000 waypoints, sharp corners (CSV)', 'cli', 'corners 5000'),
    ('1,000 waypoints, sharp corners (CSV)', 'cli', 'corners 1000'),
    ('10 mm at 0.21 mm/min (2.9e6 samples)', 'cli', 'line 0.21'),
    ('the same, --format joint_trajectory', 'cli',
     'line 0.21 joint_trajectory'),
    ('helix of 2,500 turns (480,000 gridpoints)', 'cli', 'helix 2500'),
    ('10 mm at 0.035 mm/min (refused)', 'cli', 'line 0.035'),
    ('helix of 100,000 turns (refused)', 'cli', 'helix 100000'),
    ('200,000 G-code moves, corners (refused)', 'cli', 'moves 200000'),
    ('100,000 G-code moves under G61 (refused)', 'cli', 'stops 100000'),
    ('100,000 chords of a 3D curve, plain G64', 'cli', 'chords 100000'),
    ('500,000 CSV waypoints, corners (refused)', 'cli', 'corners 500000'),
    ('Path: 400-pose circle', 'node', 'circle 400'),
    ('Path: 5,000-pose circle', 'node', 'circle 5000'),
    ('Path: 3,000 poses, sharp corners (refused)', 'node', 'corners 3000'),
    ('Path: 100,000 poses in a line', 'node', 'line 100000'),
    ('Path: 100,000 poses, sharp corners (refused)', 'node',
     'corners 100000'),
    ('Path: 100,000-pose circle (one curve)', 'node', 'circle 100000'),
)


def memory_program(case, directory):
    """Write the program of a ``cli`` case; return its path and options."""
    words = case.split()
    kind, size = words[0], float(words[1])
    rng = np.random.default_rng(1)
    if kind == 'corners':
        path = os.path.join(directory, 'waypoints.csv')
        with open(path, 'w') as stream:
            stream.write('x,y,z\n')
            for row in rng.uniform(-0.1, 0.1, (int(size), 3)).tolist():
                stream.write('%r,%r,%r\n' % tuple(row))
        return path, []
    path = os.path.join(directory, 'program.nc')
    if kind == 'line':
        text = f'G21 G1 F{words[1]} X10\n'
    elif kind == 'helix':
        text = f'G21 F60000\nG0 X10\nG2 X10 Y0 Z-1 I-10 J0 P{int(size)}\n'
    elif kind == 'chords':      # five turns of a 3D curve
        t = np.linspace(0.0, 10 * math.pi, int(size) + 1)
        text = 'G21 G64 F6000\n' + ''.join(
            'G1 X%.5f Y%.5f Z%.5f\n' % p for p in zip(
                40 * np.cos(t), 40 * np.sin(t), 10 * np.sin(3 * t)))
    else:       # moves, stops: corners blended, stopped at
        points = rng.uniform(-100.0, 100.0, (int(size), 3)).tolist()
        mode = 'G64 P0.01' if kind == 'moves' else 'G61'
        text = f'G21 {mode} F6000\n' + ''.join(
            'G1 X%.3f Y%.3f Z%.3f\n' % tuple(p) for p in points)
    with open(path, 'w') as stream:
        stream.write(text)
    return path, (['--format', words[2]] if len(words) > 2 else [])


def node_poses(case):
    """Return the poses (N, 3) of a ``node`` case."""
    kind, size = case.split()
    count = int(size)
    if kind == 'circle':
        angles = np.linspace(0.0, 2.0 * math.pi, count)
        return CIRCLE_CENTRE + CIRCLE_RADIUS * np.stack(
            (np.cos(angles), np.sin(angles), np.zeros(count)), 1)
    if kind == 'line':
        return np.linspace((0.0, 0.0, 0.0), (0.07, -0.03, 0.05), count)
    return np.random.default_rng(1).uniform(-0.1, 0.1, (count, 3))


def high_water():
    """
    Return this process's peak resident set (bytes): VmHWM.

    Not ``ru_maxrss``, which a process started from a larger one inherits
    across fork and exec.
    """
    with open('/proc/self/status') as status:
        for line in status:
            if line.startswith('VmHWM:'):
                return int(line.split()[1]) * 1024
    raise RuntimeError('no VmHWM in /proc/self/status')


def memory_child(kind, case):
    """
    Run one case in this process; print its figures as JSON.

    ``base``: the peak before the case, after small plans of the same
    kind (the interpreter, the package, numpy's first allocations and
    scipy's modules, which the first curve fitted through chords imports:
    a line and, beside it, doc/programs/loop.nc or a 100-pose circle).
    """
    from orthoglide_ros.cores import planner
    from orthoglide_ros.cores.inputs import Rejected
    from orthoglide_ros.planning import parametrization
    from orthoglide_ros.tools import cli
    seen = {}
    plan = parametrization.plan

    def noted(*args, **kwargs):
        motion = plan(*args, **kwargs)
        seen.update(gridpoints=motion.gridpoints, samples=len(motion.t))
        return motion
    parametrization.plan = planner.plan = noted
    base = high_water()
    start = time.process_time()
    if kind == 'cli':
        with tempfile.TemporaryDirectory() as directory:
            program, options = memory_program(case, directory)
            os.mkdir(os.path.join(directory, 'small'))
            small, _ = memory_program('line 6000',
                                      os.path.join(directory, 'small'))
            for warm in (small, os.path.join(PROGRAMS, 'loop.nc')):
                cli.main(['plan', '--input', warm, '--output',
                          os.path.join(directory, 'out'), *options])
            seen.clear()
            base = high_water()
            start = time.process_time()
            code = cli.main(['plan', '--input', program, '--output',
                             os.path.join(directory, 'out'), *options])
        outcome = 'planned' if code == 0 else 'refused'
    else:
        core = planner.Planner(planner.PARAMETERS.parse({}))
        core.path('', (), node_poses('circle 100'), 0.0)
        seen.clear()
        poses = node_poses(case)
        base = high_water()
        start = time.process_time()
        try:
            core.path('', (), poses, 0.0)
            outcome = 'planned'
        except Rejected as rejection:
            outcome = f'refused ({rejection.reason})'
            print(rejection, file=sys.stderr)
    moves = len(poses) if kind == 'node' else (
        1 if case.split()[0] in ('line', 'helix') else int(case.split()[1]))
    print(json.dumps(dict(
        seen, outcome=outcome, cpu=time.process_time() - start, base=base,
        peak=high_water(), moves=moves)))


def memory():
    """Peak memory and CPU of each case, each in a process of its own."""
    from orthoglide_ros.cores.planner import PLAN_BYTES
    from orthoglide_ros.planning.parametrization import (GRIDPOINT_BYTES,
                                                         MOVE_BYTES,
                                                         SAMPLE_BYTES)
    from orthoglide_ros.tools.cli.planning import PLAN_BYTES as CLI_BYTES
    print(f'\nMemory (peak resident set) and CPU, each case a process; '
          f'bound (planned): the interpreter\'s own (its peak before the '
          f'case, after small plans) + {MOVE_BYTES} B a move or pose + '
          f'{GRIDPOINT_BYTES} B a gridpoint + {SAMPLE_BYTES} B a sample; '
          f'the plan may take {CLI_BYTES / 1e6:g} MB (orthoglide plan), '
          f'{PLAN_BYTES / 1e6:g} MB (node)')
    print(f'{"case":<46}{"outcome":<20}{"gridpoints":>11}{"samples":>10}'
          f'{"peak MB":>9}{"bound MB":>9}{"CPU s":>8}')
    for name, kind, case in MEMORY_CASES:
        done = subprocess.run(
            [sys.executable, __file__, '--memory-child', kind, case],
            capture_output=True, text=True, timeout=3600)
        if done.returncode != 0:
            print(f'{name:<46}failed: {done.stderr.strip()[-300:]}')
            continue
        found = json.loads(done.stdout.strip().splitlines()[-1])
        grid, samples = found.get('gridpoints', 0), found.get('samples', 0)
        bound = (found['base'] + found['moves'] * MOVE_BYTES
                 + grid * GRIDPOINT_BYTES + samples * SAMPLE_BYTES) / 1e6
        print(f'{name:<46}{found["outcome"]:<20}{grid or "":>11}'
              f'{samples or "":>10}{found["peak"] / 1e6:>9.0f}'
              f'{f"{bound:.0f}" if grid else "":>9}{found["cpu"]:>8.1f}')
        if found['outcome'] != 'planned':
            print(f'  {done.stderr.strip().splitlines()[-1][:150]}')


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--repeat', type=int, default=5)
    parser.add_argument('--acceptance', action='store_true')
    parser.add_argument('--node', action='store_true',
                        help='also time the planner node (starts DDS)')
    parser.add_argument('--memory', action='store_true',
                        help='also the memory of plan and the node\'s core')
    parser.add_argument('--spiral', metavar='FILE', help='a copy of '
                        'LinuxCNC\'s nc_files/spiral.ngc to plan (default: '
                        'its reconstruction)')
    parser.add_argument('--memory-child', nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.memory_child:
        memory_child(*args.memory_child)
        return
    robot = load_robot(os.path.join(PROGRAMS, 'drives.yaml'))
    limits = load_limits(os.path.join(PROGRAMS, 'drives_limits.yaml'))
    print(f'Robot: doc/programs/drives.yaml; limits {limits.effort} N')
    plan_times(robot, limits, args.repeat)
    cycle_times(robot, limits)
    jerk_cost(robot, limits)
    chord_loop(robot, limits, args.acceptance)
    chord_spiral(robot, limits, None)
    if args.spiral:
        chord_spiral(robot, limits, args.spiral)
    chord_cost(robot, limits, min(args.repeat, 3))
    if args.acceptance:
        acceptance(robot, limits)
    if args.node:
        node(max(args.repeat, 10))
    if args.memory:
        memory()


if __name__ == '__main__':
    main()
