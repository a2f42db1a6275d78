"""
What the ``orthoglide`` subcommands share: errors, columns, files, types.

:class:`CliError` (one line, exit code 2), the columns the tool writes and
reads, the output files checked before anything is computed and written
atomically (doc/cli.md#exit-codes), the ``--params`` file read once
(``args.parameters``: its robot, its joint names), the joint trajectory
YAML ``batch`` and ``plan`` write, argparse types of finite numbers in
range and the options several subcommands take.
"""

import argparse
from collections import namedtuple
import contextlib
import io
import json
import math
import os
import stat
import sys
import tempfile
import warnings

import numpy as np

from orthoglide_ros.cores.parameters import joint_names
from orthoglide_ros.formats.csvfile import CsvError, read_columns
from orthoglide_ros.formats.params_file import ParametersFile
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import (JOINT_NAMES, LEGS, ParameterError,
                                        Robot, ROW)

PROG = 'orthoglide'
QUANTITIES = ('lambda', 'lambdadot', 'lambdaddot', 'force', 'power')
# Columns of every CSV the tool writes (SI units).
CSV_COLUMNS = ('t', 'x', 'y', 'z') + tuple(
    f'{q}_{leg}' for q in QUANTITIES for leg in LEGS)
# Rows of a CSV file formatted at a time (about 2 MB of text).
CSV_CHUNK_ROWS = 10_000
# Columns of a trajectory file read by ``batch``: (group, names, required).
INPUT_GROUPS = (('time', ('t',), False),
                ('position', ('x', 'y', 'z'), True),
                ('velocity', ('vx', 'vy', 'vz'), False),
                ('acceleration', ('ax', 'ay', 'az'), False))
# The options that name files, by role, the same in every subcommand (a
# new file option goes in one of the two): checked before anything is read,
# computed or written.
INPUT_OPTIONS = ('params', 'input', 'validate', 'limits')
OUTPUT_OPTIONS = ('output', 'report', 'csv', 'plot', 'validate_report')


class CliError(Exception):
    """Bad input: printed as one line ``orthoglide: error: ...``."""

    def __init__(self, message, code=2):
        """Keep ``message`` and the exit ``code``."""
        super().__init__(message)
        self.code = code


@contextlib.contextmanager
def refusals_in_one_line(source, refusals, meaning, numeric=()):
    """
    Run a tool's work on ``source``; its refusals become a CliError.

    ``refusals``: the exception types whose message is the line. A numpy
    warning (a computation that left the finite numbers), or one of
    ``numeric`` (``np.linalg.LinAlgError``), is refused in one line too,
    ``meaning`` saying what it means for the input, never shown as
    warnings and figures of inf or nan.
    """
    with warnings.catch_warnings():
        warnings.simplefilter('error', RuntimeWarning)
        try:
            yield
        except refusals as error:
            raise CliError(str(error)) from None
        except (RuntimeWarning, *numeric) as warning:
            raise CliError(f'{source}: the computation left the finite '
                           f'numbers ({warning}): {meaning}') from None


def option_flag(option):
    """Return the command-line spelling of the option ``dest``."""
    return '--' + option.replace('_', '-')


def read_params(path):
    """Return the ``--params`` file read once, or None without one."""
    return None if path is None else ParametersFile.read(path)


def robot_of(parameters):
    """
    Return the robot of the ``--params`` file (the paper's without one).

    A bad ``robot.*`` value is refused naming the file and the parameter.
    """
    if parameters is None:
        return Robot()
    try:
        return parameters.robot()
    except ParameterError as error:
        raise CliError(f'{parameters.path}: {error}') from None


def params_joint_names(parameters):
    """
    Return the ``feedforward`` section's ``joint_names`` of ``--params``.

    Checked as the nodes check them; the defaults (JOINT_NAMES) without a
    file or without the key.
    """
    if parameters is None:
        return JOINT_NAMES
    names = parameters.section().get('joint_names', list(JOINT_NAMES))
    try:
        return joint_names(names)
    except ValueError as error:
        raise CliError(f'{parameters.path}: joint_names: {error}') from None


