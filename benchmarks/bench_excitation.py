#!/usr/bin/env python3
"""
Benchmark ``orthoglide excitation --optimize`` (tools.excitation_design).

For each period, the condition number of the base regressor of the
default excitation (seed 0, the default bounds) against the optimized one
(``excitation_design.optimize`` with its default number of evaluations),
the evaluations made and the wall time. No ROS import.

Usage: python benchmarks/bench_excitation.py [--periods 6,10,30] [--evaluations N]
"""

import argparse
import os
import platform
import sys
import time


from orthoglide_ros.model.robot import Robot  # noqa: E402
from orthoglide_ros.tools import excitation_design  # noqa: E402


def main(argv=None):
    """Run the benchmark and print its figures; return 0."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('--periods', default='6,10,30',
                        help='periods (s), comma-separated (default '
                        '%(default)s)')
    parser.add_argument('--evaluations', type=int,
                        default=excitation_design.DEFAULT_EVALUATIONS,
                        help='evaluations per search (default %(default)s)')
    args = parser.parse_args(argv)
    print(f'Python {platform.python_version()}, {platform.machine()}, '
          f'{os.cpu_count()} CPUs; seed 0, default bounds')
    print(f'{"period (s)":>10}{"default":>12}{"optimized":>12}'
          f'{"ratio":>8}{"evaluations":>13}{"time (s)":>10}')
    for period in (float(p) for p in args.periods.split(',')):
        start = time.perf_counter()
        design = excitation_design.optimize(Robot(), period, 0,
                                            evaluations=args.evaluations)
        seconds = time.perf_counter() - start
        print(f'{period:10g}{design.start_condition:12.4g}'
              f'{design.condition:12.4g}'
              f'{design.condition / design.start_condition:8.2f}'
              f'{design.evaluations:13d}{seconds:10.1f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
