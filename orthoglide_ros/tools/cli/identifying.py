"""
Identify a robot: ``excitation``, ``record``, ``identify``, ``validate``.

From the motion to the check of the result; see doc/identification.md.
"""

import math
import re
import sys

import numpy as np

from orthoglide_ros.cores.recording import LOSSY, WHY
from orthoglide_ros.formats import cdr, params_file
from orthoglide_ros.model import mechanics, terms, trajectory
from orthoglide_ros.model.robot import ROW
from orthoglide_ros.tools import excitation_design, identification
from orthoglide_ros.tools.cli.common import (
    add_joint_names, CliError, count, drawn_png, finite_float, INPUT_GROUPS,
    positive_count, positive_float, print_error, refusals_in_one_line,
    robot_range, Subcommand, table_csv, table_row, write_output)
from orthoglide_ros.tools.identification import DEFAULT_CUTOFF, report

TOPIC_NAME = re.compile(r'/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*')


# The excitation's bounds (trajectory.excitation's keywords), as options.
_EXCITATION_BOUNDS = (
    ('box', trajectory.EXCITATION_BOX, 'M', 'largest |x|, |y|, |z| from '
     'home (m'),
    ('max_velocity', trajectory.EXCITATION_MAX_VELOCITY, 'M/S',
     'largest speed per axis (m/s'),
    ('max_acceleration', trajectory.EXCITATION_MAX_ACCELERATION, 'M/S2',
     'largest acceleration per axis (m/s^2'))


def add_excitation(parser):
    """Add the options of ``excitation``: a periodic motion for identification."""
    parser.add_argument('--duration', type=positive_float,
                        required=True, metavar='S',
                        help='period of the series and length of the '
                        'file (s)')
    parser.add_argument('--output', required=True, metavar='FILE',
                        help='trajectory CSV file (t, x, y, z, vx, vy, '
                        'vz, ax, ay, az; SI units), as orthoglide batch '
                        'reads it; - for standard output (the '
                        'description then goes to standard error)')
    parser.add_argument('--seed', type=count, default=0, metavar='N',
                        help='seed of the coefficients, an integer >= 0'
                        ' (default 0)')
    parser.add_argument('--seeds', type=positive_count, default=1,
                        metavar='K',
                        help='try the K seeds from --seed on and write '
                        'the one of the smallest condition number '
                        '(default 1)')
    parser.add_argument('--rate', type=positive_float, default=1000.0,
                        metavar='HZ', help='samples per second of the '
                        'file (default 1000)')
    for bound, default, metavar, what in _EXCITATION_BOUNDS:
        parser.add_argument('--' + bound.replace('_', '-'),
                            type=positive_float, default=default,
                            metavar=metavar, help=f'{what}; default '
                            '%(default)g)')
    parser.add_argument('--max-force', type=positive_float,
                        default=math.inf, metavar='N',
                        help='largest actuator force of the --params '
                        'robot along the motion (N; default: none)')
    parser.add_argument('--optimize', action='store_true',
                        help='search the Fourier coefficients, from the '
                        'seed\'s, for a smaller condition number within '
                        'the same bounds (L-BFGS-B); prints the seed\'s '
                        'and the optimized one\'s')
    parser.add_argument('--evaluations', type=positive_count,
                        default=excitation_design.DEFAULT_EVALUATIONS,
                        metavar='N', help='condition numbers the '
                        '--optimize search may compute (default '
                        '%(default)s: about 10 s)')


