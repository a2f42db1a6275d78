#!/usr/bin/env python3
"""
Identify robots on ball screws without and with the ripple term; how close.

For each seed, a robot of the rough-guideway kind on ball screws
(``orthoglide_testing.rough_guideways.screw_robot``: a Coulomb level per
direction, a Stribeck excess, a ripple of 0.5-0.7 N per actuator at a 5 mm
lead and a second harmonic of up to 15 % of it, which the model does not
hold; a lag, noise, drops, a stall), 30 s of an excitation logged with
every defect, then ``identification.identify`` twice, every choice its
own: with the paper's robot as the nominal one (no lead: the identification
of before the ripple term) and with ``robot.screw_lead`` 5 mm. Each
identified robot's forces along another motion (``mechanics.solve_batch``,
what ``orthoglide batch`` computes) against those the robot needs there.
Prints per robot the RMS error per actuator and their mean, before and
after, the ripple found against the truth, the lag found before and after
against the truth and the time of each identification; then the means
over the robots, the worst, and how many meet the targets (each actuator
within SCREW_EACH, the mean within SCREW_MEAN). No ROS import.

Usage: python benchmarks/bench_screw_ripple.py [--seeds 0-9]
"""

import argparse
import os
import platform
import sys
import time

import numpy as np

from orthoglide_testing import use_checkout
from orthoglide_testing.arguments import seeds
from orthoglide_testing import rough_guideways as rough
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools import identification

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
use_checkout(ROOT)


def identified(nominal, robot, defects, log, motion, times):
    """Identify from ``log``; give the robot, its RMS errors (N), seconds."""
    start = time.perf_counter()
    found = identification.identify(nominal, log)
    spent = time.perf_counter() - start
    predicted = mechanics.solve_batch(
        found.robot, *trajectory.excitation_batch(motion, times)).force
    return found, rough.errors(predicted, robot, defects, motion, times), \
        spent


def main(argv=None):
    """Run the benchmark and print its figures; return 0."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('--seeds', type=seeds, default=seeds('0-9'),
                        help='robots to draw (default 0-9)')
    args = parser.parse_args(argv)
    lead = rough.SCREW_LEAD
    print(f'Python {platform.python_version()}, {platform.machine()}, '
          f'{os.cpu_count()} CPUs; lead {1e3 * lead:g} mm; targets with the '
          f'term {rough.SCREW_EACH:g} N RMS per actuator, '
          f'{rough.SCREW_MEAN:g} N mean')
    print(f'{"seed":>4}  {"ripple (N, A B C)":<18}{"before: RMS (N)":<26}'
          f'{"after: RMS (N)":<26}{"found / true amplitude":<24}'
          f'{"2nd harmonic RMS":<18}{"lag (ms) before/after/true":<28}'
          'time before/after (s)')
    before_all, after_all, within = [], [], 0
    for seed in args.seeds:
        robot, defects = rough.screw_robot(seed)
        log = rough.log(robot, defects, 2 * seed, 10 + seed)
        motion, times = rough.validation_motion(defects, 2 * seed + 1)
        plain, before, spent_before = identified(
            Robot(), robot, defects, log, motion, times)
        found, after, spent_after = identified(
            Robot(screw_lead=(lead,) * 3), robot, defects, log, motion,
            times)
        amplitude = np.hypot(found.robot.ripple_sine,
                             found.robot.ripple_cosine)
        ok = (after <= rough.SCREW_EACH).all() \
            and after.mean() <= rough.SCREW_MEAN
        within += ok
        before_all.append(before)
        after_all.append(after)
        print(f'{seed:>4}  {" ".join(f"{r:.2f}" for r in defects["ripple"]):<18}'
              f'{" ".join(f"{e:.3f}" for e in before)}, {before.mean():.3f}    '
              f'{" ".join(f"{e:.3f}" for e in after)}, {after.mean():.3f}'
              f'{"" if ok else " MISS":5}'
              f'{" ".join(f"{a / r:.3f}" for a, r in zip(amplitude, defects["ripple"])):<24}'
              f'{" ".join(f"{s / np.sqrt(2.0):.3f}" for s in defects["second"]):<18}'
              f'{1e3 * plain.force_lag:.3f} / {1e3 * found.force_lag:.3f} / '
              f'{1e3 * defects["lag"]:<10.3f}'
              f'{spent_before:.2f} / {spent_after:.2f}'
              f'  {identification.law_name(found.law)}')
    before_all, after_all = np.array(before_all), np.array(after_all)
    print('RMS error per actuator, mean over the robots (N): before '
          + ' '.join(f'{e:.3f}' for e in before_all.mean(axis=0))
          + f' (mean {before_all.mean():.3f}), after '
          + ' '.join(f'{e:.3f}' for e in after_all.mean(axis=0))
          + f' (mean {after_all.mean():.3f})')
    print(f'after, worst actuator {after_all.max():.3f} N, worst mean '
          f'{after_all.mean(axis=1).max():.3f} N; within the targets: '
          f'{within} of {len(after_all)}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
