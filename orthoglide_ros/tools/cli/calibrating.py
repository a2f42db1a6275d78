"""
Calibrate a robot's legs: ``calibration-poses``, ``calibrate``.

From the positions worth measuring to the calibrated parameters file;
see doc/calibration.md.
"""

import sys

import numpy as np

from orthoglide_ros.formats import params_file
from orthoglide_ros.tools import calibration
from orthoglide_ros.tools.calibration import poses, report
from orthoglide_ros.tools.cli.common import (
    CliError, count, drawn_png, positive_count, refusals_in_one_line,
    Subcommand, within, write_output)

FRAMES = ('robot', 'instrument')
# The columns of a gauge design's nominal position (m): x, y, z are left
# for the readings.
GAUGE_NOMINAL = ('nominal_x', 'nominal_y', 'nominal_z')


def add_calibration_poses(parser):
    """Add the options of ``calibration-poses``: the positions to measure."""
    parser.add_argument('--count', type=positive_count, required=True,
                        metavar='N', help='positions to choose (readings '
                        'with --type gauge): enough to identify the values '
                        'the readings separate with '
                        f'{calibration.MIN_REDUNDANCY} readings to spare '
                        '(a count below is refused naming the fewest), at '
                        f'most {poses.MAX_COUNT}')
    parser.add_argument('--output', required=True, metavar='POSES.csv',
                        help='CSV file: lambda_a, lambda_b, lambda_c (m, '
                        'the joint positions to drive to), x, y, z (m, '
                        'where the nominal robot puts the platform there; '
                        'with --type gauge empty, to fill with the '
                        'readings, and the columns gauge, the coordinate '
                        'to read, and nominal_x, nominal_y, nominal_z, the '
                        'nominal position); - for standard output (the '
                        'summary then goes to standard error)')
    parser.add_argument('--type', choices=poses.TYPES, default='xyz',
                        help='xyz (default): each position measured in x, '
                        'y and z (a laser tracker, a CMM); gauge: one '
                        'coordinate per measurement (a dial gauge)')
    parser.add_argument('--seed', type=count, default=0, metavar='N',
                        help='seed of the candidate positions, an integer '
                        '>= 0 (default 0)')
    parser.add_argument('--evaluations',
                        type=within(int, 1, poses.MAX_EVALUATIONS),
                        default=poses.DEFAULT_EVALUATIONS, metavar='N',
                        help='condition numbers the exchange search may '
                        'compute, at most '
                        f'{poses.MAX_EVALUATIONS:,} (about 20 us each); '
                        'default %(default)s: the command takes 3-5 s up '
                        f'to --count {poses.MAX_COUNT}, about 3 min at the '
                        'most')


def run_calibration_poses(robot, args):
    """Write the positions whose measurements best condition a calibration."""
    try:
        design = poses.design(robot, args.count, args.type, args.seed,
                              args.evaluations)
    except poses.DesignError as error:
        raise CliError(f'--{error.option} {error}' if error.option
                       else f'{args.params or "the drawing"}: {error}') \
            from None
    gauge = args.type == 'gauge'
    summary = _summary_stream(args)
    print(f'Calibration poses: {args.count} '
          + ('readings of one coordinate (a dial gauge\'s), at '
             f'{len(set(map(tuple, design.lambdas)))} positions'
             if gauge else 'positions measured in x, y and z')
          + ' within the workspace cube |x|, |y|, |z| <= '
          f'{poses.CUBE:g} m and the singularity margin', file=summary)
    print(f'condition number of the calibration\'s Jacobian (the '
          f'{len(design.identified)} separable values, unit-norm columns):'
          f' {design.condition:.4g} (random positions of the cube: '
          f'{design.random_condition:.4g}; {design.evaluations} '
          'evaluations)', file=summary)
    for note in design.notes:
        print(f'note: {note}', file=summary)
    _write(args.output, _poses_csv(design), summary)
    return 0


def _summary_stream(args):
    """
    Return where the summary goes: standard error if an output is ``-``.

    The file on standard output stays the file alone, for a pipe.
    """
    return sys.stderr if '-' in (args.output,
                                 getattr(args, 'report', None)) \
        else sys.stdout


def _write(path, data, summary):
    """Write an output; say so unless it went to standard output."""
    write_output(path, data)
    if path != '-':
        print(f'written: {path}', file=summary)


def _poses_csv(design):
    """
    Format the design as CSV bytes (full precision, repr).

    The measurements' columns (:data:`calibration.COLUMNS`), x, y, z the
    nominal position; for a gauge x, y, z empty (the reading to fill in,
    so that a row left unfilled is refused, not read as the drawing's),
    ``gauge`` (the coordinate each row reads) and GAUGE_NOMINAL.
    """
    if design.coordinates is None:
        lines = [','.join(calibration.COLUMNS)] + [
            ','.join(map(repr, row)) for row in np.column_stack(
                (design.lambdas, design.positions)).tolist()]
    else:
        lines = [','.join(calibration.COLUMNS + ('gauge',) + GAUGE_NOMINAL)]
        lines += [','.join(map(repr, lam)) + ',,,,' + 'xyz'[coordinate]
                  + ',' + ','.join(map(repr, position))
                  for lam, coordinate, position in zip(
                      design.lambdas.tolist(), design.coordinates.tolist(),
                      design.positions.tolist())]
    return ('\n'.join(lines) + '\n').encode('utf-8')


