#!/usr/bin/env python3
"""
Calibrate random machines as built; how close the calibrated IK puts them.

For each seed, a robot whose every leg is off the drawing by a built
Orthoglide's errors (0.1-1 mm, 0.05-0.3 deg:
``orthoglide_testing.robots_as_built.random_built``), measured with
NOISE (10 um, each coordinate) at: 30 random positions of the workspace
cube in x, y, z; 90 random positions, one random coordinate each (a dial
gauge); the 12 positions of ``orthoglide calibration-poses --count 12``;
12 random positions; the 30 with a 5 mm blunder in one reading; the 30 in
an instrument's own frame (``--frame instrument``). Each is calibrated by
``calibration.calibrate`` from the drawing, as ``orthoglide calibrate``
does. The figure: the calibrated inverse kinematics commands 500 held-out
targets uniform in the cube, ``lambda = IK_calibrated(target)``, and the
true machine goes to ``FK_true(lambda)``: the RMS and the largest of
``|FK_true(lambda) - target|`` (um). Beside it, the drawing's (what the
machine does uncalibrated) and a reference least squares: the 18 values
doc/model.md lists as identifiable (per leg the offset, the length, the
axis point across the axis, the direction's two tilts) fitted by scipy's
Levenberg-Marquardt with finite differences on ``mechanics.forward_kinematics``
of ``Robot`` s, the blunder's row left out by hand: what the data allow,
without the calibration's rank analysis, analytic Jacobian or robust
statistics. Then the time of ``orthoglide calibrate`` (a process, imports
included, no ``--report``) on 100 measurements. No ROS import.

``--sweep``: instead, how many readings to spare find a blunder. For
each count of random positions in x, y, z (8 to 13) and of gauge
readings (24 to 36), a 5 mm blunder in one random reading of each seed's
machine (a joint reading or a coordinate): how often it is named alone,
how often the calibration is refused for the noise it leaves
(``estimate.MAX_NOISE``), how often it is missed (and of those, how often
harmfully: the calibrated IK's RMS error over the held-out targets more
than twice the calibration's without the blunder's row), and how often a
robot is written that the targets find worse than the drawing.

Usage: python benchmarks/bench_calibration.py [--seeds 0-9] [--sweep]
"""

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from orthoglide_testing import use_checkout
from orthoglide_testing.arguments import seeds
from orthoglide_testing.robots_as_built import random_built
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools import calibration
from orthoglide_ros.tools.calibration import geometry, poses

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
use_checkout(ROOT)

NOISE = 10e-6           # m, each coordinate
TARGETS = 500
BLUNDER = 5e-3          # m
TIMED = 100             # measurements of the timed command
# The figures aimed at: (RMS, worst) um of each case, None where none.
TARGET = {'xyz 30': (10.0, 45.0), 'gauge 90': (8.5, None),
          'poses 12': (14.0, None), 'random 12': (18.0, None),
          'blunder 30': (12.0, None), 'instrument 30': (None, None)}
CASES = tuple(TARGET)


def cube(robot, rng, count):
    """Return ``count`` random positions of the cube within the margin."""
    return poses._workspace(robot, rng, count)


def accuracy(commanded, true, targets, frame=None):
    """
    Return the RMS and largest ``|FK_true(IK_commanded(t)) - t|`` (um).

    ``frame``: ``(true map, identified map)`` into an instrument's frame
    (``geometry.Frame`` s): the true position is seen in the calibrated
    robot's frame through it.
    """
    lam = mechanics.solve_batch(commanded, targets).lambda_
    reached = mechanics.forward_kinematics(true, lam)
    if frame is not None:
        real, found = frame
        seen = reached @ real.rotation.T + real.translation
        reached = (seen - found.translation) @ found.rotation
    error = np.linalg.norm(reached - targets, axis=1)
    return 1e6 * float(np.sqrt(np.mean(error ** 2))), 1e6 * float(error.max())


def reference(nominal, lam, readings):
    """
    Fit the 18 listed values by plain least squares: the fitted robot.

    Per leg i (drawing axis n, the leg frame's other axes y, z): ``a_i =
    p y + q z``, ``u_i = (n + b y + c z) / |...|``, ``e_i``, ``L_i``; the
    attachments at the drawing's. scipy's ``least_squares`` (``lm``,
    finite differences) on the measured cells.
    """
    from scipy.optimize import least_squares
    mask = ~np.isnan(readings)
    axes = np.eye(3)

    def robot_of(v):
        rows, offsets, lengths = {}, [], []
        for i, leg in enumerate('abc'):
            n, y, z = axes[i], axes[(i + 1) % 3], axes[(i + 2) % 3]
            e, length, p, q, b, c = v[6 * i:6 * i + 6]
            direction = n + b * y + c * z
            rows[f'axis_point_{leg}'] = tuple(p * y + q * z)
            rows[f'axis_direction_{leg}'] = tuple(
                direction / np.linalg.norm(direction))
            offsets.append(e)
            lengths.append(nominal.l3 + length)
        return nominal.replace(joint_offset=tuple(offsets),
                               bar_length=tuple(lengths), **rows)

    def residuals(v):
        return (mechanics.forward_kinematics(robot_of(v), lam)
                - np.nan_to_num(readings))[mask]
    result = least_squares(residuals, np.zeros(18), method='lm',
                           x_scale=1e-3)
    return robot_of(result.x)