def run_excitation(robot, args):
    """Write an excitation (the best of --seeds) as a trajectory; describe it."""
    try:
        excitation_design.check_size(args.duration, args.rate)
    except ValueError as error:
        raise CliError(str(error)) from None
    base = identification.base_parameters(
        robot, identification.design_law(robot))
    bounds = {bound: getattr(args, bound) for bound, *_ in _EXCITATION_BOUNDS}
    rows = []
    for seed in range(args.seed, args.seed + args.seeds):
        motion = _excitation(robot, seed, args.duration, bounds)
        condition, force = excitation_design.measure(robot, motion, base)
        if force <= args.max_force:
            rows.append((seed, motion, condition, force))
    if not rows:
        raise CliError(f'no seed from {args.seed} to '
                       f'{args.seed + args.seeds - 1} keeps the actuator '
                       f'forces within --max-force {args.max_force:g} N: '
                       'choose smaller bounds')
    lines = []
    best = min(rows, key=lambda row: row[2])
    if args.seeds > 1:
        lines.append(f'Condition number of the base regressor, period '
                     f'{args.duration:g} s:')
        lines += [f'  seed {row[0]:<10d} {row[2]:12.4g}'
                  + (('   (best: the start)' if args.optimize
                      else '   (best: written)') if row is best else '')
                  for row in rows]
    seed, motion, condition, force = best
    made = f'seed {seed}'
    if args.optimize:
        try:
            design = excitation_design.optimize(
                robot, args.duration, seed, args.max_force,
                args.evaluations, **bounds)
        except ValueError as error:
            raise CliError(str(error)) from None
        lines.append(f'Optimized from seed {seed} ({design.evaluations} '
                     'evaluations): condition number '
                     f'{design.start_condition:.4g} (seed {seed}) -> '
                     f'{design.condition:.4g} (optimized)')
        motion, condition, force = (design.motion, design.condition,
                                    design.peak_force)
        made = f'optimized from seed {seed}'
    if not math.isfinite(condition):
        raise CliError(f'the excitation {made}, period {args.duration:g} s, '
                       'leaves a base parameter unexcited (condition number '
                       f'{condition:g}): choose a longer --duration')
    times = np.arange(0.0, args.duration, 1.0 / args.rate)
    p, v, a = trajectory.excitation_batch(motion, times)
    harmonics = motion.sines.shape[1]
    distance = mechanics.workspace_status(robot, p).singularity_distance
    lines += [
        f'Excitation: {made}, period {args.duration:g} s, '
        f'{harmonics} harmonics ({1.0 / args.duration:g} to '
        f'{harmonics / args.duration:g} Hz) per axis',
        table_row('', 'x', 'y', 'z'),
        table_row('peak |position| (m)', *np.abs(p).max(0)),
        table_row('peak |velocity| (m/s)', *np.abs(v).max(0)),
        table_row('peak |acceleration| (m/s^2)', *np.abs(a).max(0)),
        f'peak |actuator force| (N): {force:.4g}',
        f'smallest singularity distance: {distance.min():.4g}',
        f'base parameters: {", ".join(base.names)}',
        f'condition number of the base regressor: {condition:.4g} '
        '(unit-norm columns)']
    # With the trajectory on standard output, the description goes to
    # standard error.
    print('\n'.join(lines),
          file=sys.stderr if args.output == '-' else sys.stdout)
    write_output(args.output, table_csv(
        ('t',) + tuple(c for _, names, _ in INPUT_GROUPS[1:] for c in names),
        times, np.column_stack((p, v, a))))
    return 0


def _excitation(robot, seed, duration, bounds):
    try:
        return trajectory.excitation(seed, duration, robot=robot, **bounds)
    except ValueError as error:
        raise CliError(f'seed {seed}: {error}') from None


def add_record(parser):
    """Add the options of ``record``: topics into a rosbag2 bag (rclpy)."""
    parser.add_argument('--output', required=True, metavar='BAG',
                        help='bag directory to create (must not exist)')
    parser.add_argument('--duration', type=positive_float, required=True,
                        metavar='S', help='stop after S seconds')
    parser.add_argument('--topic', action='append', metavar='NAME',
                        help='topic to record, repeatable (default '
                        f'{identification.DEFAULT_TOPIC})')
    parser.add_argument('--storage', choices=cdr.BAG_STORAGES,
                        default=cdr.BAG_STORAGES[0], help='storage (default mcap, as '
                        'ros2 bag record)')
    parser.add_argument('--wait', type=positive_float, default=10.0,
                        metavar='S', help='longest wait for each topic\'s '
                        'publisher (s; default 10)')


def run_record(robot, args):
    """Record topics into a rosbag2 bag until the duration or Ctrl-C."""
    topics = [_topic(name) for name in args.topic or
              [identification.DEFAULT_TOPIC]]
    full = ['/' + name.lstrip('/') for name in topics]
    repeated = sorted({name for name in full if full.count(name) > 1})
    if repeated:
        raise CliError(f'--topic {repeated[0]} given more than once')
    from orthoglide_ros.ros import console
    console.install_signal_handlers()
    try:
        from orthoglide_ros.ros import recorder_node
    except ImportError as error:
        raise CliError(f'record needs ROS 2 (rclpy): {error}') from None
    return recorder_node.main(args.output, topics, args.storage,
                              args.duration, args.wait, report=print_error)


