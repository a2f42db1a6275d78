#!/usr/bin/env python3
"""
Benchmark the inverse kinematics and dynamics (mechanics.solve*).

Measures, in one run, on the paper trajectory of eq. (6):

- single sample: ``mechanics.solve`` on Python floats, each call timed with
  ``time.perf_counter_ns`` after a warm-up; median and p99 in microseconds;
- batch: ``mechanics.solve_batch`` on N samples, best of several repeats,
  in samples per second;

and the same figures for the straightforward ways kept as baselines:
(a) one sample through ``solve_batch`` on (1, 3) arrays, (b) a batch as a
per-sample Python loop over ``solve``. Targets: single <= 25 us median,
batch >= 1,000,000 samples/s at N = 10,000. No ROS import.

The same figures for the forward dynamics (``mechanics.forward_dynamics``
and ``forward_dynamics_batch``, the paper trajectory's feedforward forces
as input) against the same two baselines; target: single <= 100 us median.
And the cost of the sliders' friction: ``solve`` and ``solve_batch`` on a
robot with viscous and Coulomb friction (the default robot has none, and
``solve`` then skips it); and of legs as built (every per-leg row off the
drawing, ``robots_as_built.BUILT``: each leg in its own frame, ``kernel.solve_legs``), the
inverse and forward dynamics, against the drawing's.

Usage: python benchmarks/bench_mechanics.py [--samples N] [--repeat R]
"""

import os
import platform
import sys
import time

import numpy as np


from orthoglide_ros.model import trajectory  # noqa: E402
from orthoglide_ros.model import mechanics  # noqa: E402
from orthoglide_ros.model.robot import Robot  # noqa: E402
from orthoglide_testing import robots_as_built  # noqa: E402
from orthoglide_testing.arguments import script_parser  # noqa: E402

SINGLE_TARGET_US = 25.0
FORWARD_TARGET_US = 100.0
WIDTH = 38      # of the call names in the printed table
BATCH_TARGET = 1_000_000.0
BATCH_TARGET_N = 10_000


def time_calls(call, samples, calls, warmup):
    """Time ``call(*sample)`` cycling over ``samples``; return ns per call."""
    n = len(samples)
    for i in range(warmup):
        call(*samples[i % n])
    clock = time.perf_counter_ns
    out = np.empty(calls, dtype=np.int64)
    for i in range(calls):
        sample = samples[i % n]
        start = clock()
        call(*sample)
        out[i] = clock() - start
    return out


def best_time(call, repeat):
    """Return the best wall time (s) of ``call()`` over ``repeat`` runs."""
    best = float('inf')
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best


def timer_overhead_ns(calls=10000):
    """Median cost (ns) of two back-to-back perf_counter_ns calls."""
    clock = time.perf_counter_ns
    deltas = []
    for _ in range(calls):
        start = clock()
        deltas.append(clock() - start)
    return float(np.median(deltas))


def verdict(ok):
    """Return PASS or MISS."""
    return 'PASS' if ok else 'MISS'


