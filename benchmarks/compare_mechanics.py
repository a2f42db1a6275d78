#!/usr/bin/env python3
"""
Compare ``mechanics.solve``, ``solve_batch``, ``forward_dynamics`` with a revision's.

The revision's ``orthoglide_ros`` (``git archive``, renamed
``orthoglide_before`` in a temporary folder) is imported beside the
checkout's; blocks of calls alternate between the two in one process,
timed in CPU time (``time.process_time_ns``), which other processes'
load does not inflate; the medians of the blocks are printed per robot:
without terms, with viscous and Coulomb friction (bench_mechanics.py's),
with every friction term, with drives; and a robot whose legs are as
built (``robots_as_built.BUILT``) now against the drawing's before, what
the per-leg geometry costs. No ROS import.

Usage: python benchmarks/compare_mechanics.py [REVISION] [--rounds R]
"""

import argparse
import io
from pathlib import Path
import subprocess
import sys
import tarfile
import tempfile
import time

import numpy as np

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot
from orthoglide_testing import robots_as_built

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = {
    'no terms': {},
    'viscous + Coulomb': dict(friction_viscous=(40.0, 40.0, 40.0),
                              friction_coulomb=(5.0, 5.0, 5.0)),
    'every friction term': dict(friction_viscous=(40.0, 40.0, 40.0),
                                friction_coulomb=(5.0, 5.0, 5.0),
                                friction_coulomb_negative=(3.0, 4.0, 6.0),
                                friction_stribeck=(2.0, 2.0, 2.0)),
    'drives (armature)': dict(armature=(3.2, 1.1, 0.45)),
}
# Robots of the checkout only, against the revision's drawing (no rows).
NOW_ONLY = {'legs as built': robots_as_built.BUILT}
BLOCK = 1000    # solve calls per timed block


def import_revision(revision, folder):
    """Import ``revision``'s package as ``orthoglide_before``; its modules."""
    archive = subprocess.run(['git', 'archive', revision, 'orthoglide_ros'],
                             cwd=ROOT, capture_output=True, check=True)
    with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
        for member in tar.getmembers():
            if member.isfile() and member.name.endswith('.py'):
                text = tar.extractfile(member).read().decode()
                path = Path(folder, member.name.replace(
                    'orthoglide_ros', 'orthoglide_before', 1))
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(text.replace('orthoglide_ros',
                                             'orthoglide_before'))
    sys.path.insert(0, folder)
    from orthoglide_before.model import mechanics as before
    from orthoglide_before.model.robot import Robot as BeforeRobot
    return before, BeforeRobot


def block(call, robot, samples, offset, count=BLOCK):
    """Return the CPU time (us) per call of ``count`` ``call``s."""
    clock = time.process_time_ns
    start = clock()
    for i in range(offset, offset + count):
        call(robot, *samples[i % len(samples)])
    return (clock() - start) / count / 1e3


def batch(solve_batch, robot, arrays):
    """Return the CPU time (ms) of one ``solve_batch``."""
    clock = time.process_time_ns
    start = clock()
    solve_batch(robot, *arrays)
    return (clock() - start) / 1e6


def main(argv=None):
    """Print the figures; return 0."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('revision', nargs='?', default='main',
                        help='the git revision compared (default main)')
    parser.add_argument('--rounds', type=int, default=40,
                        help='blocks per robot and side (default 40)')
    args = parser.parse_args(argv)
    arrays = trajectory.paper_batch(trajectory.paper_times(10000))
    samples = [tuple(tuple(x) for x in row)
               for row in zip(*(a.tolist() for a in arrays))]
    with tempfile.TemporaryDirectory() as folder:
        before, BeforeRobot = import_revision(args.revision, folder)
        print(f'CPU time, medians, {args.revision} (before) against the '
              'checkout (now): solve and forward_dynamics in us per call, '
              'solve_batch of N = 10,000 in ms')
        print(f'{"robot":20s} {"call":16s} {"before":>8s} {"now":>8s} '
              f'{"ratio":>6s}')
        cases = [(name, values, values) for name, values in ROBOTS.items()]
        cases += [(name, {}, values) for name, values in NOW_ONLY.items()]
        for name, was_values, values in cases:
            sides = ((before, BeforeRobot(**was_values)),
                     (mechanics, Robot(**values)))
            force = mechanics.solve_batch(sides[1][1], *arrays).force
            states = [(tuple(p), tuple(v), tuple(f)) for p, v, f in zip(
                *(a[:1000].tolist() for a in (*arrays[:2], force)))]
            times = {call: ([], []) for call in
                     ('solve', 'forward_dynamics', 'solve_batch')}
            for k in range(args.rounds):
                for side, (module, robot) in enumerate(sides):
                    times['solve'][side].append(block(
                        module.solve, robot, samples, k * BLOCK))
                    times['forward_dynamics'][side].append(block(
                        module.forward_dynamics, robot, states, k * 250,
                        250))
                    if k % 4 == 0:
                        times['solve_batch'][side].append(batch(
                            module.solve_batch, robot, arrays))
            for call, (was, now) in times.items():
                was, now = np.median(was), np.median(now)
                print(f'{name:20s} {call:16s} {was:8.2f} {now:8.2f} '
                      f'{now / was:6.3f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
