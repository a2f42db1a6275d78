"""
What the ``orthoglide`` subcommands share: errors, columns, outputs, types.

- :class:`CliError`: bad input, printed as one line and exit code 2;
- the columns the tool writes and the trajectory files it reads;
- :func:`check_output` and :func:`write_output`: output files checked
  before anything is computed, written atomically once all is;
- argparse types of finite numbers in range (:func:`within`), and the
  options several subcommands take (:func:`command`, :func:`add_output`,
  :func:`add_joint_names`, :func:`add_position`, :func:`add_size`);
- the CSV and PNG writers and the trajectory reader of several
  subcommands.
"""

import argparse
import io
import math
import os
import stat
import sys
import tempfile

import numpy as np

from orthoglide_ros.formats.csvfile import CsvError, read_columns
from orthoglide_ros.model.robot import JOINT_NAMES, LEGS

PROG = 'orthoglide'
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


class CliError(Exception):
    """Bad input: printed as one line ``orthoglide: error: ...``."""

    def __init__(self, message, code=2):
        """Keep ``message`` and the exit ``code``."""
        super().__init__(message)
        self.code = code


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
        raise CliError(f'--{option} {path}: is a directory')
    directory = os.path.dirname(target)
    if not os.path.isdir(directory):
        raise CliError(f'--{option} {path}: no such directory: {directory}')
    if not os.path.exists(target) and not os.access(directory, os.W_OK):
        raise CliError(f'--{option} {path}: cannot write in {directory}')


def write_output(path, data):
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


def csv_text(times, positions, sol):
    """Format samples as CSV bytes (CSV_COLUMNS, repr); times may be None."""
    return table_csv(CSV_COLUMNS, times, np.column_stack(
        [positions] + [np.asarray(values) for values in sol[:5]]))


def table_csv(columns, times, table):
    """Format ``t`` and the (N, k) ``table`` as CSV bytes (full precision)."""
    out = [','.join(columns)]
    t_cells = [''] * len(table) if times is None else map(
        repr, np.asarray(times, dtype=float).tolist())
    for t, row in zip(t_cells, table.tolist()):
        out.append(t + ',' + ','.join(map(repr, row)))
    return ('\n'.join(out) + '\n').encode('utf-8')


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


def read_trajectory(path, name):
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


def workspace_reason(error):
    """Return a WorkspaceError's message less its 0-based sample prefix."""
    message = str(error)
    if error.row is not None:
        message = message.removeprefix(f'sample {error.row}: ')
    return message


def table_row(label, *values):
    cells = [v if isinstance(v, str) else f'{float(v):.6g}' for v in values]
    return f'{label:<26}' + ''.join(f'{c:>14}' for c in cells)


def fail(message):
    print(f'{PROG}: error: {" ".join(message.split())}', file=sys.stderr)


def within(kind, low, high=math.inf, above=False, unit=''):
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


positive_float = within(float, 0.0, above=True)
non_negative_float = within(float, 0.0)
finite_float = within(float, -math.inf)
count = within(int, 0)
positive_count = within(int, 1)


def command(sub, parents, name, run, help, description):
    """Add subcommand ``name``, run by ``run``, with ``parents``' options."""
    parser = sub.add_parser(name, parents=parents, help=help,
                            description=description)
    parser.set_defaults(run=run)
    return parser


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