def measurements(rng, true, lam, gauge=False):
    """Return the noisy readings of ``true`` at ``lam`` (NaN not read)."""
    readings = mechanics.forward_kinematics(true, lam) + rng.normal(
        0.0, NOISE, lam.shape)
    if gauge:
        read = rng.integers(0, 3, len(lam))
        mask = np.zeros(lam.shape, dtype=bool)
        mask[np.arange(len(lam)), read] = True
        readings = np.where(mask, readings, np.nan)
    return readings


def calibrated(nominal, lam, readings, instrument=False):
    """Calibrate from the readings; the :class:`calibration.Calibration`."""
    data = calibration.Measurements(lam, readings, list(range(
        2, len(lam) + 2)), 'bench')
    return calibration.calibrate(nominal, data, instrument)


def one_machine(seed, design):
    """Every case on machine ``seed``: ``{case: (ours, reference)}``."""
    nominal = Robot()
    true = Robot(**random_built(np.random.default_rng(1000 + seed)))
    rng = np.random.default_rng(seed)
    targets = cube(nominal, rng, TARGETS)
    out = {'drawing': accuracy(nominal, true, targets)}

    def ik(points):
        return mechanics.solve_batch(nominal, points).lambda_
    lam30 = ik(cube(nominal, rng, 30))
    read30 = measurements(rng, true, lam30)
    cases = {'xyz 30': (lam30, read30),
             'gauge 90': (lambda lam: (lam, measurements(rng, true, lam,
                                                         True)))(
                 ik(cube(nominal, rng, 90))),
             'poses 12': (design, measurements(rng, true, design)),
             'random 12': (lambda lam: (lam, measurements(rng, true, lam)))(
                 ik(cube(nominal, rng, 12)))}
    for case, (lam, readings) in cases.items():
        out[case] = (accuracy(calibrated(nominal, lam, readings).robot, true,
                              targets),
                     accuracy(reference(nominal, lam, readings), true,
                              targets))
    row, column = int(rng.integers(0, 30)), int(rng.integers(0, 3))
    spoiled = read30.copy()
    spoiled[row, column] += BLUNDER * rng.choice((-1.0, 1.0))
    result = calibrated(nominal, lam30, spoiled)
    found = [r for r, _, _ in result.left_out]
    kept = np.arange(30) != row
    out['blunder 30'] = (accuracy(result.robot, true, targets),
                         accuracy(reference(nominal, lam30[kept],
                                            read30[kept]), true, targets),
                         found == [row])
    real = geometry.Frame(geometry.rotation(rng.normal(0.0, 1.0, 3)),
                          rng.uniform(-2.0, 2.0, 3))
    result = calibrated(nominal, lam30, read30 @ real.rotation.T
                        + real.translation, instrument=True)
    out['instrument 30'] = (accuracy(result.robot, true, targets,
                                     (real, result.frame)), None)
    return out


def sweep(seeds_):
    """Print, per count, what a 5 mm blunder does (see the docstring)."""
    nominal = Robot()
    print(f'a {1e3 * BLUNDER:g} mm blunder in one reading, '
          f'{1e6 * NOISE:g} um noise, {len(seeds_)} machines per count; '
          'named: left out alone; refused: for the noise left '
          f'(> {1e6 * calibration.MAX_NOISE:g} um) or otherwise; harmful: '
          'missed, the IK error twice the fit\'s without it or more; '
          'worse: a robot written whose IK is worse than the drawing\'s '
          f'(RMS, {TARGETS} targets)')
    columns = (('named', 8), ('missed', 8), ('harmful', 9), ('refused', 9),
               ('other', 7), ('worse', 7))
    print(f'{"readings":>18}{"to spare":>10}'
          + ''.join(f'{k:>{w}}' for k, w in columns))
    for kind, counts in (('xyz', range(8, 15)), ('gauge', range(24, 40, 3))):
        for count in counts:
            tally = dict.fromkeys((k for k, _ in columns), 0)
            for seed in seeds_:
                true = Robot(**random_built(np.random.default_rng(seed)))
                rng = np.random.default_rng(100 + seed)
                targets = cube(nominal, rng, TARGETS)
                lam = mechanics.solve_batch(nominal, cube(
                    nominal, rng, count)).lambda_
                readings = measurements(rng, true, lam, kind == 'gauge')
                row = int(rng.integers(count))
                column = int(rng.integers(4)) if kind == 'gauge' \
                    else int(rng.integers(6))
                kept = np.arange(count) != row
                clean = (lam[kept], readings[kept])
                if column < 3:
                    lam[row, column] += BLUNDER
                else:
                    readings[row, int(np.flatnonzero(~np.isnan(
                        readings[row]))[0]) if kind == 'gauge'
                        else column - 3] += BLUNDER
                try:
                    result = calibrated(nominal, lam, readings)
                except calibration.CalibrationError as error:
                    tally['refused' if 'beyond any instrument' in str(error)
                          else 'other'] += 1
                    continue
                named = [r for r, _, _ in result.left_out] == [row]
                tally['named' if named else 'missed'] += 1
                error = accuracy(result.robot, true, targets)[0]
                tally['harmful'] += not named and error > 2.0 * accuracy(
                    calibrated(nominal, *clean).robot, true, targets)[0]
                tally['worse'] += error > accuracy(nominal, true,
                                                   targets)[0]
            spare = count * (3 if kind == 'xyz' else 1) - 18
            print(f'{count:>4} {kind:<13}{spare:>10}' + ''.join(
                f'{tally[k]:>{w}}' for k, w in columns), flush=True)