def add_calibrate(parser):
    """Add the options of ``calibrate``: the legs from measurements."""
    parser.add_argument('--input', required=True, metavar='MEASUREMENTS.csv',
                        help='CSV file with the header lambda_a, lambda_b, '
                        'lambda_c, x, y, z (m, any order): per row the '
                        'joint readings and the platform centre measured; '
                        'an empty x, y or z cell is not measured; - for '
                        'standard input')
    parser.add_argument('--output', required=True, metavar='ROBOT.yaml',
                        help='the calibrated robot as a ROS 2 parameters '
                        'file (section /**, every node\'s: every robot.* '
                        'parameter, --params\' masses, friction and drives '
                        'kept) for --params-file and --params; - for '
                        'standard output (the summary then goes to '
                        'standard error)')
    parser.add_argument('--report', metavar='FILE.png',
                        help='draw every measurement\'s residual before and '
                        'after and the identified deviations with their '
                        'standard errors as a PNG image')
    parser.add_argument('--frame', choices=FRAMES, default='robot',
                        help='robot (default): the measurements are in the '
                        'robot\'s base frame; instrument: in the '
                        'instrument\'s own frame (a laser tracker), whose '
                        'pose is identified with the geometry and reported')


def run_calibrate(robot, args):
    """Calibrate the legs; print, write the file and the report."""
    with refusals_in_one_line(
            args.input, (calibration.MeasurementError,
                         calibration.CalibrationError),
            'the measurements cannot separate the values they seemed to',
            (np.linalg.LinAlgError,)):
        data = calibration.read(args.input, robot)
        result = calibration.calibrate(robot, data,
                                       args.frame == 'instrument')
    image = None if args.report is None else drawn_png(
        lambda f: report.draw(f, data, result), (13, 9), '--report')
    summary = report.lines(data, result)
    stream = _summary_stream(args)
    print('\n'.join(summary), file=stream)
    comments = [f'Calibrated by `orthoglide calibrate` from {args.input}'
                + (f' (nominal robot: {args.params})' if args.params
                   else ' (nominal robot: the drawing\'s)'),
                *summary[1:]]
    _write(args.output, params_file.robot_file_text(
        result.robot, comments).encode('utf-8'), stream)
    if image is not None:
        _write(args.report, image, stream)
    return 0


SUBCOMMANDS = (
    Subcommand(
        'calibration-poses', run_calibration_poses, add_calibration_poses,
        'the joint positions to measure for a calibration',
        'Choose the N joint positions (with --type gauge, N readings of one '
        'coordinate) of the workspace cube |x|, |y|, |z| <= '
        f'{poses.CUBE:g} m, within the singularity margin of the --params '
        'robot, whose measurements best condition the calibration: among '
        f'{poses.CANDIDATES} random positions, a greedy choice then '
        'exchanges that lower the condition number of the calibration\'s '
        'Jacobian (the separable values, unit-norm columns), as '
        'excitation --optimize does for the dynamics. Writes a CSV file '
        'with lambda_a, lambda_b, lambda_c (m, to drive to) and x, y, z (m, '
        'where the nominal robot puts the platform, for whoever measures, '
        'to overwrite with the measurements); with --type gauge x, y, z '
        'are empty, the column gauge names the one to fill in and '
        'nominal_x, nominal_y, nominal_z hold the nominal position. Prints '
        'the condition number, and that of random positions, and a note '
        'when the count leaves too few readings to spare to find a '
        'blunder.'),
    Subcommand(
        'calibrate', run_calibrate, add_calibrate,
        'calibrate every leg\'s geometry from measured positions',
        'Identify every leg\'s geometry (doc/model.md#the-machine-as-built) '
        'from measurements: a CSV file with the header lambda_a, lambda_b, '
        'lambda_c, x, y, z (m), one row per measurement, the joint readings '
        'and the platform centre measured (an empty cell: a coordinate not '
        'measured). What the readings can separate is found from them (a '
        'QR decomposition with pivoting of the Jacobian of the readings '
        'with respect to the 30 values of the legs, 36 with --frame '
        'instrument): 18 from x, y, z on enough positions; the rest is '
        'held at its nominal value and named. Nonlinear least squares from '
        'the --params robot (scipy); a blunder is named by its line and '
        'left out. Prints each identified value with its standard error, '
        'the held ones, the residual RMS before and after and the noise '
        'it implies; writes the calibrated robot as a parameters file '
        'every node reads (section /**; the masses, friction and drives '
        'of --params kept) with a comment block of the same. A fit that '
        'leaves more noise than any instrument has (100 um per reading) '
        'is refused. Bad input exits with code 2, nothing written.'),
)
