"""
The ``orthoglide`` command-line tool: the mechanics without ROS.

Subcommands (``orthoglide SUBCOMMAND --help`` for details):

- ``paper``: the paper's figures 3-8 over the trajectory of eq. (6), as a
  summary table, a CSV file (``--csv``) and a PNG figure (``--plot``).
- ``solve``: inverse kinematics and dynamics of one sample.
- ``batch``: the same for every row of a trajectory CSV file.
- ``excitation``: a periodic trajectory for identification (a ``batch``
  input file), its peaks and the condition number of its regressor.
- ``identify``: the robot's masses and friction from a log (a CSV file or
  a rosbag2 bag), written as a parameters file (``--output``), with a
  report on standard output (and ``--report``, a PNG).
- ``validate``: a robot's forces against another log's: the error per
  actuator, the share explained (and ``--report``, a PNG).
- ``record``: joint states into a rosbag2 bag (MCAP or sqlite3); the one
  subcommand that needs ROS (rclpy).
- ``urdf``: the robot's URDF (a cut tree, see :mod:`orthoglide_ros.model.urdf`).
- ``mjcf``: the robot's MJCF for MuJoCo, loops closed (:mod:`orthoglide_ros.model.mjcf`).
- ``render``: a picture of the robot from MuJoCo's offscreen renderer.
- ``draw``: a picture of the robot at one platform position (PNG).
- ``animate``: the robot moving along a trajectory, with its actuator
  forces (GIF).

Units are SI throughout: m, m/s, m/s^2, N, W, s. Bad input exits with code 2
and one line ``orthoglide: error: ...`` on standard error; output files are
written atomically, only once every sample is solved. scipy and rosbags
are imported by the subcommands that use them, rclpy by ``record`` alone.
"""

import argparse
import io
import json
import math
import os
import re
import stat
import sys
import tempfile

import numpy as np

from orthoglide_ros.formats import cdr, params_file
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.tools import excitation_design, identification
from orthoglide_ros.tools.identification import report
from orthoglide_ros.formats.csvfile import CsvError, read_columns
from orthoglide_ros.tools.identification import DEFAULT_CUTOFF
from orthoglide_ros.cores.parameters import JOINT_NAMES, joint_names
from orthoglide_ros.formats.params_file import (load_parameters, load_robot,
                                                ParametersFileError)
from orthoglide_ros.model.robot import ParameterError, Robot

PROG = 'orthoglide'
LEGS = ('a', 'b', 'c')
QUANTITIES = ('lambda', 'lambdadot', 'lambdaddot', 'force', 'power')
# Columns of every CSV the tool writes (SI units).
CSV_COLUMNS = ('t', 'x', 'y', 'z') + tuple(
    f'{q}_{leg}' for q in QUANTITIES for leg in LEGS)
# Columns of a trajectory file read by ``batch``: (group, names, required).
INPUT_GROUPS = (('time', ('t',), False),
                ('position', ('x', 'y', 'z'), True),
                ('velocity', ('vx', 'vy', 'vz'), False),
                ('acceleration', ('ax', 'ay', 'az'), False))
# The output options of every subcommand, checked before anything is
# computed or written.
OUTPUT_OPTIONS = ('output', 'report', 'csv', 'plot', 'validate_report')
TOPIC_NAME = re.compile(r'/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*')
UNITS = {'lambda': 'm', 'lambdadot': 'm/s', 'lambdaddot': 'm/s^2',
         'force': 'N', 'power': 'W'}
DEFAULT_SAMPLES = 201
# Pictures: size limits (pixels) and the animation's defaults.
MIN_PIXELS, MAX_PIXELS = 100, 4000
MAX_FRAMES = 1000
DEFAULT_FRAMES, DEFAULT_FPS = 41, 20.0


class CliError(Exception):
    """Bad input: printed as one line ``orthoglide: error: ...``."""

    def __init__(self, message, code=2):
        """Keep ``message`` and the exit ``code``."""
        super().__init__(message)
        self.code = code