def timed():
    """Return the median seconds of ``orthoglide calibrate`` on TIMED rows."""
    rng = np.random.default_rng(7)
    nominal = Robot()
    true = Robot(**random_built(rng))
    lam = mechanics.solve_batch(nominal, cube(nominal, rng, TIMED)).lambda_
    readings = measurements(rng, true, lam)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, 'measurements.csv')
        with open(path, 'w') as stream:
            stream.write(','.join(calibration.COLUMNS) + '\n')
            for row in np.column_stack((lam, readings)).tolist():
                stream.write(','.join(map(repr, row)) + '\n')
        spent = []
        for _ in range(5):
            start = time.perf_counter()
            subprocess.run([sys.executable, '-m', 'orthoglide_ros.tools.cli',
                            'calibrate', '--input', path, '--output',
                            os.path.join(tmp, 'robot.yaml')], check=True,
                           capture_output=True)
            spent.append(time.perf_counter() - start)
        start = time.perf_counter()
        calibrated(nominal, lam, readings)
        library = time.perf_counter() - start
    return statistics.median(spent), library


def main(argv=None):
    """Run the benchmark and print its figures; return 0."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('--seeds', type=seeds, default=seeds('0-9'),
                        help='machines to draw (default 0-9)')
    parser.add_argument('--sweep', action='store_true',
                        help='how many readings to spare find a blunder '
                        '(see above), instead of the accuracy')
    args = parser.parse_args(argv)
    if args.sweep:
        sweep(args.seeds)
        return 0
    print(f'Python {platform.python_version()}, {platform.machine()}, '
          f'{os.cpu_count()} CPUs; noise {1e6 * NOISE:g} um per coordinate;'
          f' {TARGETS} held-out targets in the cube; |FK_true(IK(t)) - t| '
          'RMS / largest (um), calibrated [reference least squares]')
    design = poses.design(Robot(), 12, 'xyz')
    print(f'calibration-poses --count 12: condition number '
          f'{design.condition:.4g} (random 12: '
          f'{design.random_condition:.4g})')
    print(f'{"seed":>4}  {"drawing":>16}' + ''.join(
        f'{case:>26}' for case in CASES))
    table = {case: [] for case in CASES + ('drawing',)}
    references = {case: [] for case in CASES}
    blunders_found = 0
    for seed in args.seeds:
        out = one_machine(seed, design.lambdas)
        table['drawing'].append(out['drawing'])
        cells = []
        for case in CASES:
            ours, ref = out[case][:2]
            table[case].append(ours)
            if ref is not None:
                references[case].append(ref)
            cells.append(f'{ours[0]:.1f}/{ours[1]:.0f}'
                         + (f' [{ref[0]:.1f}/{ref[1]:.0f}]' if ref else ''))
        blunders_found += out['blunder 30'][2]
        print(f'{seed:>4}  {out["drawing"][0]:>8.0f}/{out["drawing"][1]:<7.0f}'
              + ''.join(f'{c:>26}' for c in cells), flush=True)
    print(f'mean over {len(args.seeds)} machines (RMS, largest; um):')
    nominal = np.array(table['drawing'])
    print(f'  {"drawing (uncalibrated)":<24}{nominal[:, 0].mean():10.1f}'
          f'{nominal[:, 1].mean():10.1f}')
    for case in CASES:
        ours = np.array(table[case])
        ref = np.array(references[case]) if references[case] else None
        want = TARGET[case]
        aim = ('' if want[0] is None else f'  target {want[0]:g}'
               + ('' if want[1] is None else f' / {want[1]:g}'))
        print(f'  {case:<24}{ours[:, 0].mean():10.1f}{ours[:, 1].mean():10.1f}'
              + (f'   reference {ref[:, 0].mean():.1f} / '
                 f'{ref[:, 1].mean():.1f}' if ref is not None else
                 '   reference -') + f'   worst machine {ours[:, 0].max():.1f}'
              f' / {ours[:, 1].max():.1f}' + aim)
    print(f'the blunder named (its line, alone): {blunders_found} of '
          f'{len(args.seeds)}')
    command, library = timed()
    print(f'orthoglide calibrate of {TIMED} measurements: {command:.2f} s '
          f'(a process, median of 5; the library call {library:.2f} s); '
          'target 2 s')
    return 0


if __name__ == '__main__':
    sys.exit(main())