def _topic(name):
    """
    Return a ROS topic name as given, or refuse it (CliError).

    rcl's rules for a topic name without substitutions: tokens of letters,
    digits and underscores, not starting with a digit, separated by single
    slashes; an optional leading slash, no trailing one.
    """
    if not TOPIC_NAME.fullmatch(name):
        raise CliError(f'--topic {name!r}: not a valid ROS topic name '
                       '(letters, digits, underscores and single slashes, '
                       'no token starting with a digit)')
    return name


def _add_log_options(parser):
    """Add the options that read a log (identify, validate)."""
    parser.add_argument('--input', required=True, metavar='LOG',
                        help='CSV file, or rosbag2 bag (directory, .mcap or '
                        '.db3 file)')
    parser.add_argument('--topic', default=identification.DEFAULT_TOPIC,
                        help='joint states topic in a bag (default '
                        '%(default)s)')
    add_joint_names(parser, 'the joints in the joint states')
    parser.add_argument('--start', type=finite_float, metavar='S',
                        help='use the log from S seconds after its first '
                        'sample (default: from the first)')
    parser.add_argument('--end', type=finite_float, metavar='S',
                        help='use the log up to S seconds after its first '
                        'sample (default: to the last)')
    parser.add_argument('--cutoff', type=positive_float,
                        default=DEFAULT_CUTOFF, metavar='HZ',
                        help='cutoff of the zero-phase low-pass of the '
                        'forces and the regressor (Hz; default '
                        '%(default)g; the motion\'s is '
                        f'{identification.STATE_CUTOFF_FACTOR:g} times it), '
                        'below half the log\'s sampling rate')
    parser.add_argument('--payload', type=robot_range('payload'),
                        default=None, metavar='KG', help='the payload the '
                        'log was recorded with (kg on the platform, within '
                        'robot.payload\'s limits [{:g}, {:g}]; default: '
                        'robot.payload of --params, 0 in the paper\'s '
                        'robot): its forces are the model\'s'.format(
                            *ROW['payload'].limits))


def add_identify(parser):
    """Add the options of ``identify``: the base parameters from a log."""
    _add_log_options(parser)
    parser.add_argument('--output', required=True, metavar='FILE',
                        help='the identified robot as a ROS 2 parameters '
                        'file (section /**, every node\'s: every robot.* '
                        'parameter) for --params-file and --params')
    parser.add_argument('--report', metavar='FILE',
                        help='draw the measured and predicted forces (N) '
                        'per actuator and the residuals as a PNG image')
    parser.add_argument('--force-lag', type=finite_float, default=None,
                        metavar='S', help='the forces were applied S '
                        'seconds before their stamps (default: estimated '
                        'from the log, the lag of the least residual '
                        f'within +-{identification.LAG_SEARCH * 1e3:g} '
                        'ms; a simulator or drive that reports the force '
                        'held over its last step of dt: dt / 2)')
    parser.add_argument('--friction', default='auto',
                        choices=('auto',) + tuple(
                            identification.law_name(law)
                            for law in identification.LAWS),
                        help='the law: viscous + Coulomb friction '
                        '(coulomb), with ' + ', '.join(
                            _choice(term) for term in identification.OPTIONAL)
                        + '; auto (default): the simplest law within '
                        f'{100 * identification.SELECTION_MARGIN:g} %% of '
                        'the least RMS error on held-out parts of the '
                        'log, among those the --params robot can have')
    parser.add_argument('--stribeck-velocity',
                        type=robot_range('friction_stribeck_velocity'),
                        default=None, metavar='M/S',
                        help='the Stribeck speed v_b of a law with '
                        '+stribeck (default: the best of speeds '
                        f'{identification.STRIBECK_STEP:.3g} times apart '
                        'from the robot\'s friction_velocity to the '
                        'log\'s largest slider speed, refined)')
    parser.add_argument('--max-relative-std', type=positive_float,
                        default=identification.MAX_RELATIVE_STD,
                        metavar='PCT', help='a base parameter whose '
                        'relative standard deviation exceeds PCT %% '
                        '(default %(default)g) '
                        'is not excited by the log: held at its nominal '
                        'value unless the held-out error needs it')

    parser.add_argument('--validate', metavar='LOG',
                        help='another log (another motion): validate the '
                        'nominal and the identified robot on it, as '
                        'orthoglide validate does')
    parser.add_argument('--validate-report', metavar='FILE',
                        help='draw the validation of the identified robot '
                        '(as validate --report) as a PNG image')