def main(argv=None):
    """Run the tool on ``argv`` (default: sys.argv[1:]); return the code."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:      # --help, --version or a usage error
        return 0 if stop.code is None else stop.code
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        if args.command != 'record':    # a bag: the recorder's own checks
            for option in OUTPUT_OPTIONS:
                _check_output(getattr(args, option, None), option)
        # Every subcommand but record reads the robot (--params).
        robot = _robot(args.params) if 'params' in args else None
        return args.run(robot, args)
    except CliError as error:
        _fail(str(error))
        return error.code
    except (ParametersFileError, ParameterError) as error:
        where = f'{args.params}: ' if isinstance(
            error, ParameterError) else ''
        _fail(where + str(error))
        return 2


# -- paper ------------------------------------------------------------------

def run_paper(robot, args):
    """Solve the trajectory of eq. (6); write the CSV, plot or summary."""
    times = trajectory.paper_times(args.samples)
    p, v, a = trajectory.paper_batch(times)
    try:
        sol = mechanics.solve_batch(robot, p, v, a)
    except mechanics.WorkspaceError as error:
        raise CliError(f'the paper trajectory at t = {times[error.row]:.6g} '
                       f's: {_reason(error)}') from None
    outputs = []
    if args.plot is not None:
        outputs.append((args.plot, _plot_png(times, sol)))
    if args.csv is not None:
        outputs.append((args.csv, _csv_text(times, p, sol)))
    if not outputs:
        static = mechanics.solve(robot, tuple(float(c) for c in p[0]))
        print(_paper_summary(times, sol, static.force))
    for path, data in outputs:
        _write_output(path, data)
    return 0


def _paper_summary(times, sol, static_force):
    lines = [f'Paper trajectory, eq. (6): {len(times)} samples over '
             f'[{times[0]:g}, {times[-1]:g}] s', _row('', 'A', 'B', 'C')]
    for label, values in (
            ('peak |lambda| (m)', sol.lambda_),
            ('peak |force| (N)', sol.force),
            ('peak |power| (W)', sol.power)):
        lines.append(_row(label, *np.abs(values).max(0)))
    lines.append(_row('statics force at t=0 (N)', *static_force))
    return '\n'.join(lines)


def _plot_png(times, sol):
    """Render figures 3-8 as PNG bytes."""
    figure = _figure((13, 7), '--plot')
    axes = figure.subplots(2, 3, sharex=True)
    for j, leg in enumerate('ABC'):
        top, bottom = axes[0, j], axes[1, j]
        top.plot(times, sol.lambda_[:, j] * 1e3)
        top.set_title(f'Fig. {3 + j}: displacement of actuator {leg}')
        top.set_ylabel(f'$\\lambda_{leg}$ (mm)')
        bottom.plot(times, sol.power[:, j], color='tab:red')
        bottom.set_title(f'Fig. {6 + j}: power of actuator {leg}')
        bottom.set_ylabel(f'$p_{leg}$ (W)')
        bottom.set_xlabel('t (s)')
        for ax in (top, bottom):
            ax.grid(True, alpha=0.4)
    figure.suptitle('Orthoglide, trajectory of eq. (6)')
    return _png(figure)


# -- solve ------------------------------------------------------------------

def run_solve(robot, args):
    """Solve one sample; print a table or a JSON object."""
    try:
        sol = mechanics.solve(robot, args.position, args.velocity,
                              args.acceleration)
    except mechanics.WorkspaceError as error:
        raise CliError(str(error)) from None
    if args.json:
        record = dict(zip(('x', 'y', 'z'), args.position))
        for q, values in zip(QUANTITIES, sol):
            record.update(zip((f'{q}_{leg}' for leg in LEGS), values))
        print(json.dumps({k: float(v) for k, v in record.items()}))
        return 0
    lines = [_row('', 'A', 'B', 'C')]
    for q, values in zip(QUANTITIES, sol):
        lines.append(_row(f'{q} ({UNITS[q]})', *values))
    lines.append(f'singularity distance: {sol.singularity_distance:.6g} '
                 f'(1 at home, refused below '
                 f'{mechanics.DEFAULT_SINGULARITY_MARGIN:g})')
    print('\n'.join(lines))
    return 0


# -- batch ------------------------------------------------------------------

def run_batch(robot, args):
    """Solve every row of a trajectory file; write CSV or a JointTrajectory."""
    name = '<stdin>' if args.input == '-' else args.input
    times, p, v, a, lines = _read_trajectory(args.input, name)
    try:
        sol = mechanics.solve_batch(robot, p, v, a)
    except mechanics.WorkspaceError as error:
        raise CliError(f'{name}: data row {error.row + 1} (line '
                       f'{lines[error.row]}): {_reason(error)}') from None
    if args.format == 'joint_trajectory':
        data = _joint_trajectory_yaml(_time_from_start(times, lines, name),
                                      sol, _joint_names(args.params))
    else:
        data = _csv_text(times, p, sol)
    _write_output(args.output, data)
    return 0


def _time_from_start(times, lines, name):
    """
    Return the rows' ``t`` as time_from_start in nanoseconds (int64).

    Refused (CliError): no row, no ``t`` column, or a ``t`` that is
    negative, not below 2**31 s (a Duration's int32 seconds) or, rounded
    to the nanosecond, not later than the row before it.
    """
    if times is None:
        raise CliError(f'{name}: no \'t\' column: a joint trajectory '
                       'needs each point\'s time_from_start (s)')
    if len(times) == 0:
        raise CliError(f'{name}: no data row: a joint trajectory needs at '
                       'least one point')
    bad = (times < 0.0) | (times >= 2.0 ** 31)
    ns = np.round(np.where(bad, 0.0, times) * 1e9).astype(np.int64)
    bad |= np.r_[False, np.diff(ns) <= 0]
    if bad.any():
        row = int(np.argmax(bad)) + 1
        raise CliError(f'{name}: data row {row} (line {lines[row - 1]}): '
                       't must be in [0, 2**31) s and increase from row to '
                       'row (to the nanosecond)')
    return ns


def _joint_trajectory_yaml(ns, sol, names):
    """
    Format a trajectory_msgs/JointTrajectory as YAML (bytes).

    The message as ``ros2 topic pub`` and launch files read it: a zero
    header stamp (joint_trajectory_controller starts it on arrival),
    ``names``, one point per row with positions = lambda (m), velocities =
    lambdadot (m/s), accelerations = lambdaddot (m/s^2), effort = f (N)
    and time_from_start = ``ns`` (int64 nanoseconds). Doubles in full
    precision.
    """
    def row(values):
        return '[' + ', '.join(repr(float(x)) for x in values) + ']'
    out = ['header:', '  stamp:', '    sec: 0', '    nanosec: 0',
           "  frame_id: ''",
           'joint_names: [' + ', '.join(map(json.dumps, names)) + ']',
           'points:']
    for k in range(len(ns)):
        sec, nanosec = divmod(int(ns[k]), 10**9)
        out += [f'- positions: {row(sol.lambda_[k])}',
                f'  velocities: {row(sol.lambdadot[k])}',
                f'  accelerations: {row(sol.lambdaddot[k])}',
                f'  effort: {row(sol.force[k])}',
                '  time_from_start:', f'    sec: {sec}',
                f'    nanosec: {nanosec}']
    return ('\n'.join(out) + '\n').encode('utf-8')


def _joint_names(path):
    """Return the feedforward section's joint_names of ``path``, or the defaults."""
    if path is None:
        return JOINT_NAMES
    names = load_parameters(path).get('joint_names', list(JOINT_NAMES))
    try:
        return joint_names(names)
    except ValueError as error:
        raise CliError(f'{path}: joint_names: {error}') from None


def _read_trajectory(path, name):
    """
    Read ``t,x,y,z,vx,...`` by header name; return arrays and line numbers.

    ``t`` is None if the file has no ``t`` column; a missing velocity or
    acceleration group is None (zero).
    """
    try:
        values, lines = read_columns(path, INPUT_GROUPS, name)
    except CsvError as error:
        raise CliError(str(error)) from None
    times = values['time']
    return (None if times is None else times[:, 0], values['position'],
            values['velocity'], values['acceleration'], lines)


# -- excitation -------------------------------------------------------------

def run_excitation(robot, args):
    """Write an excitation (the best of --seeds) as a trajectory; describe it."""
    base = identification.base_parameters(
        robot, identification.design_law(robot))
    bounds = dict(box=args.box, max_velocity=args.max_velocity,
                  max_acceleration=args.max_acceleration)
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
    times = np.arange(0.0, args.duration, 1.0 / args.rate)
    p, v, a = trajectory.excitation_batch(motion, times)
    harmonics = motion.sines.shape[1]
    distance = mechanics.workspace_status(robot, p).singularity_distance
    lines += [
        f'Excitation: {made}, period {args.duration:g} s, '
        f'{harmonics} harmonics ({1.0 / args.duration:g} to '
        f'{harmonics / args.duration:g} Hz) per axis',
        _row('', 'x', 'y', 'z'),
        _row('peak |position| (m)', *np.abs(p).max(0)),
        _row('peak |velocity| (m/s)', *np.abs(v).max(0)),
        _row('peak |acceleration| (m/s^2)', *np.abs(a).max(0)),
        f'peak |actuator force| (N): {force:.4g}',
        f'smallest singularity distance: {distance.min():.4g}',
        f'base parameters: {", ".join(base.names)}',
        f'condition number of the base regressor: {condition:.4g} '
        '(unit-norm columns)']
    # With the trajectory on standard output, the description goes to
    # standard error.
    print('\n'.join(lines),
          file=sys.stderr if args.output == '-' else sys.stdout)
    _write_output(args.output, _table_csv(
        ('t',) + tuple(c for _, names, _ in INPUT_GROUPS[1:] for c in names),
        times, np.column_stack((p, v, a))))
    return 0


def _excitation(robot, seed, duration, bounds):
    try:
        return trajectory.excitation(seed, duration, robot=robot, **bounds)
    except ValueError as error:
        raise CliError(f'seed {seed}: {error}') from None


# -- identify and validate -------------------------------------------------

def run_identify(robot, args):
    """Identify the base parameters from a log; print, write the file(s)."""
    if args.validate_report is not None and args.validate is None:
        raise CliError('--validate-report needs --validate LOG')
    joints = tuple(args.joint_names)
    try:
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
            other = identification.read_log(args.validate, args.topic, joints)
            # The lag is the drive's: the one given or found.
            validation = [identification.validate(model, other, args.cutoff,
                                                  result.force_lag)
                          for model in (robot, result.robot)]
    except (identification.LogError,
            identification.IdentificationError) as error:
        raise CliError(str(error)) from None
    images = []
    if args.report is not None:
        images.append((args.report, _drawn(
            lambda f: report.draw_identification(f, args.input, result),
            (13, 6.5), '--report')))
    if args.validate_report is not None:
        images.append((args.validate_report, _drawn(
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
    _write_output(args.output, params_file.robot_file_text(
        result.robot, comments).encode('utf-8'))
    print(f'written: {args.output}')
    for path, image in images:
        _write_output(path, image)
        print(f'written: {path}')
    return 0


def run_validate(robot, args):
    """Compare the robot's forces with a log's; print, draw (--report)."""
    try:
        log = identification.crop(identification.read_log(
            args.input, args.topic, tuple(args.joint_names)),
            args.start, args.end)
        validation = identification.validate(robot, log, args.cutoff,
                                             args.force_lag, args.payload)
    except identification.LogError as error:
        raise CliError(str(error)) from None
    image = None if args.report is None else _drawn(
        lambda f: report.draw_validation(f, validation), (13, 10),
        '--report')
    print('\n'.join(report.validation_lines(validation)))
    if image is not None:
        _write_output(args.report, image)
        print(f'written: {args.report}')
    return 0


def _drawn(draw, size, option):
    """Return the PNG bytes of ``draw(figure)`` on a new figure."""
    figure = _figure(size, option)
    draw(figure)
    return _png(figure)


# -- record -----------------------------------------------------------------

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
                              args.duration, args.wait)


# -- urdf -------------------------------------------------------------------

def run_urdf(robot, args):
    """Write the robot's URDF (standard output or ``--output``)."""
    from orthoglide_ros.model import urdf
    try:
        names = joint_names(args.joint_names)
    except ValueError as error:
        raise CliError(f'--joint-names: {error}') from None
    text = urdf.urdf(robot, names, args.singularity_margin)
    _write_output(args.output, text.encode('utf-8'))
    return 0


# -- mjcf -------------------------------------------------------------------

def run_mjcf(robot, args):
    """Write the robot's MJCF (standard output or ``--output``)."""
    from orthoglide_ros.model import mjcf
    try:
        names = joint_names(args.joint_names)
    except ValueError as error:
        raise CliError(f'--joint-names: {error}') from None
    if args.armature is not None:
        robot = robot.replace(armature=tuple(args.armature))
    text = mjcf.mjcf(robot, names, args.force_limit)
    _write_output(args.output, text.encode('utf-8'))
    return 0


# -- draw, animate ----------------------------------------------------------

def run_draw(robot, args):
    """Draw the robot at one platform position; write a PNG."""
    _check_extension(args.output, '.png')
    drawing = _drawing()
    try:
        data = drawing.draw(robot, args.position, args.size)
    except mechanics.WorkspaceError as error:
        raise CliError(str(error)) from None
    _write_output(args.output, data)
    return 0


def run_render(robot, args):
    """
    Render the robot with MuJoCo; write a PNG, or a GIF along eq. (6).

    A ``.png`` at ``--position``; a ``.gif``: ``--frames`` along the
    paper's trajectory (the demos' motion), ``--fps`` frames a second.
    """
    animated = args.output.lower().endswith('.gif')
    if not animated:
        _check_extension(args.output, '.png')
        if args.position is None:
            raise CliError('--position X Y Z is needed for a PNG')
    from orthoglide_ros.tools.rendering import Renderer, RenderError
    try:
        renderer = Renderer(robot, args.size)
        try:
            if animated:
                positions = trajectory.paper_batch(
                    trajectory.paper_times(max(args.frames, 2)))[0]
                data = renderer.gif(positions, args.fps)
            else:
                data = renderer.png(args.position)
        finally:
            renderer.close()
    except (RenderError, mechanics.WorkspaceError) as error:
        raise CliError(str(error)) from None
    _write_output(args.output, data)
    return 0


def run_animate(robot, args):
    """Animate the robot along a trajectory; write a GIF."""
    _check_extension(args.output, '.gif')
    drawing = _drawing()
    if args.input is None:
        times = trajectory.paper_times(max(args.frames, 2))
        p, v, a = trajectory.paper_batch(times)
        where = 'the paper trajectory'
        lines = None
    else:
        where = '<stdin>' if args.input == '-' else args.input
        times, p, v, a, lines = _read_trajectory(args.input, where)
        if not len(p):
            raise CliError(f'{where}: no data row')
    try:
        sol = mechanics.solve_batch(robot, p, v, a)
    except mechanics.WorkspaceError as error:
        if lines is None:
            raise CliError(f'{where} at t = {times[error.row]:.6g} s: '
                           f'{_reason(error)}') from None
        raise CliError(f'{where}: data row {error.row + 1} (line '
                       f'{lines[error.row]}): {_reason(error)}') from None
    rows = drawing.frame_rows(len(p), args.frames)
    data = drawing.animate(
        robot, None if times is None else times[rows], p[rows],
        sol.force[rows], args.size, args.fps,
        'Orthoglide, ' + ('eq. (6)' if lines is None
                          else os.path.basename(where)))
    _write_output(args.output, data)
    return 0


def _drawing():
    try:
        from orthoglide_ros.tools import drawing
        import matplotlib  # noqa: F401
    except ImportError:
        raise CliError('drawing needs matplotlib (pip install matplotlib)',
                       code=1) from None
    return drawing


def _check_extension(path, extension):
    if not path.lower().endswith(extension):
        raise CliError(f'--output {path}: the file name must end with '
                       f'{extension} (the picture is written as '
                       f'{extension[1:].upper()})')


# -- shared -----------------------------------------------------------------

def _csv_text(times, positions, sol):
    """Format samples as CSV bytes (CSV_COLUMNS, repr); times may be None."""
    return _table_csv(CSV_COLUMNS, times, np.column_stack(
        [positions] + [np.asarray(values) for values in sol[:5]]))


def _table_csv(columns, times, table):
    """Format ``t`` and the (N, k) ``table`` as CSV bytes (full precision)."""
    out = [','.join(columns)]
    t_cells = [''] * len(table) if times is None else map(
        repr, np.asarray(times, dtype=float).tolist())
    for t, row in zip(t_cells, table.tolist()):
        out.append(t + ',' + ','.join(map(repr, row)))
    return ('\n'.join(out) + '\n').encode('utf-8')


def _figure(size, option):
    """Return a matplotlib Figure on the Agg canvas (no pyplot)."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        raise CliError(f'{option} needs matplotlib (pip install matplotlib)',
                       code=1) from None
    figure = Figure(figsize=size, layout='constrained')
    FigureCanvasAgg(figure)
    return figure


def _png(figure):
    """Return ``figure`` as PNG bytes."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format='png', dpi=100)
    return buffer.getvalue()


def _check_output(path, option):
    """
    Refuse an output path that cannot be written, before anything is.

    None and ``-`` (standard output) pass. A symbolic link is followed to
    its target; the target must be a regular file, a device or a FIFO, or
    not exist in an existing directory.
    """
    if path is None or path == '-':
        return
    target = os.path.realpath(path)
    if os.path.isdir(target):
        raise CliError(f'--{option} {path}: is a directory')
    directory = os.path.dirname(target)
    if not os.path.isdir(directory):
        raise CliError(f'--{option} {path}: no such directory: {directory}')
    if not os.path.exists(target) and not os.access(directory, os.W_OK):
        raise CliError(f'--{option} {path}: cannot write in {directory}')


def _write_output(path, data):
    """
    Write bytes to ``path``; atomically where it is a regular file.

    A regular file (or a new one) is written to a temporary file renamed
    over it (os.replace); a symbolic link is followed to its target; a
    device or a FIFO is written through, as any Unix tool does, never
    replaced.
    """
    if path is None or path == '-':
        sys.stdout.write(data.decode('utf-8'))
        sys.stdout.flush()
        return
    target = os.path.realpath(path)
    try:
        special = not stat.S_ISREG(os.stat(target).st_mode)
    except FileNotFoundError:
        special = False
    except OSError as error:
        raise CliError(f'cannot write {path}: {error.strerror}') from None
    if special:
        try:
            with open(target, 'wb') as stream:
                stream.write(data)
        except OSError as error:
            raise CliError(f'cannot write {path}: {error.strerror}') \
                from None
        return
    path = target
    directory = os.path.dirname(path)
    try:
        mode = os.stat(path).st_mode & 0o777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    try:
        fd, tmp = tempfile.mkstemp(dir=directory, suffix='.tmp',
                                   prefix='.' + os.path.basename(path) + '.')
    except OSError as error:
        raise CliError(f'cannot write {path}: {error.strerror}') from None
    try:
        with os.fdopen(fd, 'wb') as stream:
            stream.write(data)
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except OSError as error:
        os.unlink(tmp)
        raise CliError(f'cannot write {path}: {error.strerror}') from None


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


def _robot(path):
    return Robot() if path is None else load_robot(path)


def _reason(error):
    """Return a WorkspaceError's message less its 0-based sample prefix."""
    message = str(error)
    if error.row is not None:
        message = message.removeprefix(f'sample {error.row}: ')
    return message


def _row(label, *values):
    cells = [v if isinstance(v, str) else f'{float(v):.6g}' for v in values]
    return f'{label:<26}' + ''.join(f'{c:>14}' for c in cells)


def _fail(message):
    print(f'{PROG}: error: {" ".join(message.split())}', file=sys.stderr)


def _within(kind, low, high=math.inf, above=False, unit=''):
    """
    Return an argparse type: a finite ``kind`` (int or float) in range.

    ``[low, high]``, or above ``low`` when ``above``; ``unit`` ends the
    message of a refusal.
    """
    noun = 'an integer' if kind is int else 'a finite number'
    span = (f'above {low:g}' if above else f'of at least {low:g}'
            if high == math.inf else f'in [{low:g}, {high:g}]')

    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value <= high
                and (value > low if above else value >= low)):
            raise argparse.ArgumentTypeError(
                f'must be {noun} {span}{unit}, got {text!r}')
        return value
    return parse


_pixels = _within(int, MIN_PIXELS, MAX_PIXELS, unit=' pixels')
_frames = _within(int, 1, MAX_FRAMES)
_fps = _within(float, 0.5, 50.0, unit=' frames/s')
_margin = _within(float, 0.0, 0.99)
_samples = _within(int, 2)
_positive_float = _within(float, 0.0, above=True)
_non_negative_float = _within(float, 0.0)
_finite_float = _within(float, -math.inf)
_count = _within(int, 0)
_positive_count = _within(int, 1)


def _log_options():
    """Return the parent parser of the options that read a log."""
    options = argparse.ArgumentParser(add_help=False)
    options.add_argument('--input', required=True, metavar='LOG',
                         help='CSV file, or rosbag2 bag (directory, .mcap or '
                         '.db3 file)')
    options.add_argument('--topic', default=identification.DEFAULT_TOPIC,
                         help='joint states topic in a bag (default '
                         f'{identification.DEFAULT_TOPIC})')
    options.add_argument('--joint-names', nargs=3, metavar='NAME',
                         default=list(JOINT_NAMES),
                         help='joints of actuators A, B, C in the joint '
                         'states (default ' + ' '.join(JOINT_NAMES) + ')')
    options.add_argument('--start', type=float, metavar='S',
                         help='use the log from S seconds after its first '
                         'sample (default: from the first)')
    options.add_argument('--end', type=float, metavar='S',
                         help='use the log up to S seconds after its first '
                         'sample (default: to the last)')
    options.add_argument('--cutoff', type=_positive_float,
                         default=DEFAULT_CUTOFF, metavar='HZ',
                         help='cutoff of the zero-phase low-pass of the '
                         'forces and the regressor (Hz; default '
                         f'{DEFAULT_CUTOFF:g}; the motion\'s is '
                         f'{identification.STATE_CUTOFF_FACTOR:g} times it), '
                         'below half the log\'s sampling rate')
    options.add_argument('--payload', type=_non_negative_float, default=None,
                         metavar='KG', help='the payload the log was '
                         'recorded with (kg on the platform; default: '
                         'robot.payload of --params, 0 in the paper\'s '
                         'robot): its forces are the model\'s')
    return options


def _version():
    try:
        from importlib.metadata import version
        return version('orthoglide_ros')
    except Exception:       # not installed: running from a source tree
        return 'unknown'


def _parser():
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        '--params', metavar='FILE',
        help='ROS 2 parameters file with the robot.* parameters (as '
             'config/orthoglide.yaml: lengths m, angle rad, masses kg, '
             'gravity m/s^2, slider friction N s/m and N); default: the '
             'paper\'s robot')
    parser = argparse.ArgumentParser(
        prog=PROG, description='Inverse kinematics and dynamics of the '
        'Orthoglide, without ROS. Units: m, m/s, m/s^2, N, W, s. Bad input '
        'exits with code 2 and one line on standard error.')
    parser.add_argument('--version', action='version',
                        version=f'%(prog)s {_version()}')
    sub = parser.add_subparsers(dest='command', metavar='COMMAND')
    columns = ', '.join(CSV_COLUMNS)

    paper = sub.add_parser(
        'paper', parents=[common], help='reproduce the paper\'s figures 3-8',
        description='Solve the trajectory of eq. (6), r_G(t) = r* (1 - '
        'cos(pi t / 3)) with r* = (0.05, 0.10, -0.20) m, over [0, 2] s: '
        'actuator displacements lambda (m; figures 3-5) and powers p (W; '
        'figures 6-8). Without --csv or --plot, print peak |lambda| (m), '
        '|force| (N), |power| (W) per actuator and the statics force (N) at '
        't = 0.')
    paper.add_argument('--samples', type=_samples, default=DEFAULT_SAMPLES,
                       metavar='N', help='number of instants evenly spaced '
                       'over [0, 2] s, both ends included (default '
                       f'{DEFAULT_SAMPLES})')
    paper.add_argument('--csv', metavar='FILE', help='write the samples as '
                       f'CSV ({columns}; SI units); - for standard output')
    paper.add_argument('--plot', metavar='FILE', help='write figures 3-8 as '
                       'a PNG image (needs matplotlib)')
    paper.set_defaults(run=run_paper)

    solve = sub.add_parser(
        'solve', parents=[common], help='solve one sample',
        description='Inverse kinematics and dynamics of one sample: lambda '
        '(m), lambdadot (m/s), lambdaddot (m/s^2), force (N, on each slider '
        'along +lambda) and power (W) of actuators A, B, C.')
    solve.add_argument('--position', type=float, nargs=3, required=True,
                       metavar=('X', 'Y', 'Z'),
                       help='platform centre in the base frame (m)')
    solve.add_argument('--velocity', type=float, nargs=3,
                       default=mechanics.ZERO, metavar=('VX', 'VY', 'VZ'),
                       help='its velocity (m/s; default 0 0 0)')
    solve.add_argument('--acceleration', type=float, nargs=3,
                       default=mechanics.ZERO, metavar=('AX', 'AY', 'AZ'),
                       help='its acceleration (m/s^2; default 0 0 0)')
    solve.add_argument('--json', action='store_true', help='print one JSON '
                       f'object with the keys {columns[3:]} (SI units, full '
                       'double precision)')
    solve.set_defaults(run=run_solve)

    batch = sub.add_parser(
        'batch', parents=[common], help='solve a trajectory CSV file',
        description='Solve every row of a trajectory CSV file. Columns are '
        'matched by header name, in any order, case-insensitively; others '
        'are ignored. x, y, z (m) are required; vx, vy, vz (m/s) and ax, '
        'ay, az (m/s^2) are optional, each group all or none, a missing '
        'group meaning zero; t (s) is optional and copied to the output, '
        'left empty if absent. Blank lines are skipped; rows are counted '
        'from 1 after the header. Output columns: ' + columns + ' (SI '
        'units). Nothing is written unless every row is solved.')
    batch.add_argument('--input', required=True, metavar='FILE',
                       help='trajectory CSV file; - for standard input')
    batch.add_argument('--format', choices=('csv', 'joint_trajectory'),
                       default='csv', help='csv: the columns above '
                       '(default); joint_trajectory: a trajectory_msgs/'
                       'JointTrajectory in YAML, as ros2 topic pub and '
                       'launch files read it (needs t; joint names from '
                       'the --params file\'s joint_names, default '
                       'slider_a, slider_b, slider_c)')
    batch.add_argument('--output', metavar='FILE', help='result file '
                       '(default: standard output)')
    batch.set_defaults(run=run_batch)

    excitation = sub.add_parser(
        'excitation', parents=[common],
        help='a periodic trajectory for identification',
        description='Write one period of an excitation as a trajectory CSV '
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
        '--format joint_trajectory).')
    excitation.add_argument('--duration', type=_positive_float,
                            required=True, metavar='S',
                            help='period of the series and length of the '
                            'file (s)')
    excitation.add_argument('--output', required=True, metavar='FILE',
                            help='trajectory CSV file (t, x, y, z, vx, vy, '
                            'vz, ax, ay, az; SI units), as orthoglide batch '
                            'reads it; - for standard output (the '
                            'description then goes to standard error)')
    excitation.add_argument('--seed', type=_count, default=0, metavar='N',
                            help='seed of the coefficients, an integer >= 0'
                            ' (default 0)')
    excitation.add_argument('--seeds', type=_positive_count, default=1,
                            metavar='K',
                            help='try the K seeds from --seed on and write '
                            'the one of the smallest condition number '
                            '(default 1)')
    excitation.add_argument('--rate', type=_positive_float, default=1000.0,
                            metavar='HZ', help='samples per second of the '
                            'file (default 1000)')
    excitation.add_argument('--box', type=_positive_float,
                            default=trajectory.EXCITATION_BOX, metavar='M',
                            help='largest |x|, |y|, |z| from home (m; '
                            f'default {trajectory.EXCITATION_BOX:g})')
    excitation.add_argument('--max-velocity', type=_positive_float,
                            default=trajectory.EXCITATION_MAX_VELOCITY,
                            metavar='M/S', help='largest speed per axis '
                            '(m/s; default '
                            f'{trajectory.EXCITATION_MAX_VELOCITY:g})')
    excitation.add_argument('--max-acceleration', type=_positive_float,
                            default=trajectory.EXCITATION_MAX_ACCELERATION,
                            metavar='M/S2', help='largest acceleration per '
                            'axis (m/s^2; default '
                            f'{trajectory.EXCITATION_MAX_ACCELERATION:g})')
    excitation.add_argument('--max-force', type=_positive_float,
                            default=math.inf, metavar='N',
                            help='largest actuator force of the --params '
                            'robot along the motion (N; default: none)')
    excitation.add_argument('--optimize', action='store_true',
                            help='search the Fourier coefficients, from the '
                            'seed\'s, for a smaller condition number within '
                            'the same bounds (L-BFGS-B); prints the seed\'s '
                            'and the optimized one\'s')
    excitation.add_argument('--evaluations', type=_positive_count,
                            default=excitation_design.DEFAULT_EVALUATIONS,
                            metavar='N', help='condition numbers the '
                            '--optimize search may compute (default '
                            f'{excitation_design.DEFAULT_EVALUATIONS}: about '
                            '10 s)')
    excitation.set_defaults(run=run_excitation)

    identify = sub.add_parser(
        'identify', parents=[common, _log_options()],
        help='identify masses, drives and friction from a log',
        description='Identify the base parameters (the combinations of the '
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
        'no motion) exits with code 2; nothing is then written.')
    identify.add_argument('--output', required=True, metavar='FILE',
                          help='the identified robot as a ROS 2 parameters '
                          'file (section feedforward, every robot.* '
                          'parameter) for --params-file and --params')
    identify.add_argument('--report', metavar='FILE',
                          help='draw the measured and predicted forces (N) '
                          'per actuator and the residuals as a PNG image')
    identify.add_argument('--force-lag', type=_finite_float, default=None,
                          metavar='S', help='the forces were applied S '
                          'seconds before their stamps (default: estimated '
                          'from the log, the lag of the least residual '
                          f'within +-{identification.LAG_SEARCH * 1e3:g} '
                          'ms; a simulator or drive that reports the force '
                          'held over its last step of dt: dt / 2)')
    identify.add_argument('--friction', default='auto',
                          choices=('auto',) + tuple(
                              identification.law_name(law)
                              for law in identification.LAWS),
                          help='the law: viscous + Coulomb friction '
                          '(coulomb), with a Coulomb level per direction '
                          '(+direction), with a Stribeck excess at low '
                          'speed (+stribeck), with the drives\' armature '
                          '(+armature); auto (default): the simplest law '
                          'within '
                          f'{100 * identification.SELECTION_MARGIN:g} %% of '
                          'the least RMS error on held-out parts of the '
                          'log')
    identify.add_argument('--stribeck-velocity', type=_positive_float,
                          default=None, metavar='M/S',
                          help='the Stribeck speed v_b of a law with '
                          '+stribeck (default: the best of '
                          f'{len(identification.STRIBECK_VELOCITIES)} from '
                          f'{identification.STRIBECK_VELOCITIES[0]:g} to '
                          f'{identification.STRIBECK_VELOCITIES[-1]:g} m/s)')
    identify.add_argument('--max-relative-std', type=_positive_float,
                          default=identification.MAX_RELATIVE_STD,
                          metavar='PCT', help='a base parameter whose '
                          'relative standard deviation exceeds PCT %% '
                          f'(default {identification.MAX_RELATIVE_STD:g}) '
                          'is not excited by the log: held at its nominal '
                          'value unless the held-out error needs it')

    identify.add_argument('--validate', metavar='LOG',
                          help='another log (another motion): validate the '
                          'nominal and the identified robot on it, as '
                          'orthoglide validate does')
    identify.add_argument('--validate-report', metavar='FILE',
                          help='draw the validation of the identified robot '
                          '(as validate --report) as a PNG image')
    identify.set_defaults(run=run_identify)

    validate = sub.add_parser(
        'validate', parents=[common, _log_options()],
        help='predict the forces of a log, report the error',
        description='Predict the actuator forces of a log (another motion '
        'than the one identified from) with the robot of --params (every '
        'robot.* parameter, friction included: the full model) and compare '
        'them with the measured ones, both through the same zero-phase '
        'low-pass as identify\'s. Prints per actuator the RMS and the '
        'largest error (N) and the share of the force explained (1 - '
        'sum(error^2) / sum(force^2)), with the force lag and the part of '
        'the log used. The log is read as by identify (CSV or rosbag2). A '
        'log that cannot be used exits with code 2.')
    validate.add_argument('--report', metavar='FILE',
                          help='draw measured and predicted forces against '
                          'time and the error against the slider\'s speed '
                          'and position, per actuator, as a PNG image')
    validate.add_argument('--force-lag', type=_finite_float, default=None,
                          metavar='S', help='the forces were applied S '
                          'seconds before their stamps (default: the lag '
                          'that best matches the prediction)')
    validate.set_defaults(run=run_validate)

    record = sub.add_parser(
        'record', help='record joint states into a rosbag2 bag (needs ROS 2)',
        description='Record topics (serialized messages, stamped at '
        'reception) into a new rosbag2 bag directory for --duration seconds '
        '(Ctrl-C ends it earlier, the bag complete); their types are taken '
        'from their publishers. The bag is what identify reads (topic '
        f'{identification.DEFAULT_TOPIC}) and what ros2 bag reads. Needs '
        'rclpy; DDS settings from the environment (ROS_DOMAIN_ID, '
        'ROS_AUTOMATIC_DISCOVERY_RANGE).')
    record.add_argument('--output', required=True, metavar='BAG',
                        help='bag directory to create (must not exist)')
    record.add_argument('--duration', type=_positive_float, required=True,
                        metavar='S', help='stop after S seconds')
    record.add_argument('--topic', action='append', metavar='NAME',
                        help='topic to record, repeatable (default '
                        f'{identification.DEFAULT_TOPIC})')
    record.add_argument('--storage', choices=cdr.BAG_STORAGES,
                        default=cdr.BAG_STORAGES[0], help='storage (default mcap, as '
                        'ros2 bag record)')
    record.add_argument('--wait', type=_positive_float, default=10.0,
                        metavar='S', help='longest wait for each topic\'s '
                        'publisher (s; default 10)')
    record.set_defaults(run=run_record)
    urdf = sub.add_parser(
        'urdf', parents=[common], help='write the robot\'s URDF',
        description='Write the URDF of the robot (lengths m, masses kg, '
        'inertias kg m^2, angles rad): a cut tree of the closed mechanism '
        'for robot_state_publisher, whose every moving joint the '
        'mechanism_state_publisher node publishes. Joint limits are the '
        'ranges over the workspace within the singularity margin.')
    urdf.add_argument('--output', metavar='FILE', help='URDF file '
                      '(default: standard output)')
    urdf.add_argument('--joint-names', nargs=3, metavar=('A', 'B', 'C'),
                      default=list(JOINT_NAMES), help='names of '
                      'the prismatic joints of actuators A, B, C (default: '
                      + ' '.join(JOINT_NAMES) + ')')
    urdf.add_argument('--singularity-margin', type=_margin,
                      default=mechanics.DEFAULT_SINGULARITY_MARGIN,
                      metavar='D', help='the workspace of the joint limits: '
                      'singularity distance at least D, in [0, 0.99] '
                      f'(default {mechanics.DEFAULT_SINGULARITY_MARGIN:g})')
    urdf.set_defaults(run=run_urdf)
    mjcf = sub.add_parser(
        'mjcf', parents=[common], help='write the robot\'s MJCF (MuJoCo)',
        description='Write the robot as a MuJoCo model (MJCF): the URDF\'s '
        'bodies, masses and inertias, the loops closed by equality '
        'constraints, three force actuators named as the sliders (N); '
        'see doc/mujoco.md.')
    mjcf.add_argument('--output', metavar='FILE', help='MJCF file '
                      '(default: standard output)')
    mjcf.add_argument('--joint-names', nargs=3, metavar=('A', 'B', 'C'),
                      default=list(JOINT_NAMES), help='names of '
                      'the slide joints and actuators A, B, C (default: '
                      + ' '.join(JOINT_NAMES) + ')')
    mjcf.add_argument('--force-limit', type=_positive_float, default=None,
                      metavar='N', help='the actuators\' control range '
                      '+-N (newton; default: none)')
    mjcf.add_argument('--armature', type=_non_negative_float, nargs=3,
                      default=None, metavar=('A', 'B', 'C'),
                      help='the drives\' inertia reflected to each slider '
                      '(kg; MuJoCo\'s armature): sets robot.armature '
                      '(default: the parameters file\'s, 0 in the paper\'s '
                      'robot)')
    mjcf.set_defaults(run=run_mjcf)

    draw = sub.add_parser(
        'draw', parents=[common], help='draw the robot at a position (PNG)',
        description='Draw the robot in 3D with its platform centre at a '
        'position: every body, the actuator axes, the paper\'s workspace '
        'cube (|x|, |y|, |z| <= 0.3 m) and the actuator forces (N) that '
        'hold it at rest there. Needs matplotlib.')
    draw.add_argument('--position', type=float, nargs=3, required=True,
                      metavar=('X', 'Y', 'Z'),
                      help='platform centre in the base frame (m)')
    draw.add_argument('--output', required=True, metavar='FILE.png',
                      help='PNG file to write')
    draw.add_argument('--size', type=_pixels, nargs=2, default=(800, 800),
                      metavar=('WIDTH', 'HEIGHT'), help='image size in '
                      'pixels (default 800 800)')
    draw.set_defaults(run=run_draw)

    render = sub.add_parser(
        'render', parents=[common], help='render the robot at a position '
        'with MuJoCo (PNG)',
        description='Render the robot\'s MuJoCo model (orthoglide mjcf) '
        'with its platform centre at a position, through MuJoCo\'s '
        'offscreen renderer (OpenGL: MUJOCO_GL=egl by default, or osmesa). '
        'Needs mujoco; exits 2 where no OpenGL backend exists. A .gif '
        'output animates the robot along the paper\'s trajectory.')
    render.add_argument('--position', type=float, nargs=3,
                        metavar=('X', 'Y', 'Z'),
                        help='platform centre in the base frame (m; for a '
                        'PNG)')
    render.add_argument('--output', required=True, metavar='FILE.png|.gif',
                        help='PNG file, or GIF (animation) to write')
    render.add_argument('--frames', type=_frames, default=DEFAULT_FRAMES,
                        help=f'GIF frames along eq. (6) (default '
                        f'{DEFAULT_FRAMES})')
    render.add_argument('--fps', type=_fps, default=DEFAULT_FPS,
                        help=f'GIF frames per second (default '
                        f'{DEFAULT_FPS:g})')
    render.add_argument('--size', type=_pixels, nargs=2, default=(800, 600),
                        metavar=('WIDTH', 'HEIGHT'), help='image size in '
                        'pixels (default 800 600)')
    render.set_defaults(run=run_render)

    animate = sub.add_parser(
        'animate', parents=[common], help='animate the robot along a '
        'trajectory (GIF)',
        description='Animate the robot along a trajectory with each '
        'actuator\'s force (N, an arrow along its slider) and the time. '
        'The trajectory is the paper\'s, eq. (6), or a CSV file read as '
        'batch reads it (x, y, z in m; vx, vy, vz in m/s and ax, ay, az in '
        'm/s^2 optional; t in s optional); its rows are sampled evenly '
        'down to --frames. Needs matplotlib.')
    animate.add_argument('--input', metavar='FILE', help='trajectory CSV '
                         'file, - for standard input (default: the paper\'s '
                         'trajectory, eq. (6))')
    animate.add_argument('--output', required=True, metavar='FILE.gif',
                         help='GIF file to write')
    animate.add_argument('--frames', type=_frames, default=DEFAULT_FRAMES,
                         metavar='N', help='frames at most, evenly spread '
                         f'over the trajectory (default {DEFAULT_FRAMES})')
    animate.add_argument('--fps', type=_fps, default=DEFAULT_FPS,
                         metavar='F', help='frames per second of the GIF '
                         f'(default {DEFAULT_FPS:g}: eq. (6) in real time)')
    animate.add_argument('--size', type=_pixels, nargs=2,
                         default=(640, 640), metavar=('WIDTH', 'HEIGHT'),
                         help='image size in pixels (default 640 640)')
    animate.set_defaults(run=run_animate)
    return parser


if __name__ == '__main__':
    sys.exit(main())