def option_joint_names(args):
    """Return ``--joint-names`` checked as the nodes check them."""
    try:
        return joint_names(args.joint_names)
    except ValueError as error:
        raise CliError(f'--joint-names: {error}') from None


def check_output(path, option):
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
        raise CliError(f'{option_flag(option)} {path}: is a directory')
    directory = os.path.dirname(target)
    if not os.path.isdir(directory):
        raise CliError(f'{option_flag(option)} {path}: no such directory: '
                       f'{directory}')
    if not os.path.exists(target) and not os.access(directory, os.W_OK):
        raise CliError(f'{option_flag(option)} {path}: cannot write in {directory}')


def check_distinct(args):
    """
    Refuse an output that is the same file as an input or another output.

    The options of INPUT_OPTIONS and OUTPUT_OPTIONS that ``args`` has, before
    anything is read or written. The same file: symbolic links resolved,
    the same inode (:func:`os.path.samestat`, so hard links too) where both
    exist, the same resolved path otherwise; ``-`` is standard input or
    output. An output inside an input directory (a bag) is refused too. A
    character device (a terminal, ``/dev/null``) holds nothing to lose and
    may be named twice, except standard output (``-``) by two outputs.
    """
    seen = [(option, path, 0) for option in INPUT_OPTIONS
            for path in [getattr(args, option, None)] if path is not None]
    for option, path in [(o, p) for o in OUTPUT_OPTIONS
                         for p in [getattr(args, o, None)] if p is not None]:
        for other, other_path, fd in seen:
            where = _clash(path, other_path, fd)
            if where:
                why = ('an output must not replace an input' if fd == 0
                       else 'each output needs a file of its own')
                raise CliError(f'{option_flag(option)} {path}: {where} '
                               f'{option_flag(other)} {other_path}: {why}; nothing '
                               'was written')
        seen.append((option, path, 1))


def _clash(output, other, fd):
    """
    Return how ``output`` clashes with ``other`` (see check_distinct), or ''.

    ``fd``: 0 if ``other`` is an input (``-``: standard input), 1 if it is
    an output (``-``: standard output).
    """
    same, inside = 'the same file as', 'inside the directory'
    if output == other == '-':
        return same if fd == 1 else ''
    try:
        mine = os.fstat(1) if output == '-' else os.stat(output)
        theirs = os.fstat(fd) if other == '-' else os.stat(other)
    except OSError:     # one does not exist (yet): compare the paths
        if '-' in (output, other):
            return ''
        if os.path.realpath(output) == os.path.realpath(other):
            return same
        return inside if fd == 0 and os.path.isdir(other) and _inside(
            output, other) else ''
    if os.path.samestat(mine, theirs):
        return '' if stat.S_ISCHR(mine.st_mode) else same
    return inside if (fd == 0 and other != '-' and stat.S_ISDIR(
        theirs.st_mode) and _inside(output, other)) else ''


def _inside(path, directory):
    """Tell whether ``path`` resolves to a place inside ``directory``."""
    path, directory = os.path.realpath(path), os.path.realpath(directory)
    return os.path.commonpath((path, directory)) == directory


def write_output(path, data):
    """
    Write bytes, or an iterable of bytes, to ``path``; atomically if it can.

    A regular file (or a new one) is written to a temporary file renamed
    over it (os.replace); a symbolic link is followed to its target; a
    device or a FIFO is written through, as any Unix tool does, never
    replaced. Chunks (:func:`table_csv`'s) are written as they come.
    """
    chunks = (data,) if isinstance(data, bytes) else data
    if path is None or path == '-':     # bytes as given (a PNG too)
        sys.stdout.flush()
        binary = getattr(sys.stdout, 'buffer', None)
        for chunk in chunks:
            if binary is None:
                sys.stdout.write(chunk.decode('utf-8', 'replace'))
            else:
                binary.write(chunk)
        (binary or sys.stdout).flush()
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
                for chunk in chunks:
                    stream.write(chunk)
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
            for chunk in chunks:
                stream.write(chunk)
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except OSError as error:
        os.unlink(tmp)
        raise CliError(f'cannot write {path}: {error.strerror}') from None