def _choice(term):
    """Describe a term ``--friction`` may add: ``Stribeck ... (+stribeck)``."""
    parts = ''.join(f', with the {t.meaning.format("each slider")}'
                    for t in terms.TERMS if t.part_of == term.name)
    needs = term.rows[0].needs
    return (f'{term.meaning.format("each slider")} (+{term.name}{parts}'
            + (f'; needs robot.{needs} of --params' if needs else '') + ')')


def run_identify(robot, args):
    """Identify the base parameters from a log; print, write the file(s)."""
    if args.validate_report is not None and args.validate is None:
        raise CliError('--validate-report needs --validate LOG')
    joints = tuple(args.joint_names)
    with _refusals_in_one_line(args.input):
        log = identification.read_log(args.input, args.topic, joints)
        window = identification.crop(log, args.start, args.end)
        result = identification.identify(
            robot, window, args.cutoff, force_lag=args.force_lag,
            max_relative_std=args.max_relative_std,
            friction=None if args.friction == 'auto'
            else identification.parse_law(args.friction),
            stribeck_velocity=args.stribeck_velocity, payload=args.payload)
    validation = None
    if args.validate is not None:
        with _refusals_in_one_line(args.validate):
            other = identification.read_log(args.validate, args.topic, joints)
            # The lag is the drive's: the one given or found.
            validation = [identification.validate(model, other, args.cutoff,
                                                  result.force_lag)
                          for model in (robot, result.robot)]
    images = []
    if args.report is not None:
        images.append((args.report, drawn_png(
            lambda f: report.draw_identification(f, args.input, result),
            (13, 6.5), '--report')))
    if args.validate_report is not None:
        images.append((args.validate_report, drawn_png(
            lambda f: report.draw_validation(f, validation[1]), (13, 10),
            '--validate-report')))
    summary = report.identification_lines(args.input, log, window, result,
                                          args.cutoff)
    print('\n'.join(summary))
    notes = [*result.held, *result.notes]
    for note in notes:
        print(f'note: {note}')
    if validation is not None:
        print('\n'.join(report.validation_lines(validation[1],
                                                validation[0])))
    comments = [f'Identified by `orthoglide identify` from {args.input}',
                *summary[1:]] + [f'note: {n}' for n in notes]
    write_output(args.output, params_file.robot_file_text(
        result.robot, comments).encode('utf-8'))
    print(f'written: {args.output}')
    for path, image in images:
        write_output(path, image)
        print(f'written: {path}')
    return 0


def add_validate(parser):
    """Add the options of ``validate``: a robot against a log."""
    _add_log_options(parser)
    parser.add_argument('--report', metavar='FILE',
                        help='draw measured and predicted forces against '
                        'time and the error against the slider\'s speed '
                        'and position, per actuator, as a PNG image')
    parser.add_argument('--force-lag', type=finite_float, default=None,
                        metavar='S', help='the forces were applied S '
                        'seconds before their stamps (default: the lag '
                        'that best matches the prediction)')


def run_validate(robot, args):
    """Compare the robot's forces with a log's; print, draw (--report)."""
    with _refusals_in_one_line(args.input):
        log = identification.crop(identification.read_log(
            args.input, args.topic, tuple(args.joint_names)),
            args.start, args.end)
        validation = identification.validate(robot, log, args.cutoff,
                                             args.force_lag, args.payload)
    image = None if args.report is None else drawn_png(
        lambda f: report.draw_validation(f, validation), (13, 10),
        '--report')
    print('\n'.join(report.validation_lines(validation)))
    if image is not None:
        write_output(args.report, image)
        print(f'written: {args.report}')
    return 0