def main(argv=None):
    """Run the benchmark and print its figures; return 0."""
    parser = script_parser(
        __doc__, ('--samples', BATCH_TARGET_N, 'batch size N'),
        ('--repeat', 7, 'batch repeats, best kept; the slow loop baseline '
         'runs min(3, R)'),
        ('--calls', 20000, 'timed single-sample calls'),
        ('--warmup', 2000, 'untimed warm-up calls'))
    args = parser.parse_args(argv)

    robot = Robot()
    p, v, a = trajectory.paper_batch(trajectory.paper_times(args.samples))

    print(f'Python {platform.python_version()}, numpy {np.__version__}, '
          f'{platform.machine()}, {os.cpu_count()} CPUs; timer overhead '
          f'{timer_overhead_ns():.0f} ns (included below)')

    s_med, batch_rate = measure(
        'Inverse dynamics', mechanics.solve, mechanics.solve_batch,
        (robot, p, v, a), args.calls, args)
    friction_single, friction_rate = measure_variant(
        'Inverse dynamics with friction', mechanics.solve,
        mechanics.solve_batch,
        robot.replace(friction_viscous=(40.0, 40.0, 40.0),
                      friction_coulomb=(5.0, 5.0, 5.0)),
        (p, v, a), args.calls, args)
    built = robot.replace(**robots_as_built.BUILT)
    built_single, built_rate = measure_variant(
        'Inverse dynamics, legs as built', mechanics.solve,
        mechanics.solve_batch, built, (p, v, a), args.calls, args)
    # Forward dynamics from the trajectory's feedforward forces.
    f = mechanics.solve_batch(robot, p, v, a).force
    forward_med, forward_rate = measure(
        'Forward dynamics', mechanics.forward_dynamics,
        mechanics.forward_dynamics_batch, (robot, p, v, f),
        args.calls // 4, args)
    built_forward, built_forward_rate = measure_variant(
        'Forward dynamics, legs as built', mechanics.forward_dynamics,
        mechanics.forward_dynamics_batch, built,
        (p, v, mechanics.solve_batch(built, p, v, a).force),
        args.calls // 4, args)

    n = len(p)
    print('\nTargets:')
    print(f'  single median <= {SINGLE_TARGET_US:g} us: {s_med:.2f} us  '
          f'{verdict(s_med <= SINGLE_TARGET_US)}')
    if n == BATCH_TARGET_N:
        print(f'  batch >= {BATCH_TARGET:,.0f} samples/s at N = '
              f'{BATCH_TARGET_N:,}: {batch_rate:,.0f}  '
              f'{verdict(batch_rate >= BATCH_TARGET)}')
    else:
        print(f'  batch target applies at N = {BATCH_TARGET_N:,} only '
              f'(ran N = {n:,})')
    print(f'  forward single median <= {FORWARD_TARGET_US:g} us: '
          f'{forward_med:.2f} us  {verdict(forward_med <= FORWARD_TARGET_US)}')
    print(f'  with friction: single median {friction_single:.2f} us  '
          f'{verdict(friction_single <= SINGLE_TARGET_US)}, batch '
          f'{friction_rate:,.0f} samples/s')
    print(f'  legs as built: single median {built_single:.2f} us '
          f'({built_single / s_med:.2f}x the drawing\'s time)  '
          f'{verdict(built_single <= SINGLE_TARGET_US)}, batch '
          f'{built_rate:,.0f} samples/s ({batch_rate / built_rate:.2f}x); '
          f'forward single median {built_forward:.2f} us '
          f'({built_forward / forward_med:.2f}x)  '
          f'{verdict(built_forward <= FORWARD_TARGET_US)}, batch '
          f'{built_forward_rate:,.0f} samples/s '
          f'({forward_rate / built_forward_rate:.2f}x)')
    return 0


def measure_variant(title, single_call, batch_call, robot, arrays, calls,
                    args):
    """Time ``single_call`` and ``batch_call`` on another ``robot``."""
    floats = [(robot, *(tuple(x) for x in row))
              for row in zip(*(arr.tolist() for arr in arrays))]
    single = time_calls(single_call, floats, calls, args.warmup)
    s_med, s_p99 = np.percentile(single, [50, 99]) / 1e3
    t_batch = best_time(lambda: batch_call(robot, *arrays), args.repeat)
    rate = len(floats) / t_batch
    print(f'\n{title} ({calls} calls; batch N = {len(floats)}):')
    print(f'  ours  {single_call.__name__ + " (Python floats)":{WIDTH}s}'
          f'median {s_med:8.2f} us   p99 {s_p99:8.2f} us')
    print(f'  ours  {batch_call.__name__:{WIDTH}s}{rate:14,.0f} samples/s'
          f'  ({t_batch * 1e3:.2f} ms)')
    return s_med, rate


def measure(title, single_call, batch_call, inputs, calls, args):
    """
    Time one single-sample call and its batch twin against the baselines.

    ``inputs``: ``(robot, P, Q, R)`` with three (N, 3) arrays. Single
    sample: ``single_call`` on Python floats against ``batch_call`` on
    (1, 3) arrays; batch: ``batch_call`` against a loop over
    ``single_call``. Prints the figures; returns (single median in us,
    batch samples/s).
    """
    robot, *arrays = inputs
    floats = [(robot, *(tuple(x) for x in row))
              for row in zip(*(arr.tolist() for arr in arrays))]
    rows = [(robot, *(arr[i:i + 1] for arr in arrays))
            for i in range(min(len(floats), 2000))]
    single_name, batch_name = single_call.__name__, batch_call.__name__
    single = time_calls(single_call, floats, calls, args.warmup)
    base = time_calls(batch_call, rows, calls // 4, args.warmup // 4)
    s_med, s_p99 = np.percentile(single, [50, 99]) / 1e3
    b_med, b_p99 = np.percentile(base, [50, 99]) / 1e3
    print(f'\n{title}, single sample, paper trajectory points '
          f'({calls} calls):')
    print(f'  ours  {single_name + " (Python floats)":{WIDTH}s}median '
          f'{s_med:8.2f} us   p99 {s_p99:8.2f} us')
    print(f'  base  {batch_name + " on (1, 3)":{WIDTH}s}median '
          f'{b_med:8.2f} us   p99 {b_p99:8.2f} us')
    print(f'  {"ratio ours/base (time)":{WIDTH + 6}s}median '
          f'{s_med / b_med:8.3f}      p99 {s_p99 / b_p99:8.3f}')

    n = len(floats)
    t_batch = best_time(lambda: batch_call(*inputs), args.repeat)
    t_loop = best_time(lambda: [single_call(*s) for s in floats],
                       min(3, args.repeat))
    batch_rate, loop_rate = n / t_batch, n / t_loop
    print(f'{title}, batch, N = {n} (best of {args.repeat}):')
    print(f'  ours  {batch_name:{WIDTH}s}{batch_rate:14,.0f} samples/s'
          f'  ({t_batch * 1e3:.2f} ms)')
    print(f'  base  {"loop over " + single_name:{WIDTH}s}{loop_rate:14,.0f} '
          f'samples/s  ({t_loop * 1e3:.2f} ms)')
    print(f'  {"ratio ours/base (throughput)":{WIDTH + 6}s}'
          f'{batch_rate / loop_rate:14.1f}')
    return s_med, batch_rate


if __name__ == '__main__':
    sys.exit(main())
