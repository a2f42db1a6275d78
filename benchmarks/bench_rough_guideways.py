#!/usr/bin/env python3
"""
Identify robots of the rough-guideway kind drawn at random; report how close.

For each seed, a robot and its log's defects drawn by
``orthoglide_testing.rough_guideways.drawn_robot`` (a Coulomb level per
direction, a Stribeck excess, a ripple periodic in position, a lag, noise,
drops, a stall), 30 s of an excitation logged with every defect, plain
``identification.identify`` (every choice its own), then the identified robot's
forces along another motion (``mechanics.solve_batch``, what ``orthoglide
batch`` computes) against those the robot needs there. Prints per robot the law
chosen, the Stribeck speed and the lag found against the truth, the RMS error
per actuator as a multiple of the floor (the ripple's RMS, which no model
holds) and the time of the identification; then how many are within EACH times
the floor per actuator and MEAN in the mean. No ROS import.

Usage: python benchmarks/bench_rough_guideways.py [--seeds 0-19]
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


def main(argv=None):
    """Run the benchmark and print its figures; return 0."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('--seeds', type=seeds, default=seeds('0-19'),
                        help='robots to draw (default 0-19)')
    args = parser.parse_args(argv)
    print(f'Python {platform.python_version()}, {platform.machine()}, '
          f'{os.cpu_count()} CPUs; limits {rough.EACH:g} x floor per '
          f'actuator, {rough.MEAN:g} x floor in the mean')
    print(f'{"seed":>4} {"law":<36}{"v_b found/true (mm/s)":>22}'
          f'{"lag found/true (ms)":>20}   error / floor (A B C, mean)'
          f'{"time (s)":>10}')
    ratios, within = [], 0
    for seed in args.seeds:
        robot, defects = rough.drawn_robot(seed)
        log = rough.log(robot, defects, 2 * seed, 10 + seed)
        start = time.perf_counter()
        found = identification.identify(Robot(), log)
        spent = time.perf_counter() - start
        motion, times = rough.validation_motion(defects, 2 * seed + 1)
        predicted = mechanics.solve_batch(
            found.robot, *trajectory.excitation_batch(motion, times)).force
        ratio = rough.errors(predicted, robot, defects, motion, times) \
            / rough.floor(defects)
        ratios.append(ratio)
        ok = (ratio <= rough.EACH).all() and ratio.mean() <= rough.MEAN
        within += ok
        speed = found.stribeck_velocity
        print(f'{seed:>4} {identification.law_name(found.law):<36}'
              f'{"-" if speed is None else f"{1e3 * speed:.3g}":>12}/'
              f'{1e3 * robot.friction_stribeck_velocity:<9.3g}'
              f'{1e3 * found.force_lag:>10.3f}/{1e3 * defects["lag"]:<9.3f}'
              f'   {" ".join(f"{r:.2f}" for r in ratio)}, '
              f'{ratio.mean():.2f}{"" if ok else " MISS":5}{spent:>8.2f}')
    ratios = np.array(ratios)
    print(f'within the limits: {within} of {len(ratios)}; error / floor: '
          f'mean {ratios.mean():.3f}, worst actuator {ratios.max():.2f}, '
          f'worst mean {ratios.mean(axis=1).max():.2f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