def _refusals_in_one_line(source):
    """
    Run identification's work on a log; its refusals become a CliError.

    The log's values, its motion and every option are checked in range
    before any arithmetic (formats.logs.LIMITS, motion.MOTION_LIMITS, the
    options' types), so no numpy warning is expected: one that still
    comes is refused in one line too (:func:`refusals_in_one_line`).
    """
    return refusals_in_one_line(
        source, (identification.LogError,
                 identification.IdentificationError),
        'a value of the log or an option is beyond what it can use')


SUBCOMMANDS = (
    Subcommand(
        'excitation', run_excitation, add_excitation,
        'a periodic trajectory for identification',
        'Write one period of an excitation as a trajectory CSV '
        'file (the batch input columns t, x, y, z (m), vx, vy, vz (m/s), ax, '
        'ay, az (m/s^2)): a finite Fourier series per axis of frame 0, '
        f'{trajectory.EXCITATION_HARMONICS} harmonics of 1 / duration with '
        'random coefficients from --seed, starting and ending at home at '
        'rest, within --box of home, --max-velocity and --max-acceleration '
        'per axis, inside the workspace, its actuator forces within '
        '--max-force. Prints its peaks, its smallest singularity distance '
        'and the condition number of its base regressor (the smaller the '
        'better: noise in a log is amplified by it); --optimize searches '
        'the coefficients for a smaller one. The setpoint_publisher '
        'streams the same motion (motion: excitation, seed, duration); an '
        '--optimize motion is streamed from the file (orthoglide batch '
        '--format joint_trajectory).'),
    Subcommand(
        'record', run_record, add_record,
        'record joint states into a rosbag2 bag (needs ROS 2)',
        'Record topics (serialized messages, stamped at '
        'reception) into a new rosbag2 bag directory for --duration seconds '
        '(Ctrl-C ends it earlier, the bag complete); their types are taken '
        'from their publishers. The bag is what identify reads (topic '
        f'{identification.DEFAULT_TOPIC}) and what ros2 bag reads. A '
        f'message {WHY["oversize"]} is dropped; the last line counts what '
        'was recorded and what was dropped, and why, and the exit code is '
        f'{LOSSY} when any was dropped (0 when none). Needs '
        'rclpy; DDS settings from the environment (ROS_DOMAIN_ID, '
        'ROS_AUTOMATIC_DISCOVERY_RANGE).', robot=False),
    Subcommand(
        'identify', run_identify, add_identify,
        'identify masses, drives and friction from a log',
        'Identify the base parameters (the combinations of the '
        'masses (kg), the drives\' armature (kg) and the viscous (N s/m) '
        'and Coulomb (N) friction of the sliders that the forces depend '
        'on) from a log, and write '
        'the identified robot as a ROS 2 parameters file. The log: a CSV '
        'file with the columns t (s), lambda_a, lambda_b, lambda_c (m), '
        'force_a, force_b, force_c (N) and, optional, lambdadot_a, '
        'lambdadot_b, lambdadot_c (m/s), or a rosbag2 bag (a directory, or '
        'its .mcap or .db3 file) of sensor_msgs/JointState (position: '
        'lambda, effort: force, header stamp: time). The forces and the '
        'regressor go through the same zero-phase low-pass; least squares; '
        'the robot of --params is the nominal one (its geometry, gravity '
        'and friction_velocity are kept). Prints each base parameter with '
        'its meaning, estimate and relative standard deviation, the '
        'condition number, the RMS residual per actuator, the samples used '
        'and their time span. A base parameter the log does not excite is '
        'held at its nominal value (unless the held-out error needs it), '
        'and said; a log that cannot be used at all (unreadable, too short, '
        'no motion) exits with code 2; nothing is then written.'),
    Subcommand(
        'validate', run_validate, add_validate,
        'predict the forces of a log, report the error',
        'Predict the actuator forces of a log (another motion '
        'than the one identified from) with the robot of --params (every '
        'robot.* parameter, friction included: the full model) and compare '
        'them with the measured ones, both through the same zero-phase '
        'low-pass as identify\'s. Prints per actuator the RMS and the '
        'largest error (N) and the share of the force explained (1 - '
        'sum(error^2) / sum(force^2)), with the force lag and the part of '
        'the log used. The log is read as by identify (CSV or rosbag2). A '
        'log that cannot be used exits with code 2.'),
)