def csv_text(times, positions, sol):
    """Format samples as CSV bytes (CSV_COLUMNS, repr); times may be None."""
    return table_csv(CSV_COLUMNS, times, np.column_stack(
        [positions] + [np.asarray(values) for values in sol[:5]]))


def table_csv(columns, times, table):
    """
    Format ``t`` and the (N, k) ``table`` as CSV (full precision, repr).

    Yields the bytes in chunks of CSV_CHUNK_ROWS rows, for
    :func:`write_output`: the text of a large table is never held whole.
    ``times`` may be None (an empty ``t`` cell).
    """
    yield (','.join(columns) + '\n').encode('utf-8')
    times = None if times is None else np.asarray(times, dtype=float)
    for start in range(0, len(table), CSV_CHUNK_ROWS):
        rows = table[start:start + CSV_CHUNK_ROWS].tolist()
        t_cells = [''] * len(rows) if times is None else map(
            repr, times[start:start + CSV_CHUNK_ROWS].tolist())
        yield ''.join(t + ',' + ','.join(map(repr, row)) + '\n'
                      for t, row in zip(t_cells, rows)).encode('utf-8')


def new_figure(size, option):
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


def png_bytes(figure):
    """Return ``figure`` as PNG bytes."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format='png', dpi=100)
    return buffer.getvalue()


def drawn_png(draw, size, option):
    """Return the PNG bytes of ``draw(figure)`` on a new figure."""
    figure = new_figure(size, option)
    draw(figure)
    return png_bytes(figure)


def read_trajectory(path):
    """
    Read ``t,x,y,z,vx,...`` by header name: ``(name, t, p, v, a, lines)``.

    ``name`` the file's (``<stdin>`` for ``-``); ``t`` None if the file
    has no ``t`` column; a missing velocity or acceleration group None
    (zero); ``lines`` each row's line number.
    """
    name = '<stdin>' if path == '-' else path
    try:
        values, lines = read_columns(path, INPUT_GROUPS, name)
    except CsvError as error:
        raise CliError(str(error)) from None
    times = values['time']
    return (name, None if times is None else times[:, 0],
            values['position'], values['velocity'], values['acceleration'],
            lines)


def solve_trajectory(robot, where, times, lines, p, v, a):
    """
    Return the solution of every sample, or refuse the one out of reach.

    The refusal names ``where`` and the sample: its data row and line
    when ``lines`` are given (a file), else its time.
    """
    try:
        return mechanics.solve_batch(robot, p, v, a)
    except mechanics.WorkspaceError as error:
        k = error.row
        at = (f' at t = {times[k]:.6g} s' if lines is None
              else f': data row {k + 1} (line {lines[k]})')
        raise CliError(f'{where}{at}: {error.detail}') from None


def joint_trajectory_yaml(nanoseconds, sol, names):
    """
    Format a trajectory_msgs/JointTrajectory as YAML (chunks of bytes).

    The message as ``ros2 topic pub`` and launch files read it: a zero
    header stamp (joint_trajectory_controller starts it on arrival),
    ``names``, one point per row with positions = lambda (m), velocities =
    lambdadot (m/s), accelerations = lambdaddot (m/s^2), effort = f (N)
    and time_from_start = ``nanoseconds`` (int64). Doubles in full
    precision. Yields CSV_CHUNK_ROWS points at a time, for
    :func:`write_output`: the text is never held whole.
    """
    def row(values):
        return '[' + ', '.join(map(repr, values)) + ']'
    yield ('\n'.join(['header:', '  stamp:', '    sec: 0', '    nanosec: 0',
                      "  frame_id: ''", 'joint_names: ['
                      + ', '.join(map(json.dumps, names)) + ']', 'points:'])
           + '\n').encode('utf-8')
    for start in range(0, len(nanoseconds), CSV_CHUNK_ROWS):
        part = slice(start, start + CSV_CHUNK_ROWS)
        out = []
        for ns, lam, rate, acc, force in zip(
                nanoseconds[part].tolist(), sol.lambda_[part].tolist(),
                sol.lambdadot[part].tolist(), sol.lambdaddot[part].tolist(),
                sol.force[part].tolist()):
            sec, nanosec = divmod(int(ns), 10**9)
            out += [f'- positions: {row(lam)}', f'  velocities: {row(rate)}',
                    f'  accelerations: {row(acc)}', f'  effort: {row(force)}',
                    '  time_from_start:', f'    sec: {sec}',
                    f'    nanosec: {nanosec}']
        yield ('\n'.join(out) + '\n').encode('utf-8')


def table_row(label, *values):
    cells = [v if isinstance(v, str) else f'{float(v):.6g}' for v in values]
    return f'{label:<26}' + ''.join(f'{c:>14}' for c in cells)


def print_error(message):
    print(f'{PROG}: error: {" ".join(message.split())}', file=sys.stderr)


def within(kind, low, high=math.inf, above=False, unit=''):
    """
    Return an argparse type: a finite ``kind`` (int or float) in range.

    ``[low, high]``, or above ``low`` when ``above``; ``unit`` ends the
    message of a refusal.
    """
    noun = 'an integer' if kind is int else 'a finite number'
    span = (f'above {low:g}' if above else f'in [{low:g}, {high:g}]'
            if high < math.inf else f'of at least {low:g}'
            if low > -math.inf else '')

    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value <= high
                and (value > low if above else value >= low)):
            raise argparse.ArgumentTypeError(
                f'must be {" ".join(filter(None, (noun, span)))}{unit}, '
                f'got {text!r}')
        return value
    return parse


def robot_range(name):
    """
    Return the argparse type of an option that sets robot parameter ``name``.

    A finite number within the parameter's own (closed) limits, in its
    unit (:data:`robot.ROW`, the one home of both): what a ``--params``
    file accepts for it.
    """
    row = ROW[name]
    return within(float, *row.limits, unit=f' {row.unit}')


positive_float = within(float, 0.0, above=True)
non_negative_float = within(float, 0.0)
finite_float = within(float, -math.inf)
count = within(int, 0)
positive_count = within(int, 1)


class Subcommand(namedtuple('Subcommand',
                            'name run add help description robot',
                            defaults=(True,))):
    """
    One subcommand: a row of its module's ``SUBCOMMANDS`` table.

    ``run(robot, args)`` does the work; ``add(parser)`` adds its own
    options; ``help`` (the line in the list of commands) and
    ``description`` (its ``--help``); ``robot``: it takes ``--params``.
    """

    __slots__ = ()


def add_output(parser, what, required=False, metavar='FILE'):
    """Add ``--output``: ``what`` to write (standard output by default)."""
    parser.add_argument('--output', required=required, metavar=metavar,
                        help=what if required
                        else f'{what} (default: standard output)')


def add_joint_names(parser, what):
    """Add ``--joint-names``: the names of ``what`` of actuators A, B, C."""
    parser.add_argument('--joint-names', nargs=3, metavar=('A', 'B', 'C'),
                        default=list(JOINT_NAMES), help=f'names of {what} '
                        'of actuators A, B, C (default: '
                        + ' '.join(JOINT_NAMES) + ')')


def add_position(parser, required=True, note=''):
    """Add ``--position``: the platform centre (m)."""
    parser.add_argument('--position', type=float, nargs=3, required=required,
                        metavar=('X', 'Y', 'Z'), help='platform centre in '
                        f'the base frame (m{note})')


def add_size(parser, default, kind):
    """Add ``--size``: a picture's width and height (``kind`` pixels)."""
    parser.add_argument('--size', type=kind, nargs=2, default=default,
                        metavar=('WIDTH', 'HEIGHT'), help='image size in '
                        'pixels (default {} {})'.format(*default))
