"""
The measurements a calibration reads: joint readings and the platform centre.

A CSV file with the header ``lambda_a,lambda_b,lambda_c,x,y,z`` (m, any
order, more columns ignored), one row per measurement: the joint readings
and the platform centre G an instrument measured; an empty ``x``, ``y`` or
``z`` cell is a coordinate not measured (a dial gauge reads one).
:func:`read` reads it within MAX_MEASUREMENTS rows and refuses, naming the
line and the column, a cell that is not a finite number, a missing
column, a row that measures nothing and joint readings that put the
nominal robot's platform outside its workspace; :func:`repeats` finds the
rows that repeat another exactly (counted twice, and said)
(doc/calibration.md#what-to-measure-and-how).
"""

from __future__ import annotations

from collections import namedtuple
from typing import TYPE_CHECKING

import numpy as np

from orthoglide_ros.formats.csvfile import CsvError, read_columns
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.types import Path

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

JOINTS = ('lambda_a', 'lambda_b', 'lambda_c')
COORDINATES = ('x', 'y', 'z')
COLUMNS = JOINTS + COORDINATES
# Most measurements a file may hold: a campaign is tens to hundreds of
# positions; the least squares then holds 10,000 x 3 x 36 doubles (9 MB)
# and takes about a minute.
MAX_MEASUREMENTS = 10_000

Measurements = namedtuple('Measurements', ('lambdas', 'readings', 'lines',
                                           'source'))
Measurements.__doc__ = """What :func:`read` read.

``lambdas`` (N, 3): the joint readings (m, A, B, C); ``readings`` (N, 3):
the platform centre's x, y, z (m), NaN where not measured; ``lines``: each
row's line in the file; ``source``: the file's name.
"""


class MeasurementError(ValueError):
    """Measurements that cannot be used; the message names line and column."""


def read(path: Path, robot: Robot,
         margin: float = mechanics.DEFAULT_SINGULARITY_MARGIN
         ) -> Measurements:
    """
    Read and check a measurements file (``-``: standard input).

    ``robot``: the nominal robot, whose workspace the joint readings must
    lie in: a platform position on the home branch at least ``margin``
    from every singularity (the machine's own limit: its feedforward
    never commands beyond it). Raises :class:`MeasurementError`.
    """
    name = '<stdin>' if path == '-' else str(path)
    try:
        values, lines = read_columns(
            path, (('joint readings', JOINTS, True),
                   ('platform position', COORDINATES, True)), name,
            blank=COORDINATES, max_rows=MAX_MEASUREMENTS)
    except CsvError as error:
        raise MeasurementError(str(error)) from None
    data = Measurements(values['joint readings'],
                        values['platform position'], lines, name)
    if not len(lines):
        raise MeasurementError(f'{name}: no measurement (a header and no '
                               'row)')
    _check_rows(data)
    _check_workspace(data, robot, margin)
    return data


def where(data: Measurements, row: int, column: str) -> str:
    """Return ``file: line N, column 'x'`` of a data row."""
    return f'{data.source}: line {data.lines[row]}, column {column!r}'


def repeats(data: Measurements) -> list[tuple[int, int]]:
    """
    Return ``(row, earlier row)`` for each row that repeats another exactly.

    Every cell alike, the empty ones too: a quantised instrument reading a
    position again, or a row pasted twice; either counts twice.
    """
    table = np.column_stack((data.lambdas, np.nan_to_num(
        data.readings, nan=np.inf)))
    _, first, inverse = np.unique(table, axis=0, return_index=True,
                                  return_inverse=True)
    earliest = first[inverse.ravel()]
    return [(int(row), int(earliest[row])) for row in np.flatnonzero(
        earliest != np.arange(len(table)))]


def _check_rows(data):
    """Refuse a row that measures nothing."""
    empty = np.isnan(data.readings).all(1)
    if empty.any():
        row = int(np.argmax(empty))
        raise MeasurementError(
            f'{data.source}: line {data.lines[row]}, columns x, y, z: no '
            'coordinate measured (an empty cell is one not measured; each '
            'row needs one at least)')


def _check_workspace(data, robot, margin):
    """
    Refuse joint readings outside the nominal robot's workspace.

    Named by the column of the leg nearest its singularity (J1), or of
    the reading farthest from home where no platform position exists or
    J2 is the nearer.
    """
    position, found = mechanics.forward_kinematics_rows(robot, data.lambdas)
    position = np.where(found[:, None], position, 0.0)
    status = mechanics.workspace_status(robot, position, margin)
    bad = ~found | ~status.ok
    if not bad.any():
        return
    row = int(np.argmax(bad))
    lam = data.lambdas[row]
    readings = ', '.join(f'{v:.6g}' for v in lam)
    if not found[row]:
        column = JOINTS[int(np.argmax(np.abs(lam)))]
        raise MeasurementError(
            f'{where(data, row, column)}: the joint readings [{readings}] m '
            'give the nominal robot no platform position: outside its '
            'workspace')
    ratio = status.alpha_ratio[row]
    leg = int(np.argmin(ratio))
    if ratio[leg] < status.conditioning[row]:
        column = JOINTS[leg]
        why = f'leg {"ABC"[leg]} at alpha/L {ratio[leg]:.3g}'
    else:
        column = JOINTS[int(np.argmax(np.abs(lam)))]
        why = f'1/kappa(J_lambda) {status.conditioning[row]:.3g}'
    raise MeasurementError(
        f'{where(data, row, column)}: the joint readings [{readings}] m put '
        'the nominal robot\'s platform at '
        f'{mechanics.format_vector(position[row])} m, nearer a singularity '
        f'than the margin {margin:g} ({why}): outside the workspace the '
        'machine is driven in')
