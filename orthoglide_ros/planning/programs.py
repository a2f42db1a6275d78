"""
Read a program file into a path: G-code, or CSV waypoints.

:func:`read_program` tells them apart by their first line that holds
anything: a CSV file's header names its columns ``x,y,z`` (and,
optionally, ``feed``), which no G-code line is. Waypoints are in
m, feeds in m/s (a row's feed caps the segment that ends there); G-code as
:mod:`orthoglide_ros.planning.gcode` reads it. Either starts at ``start``
(m): the first move goes from there to the program's first point.
"""

from __future__ import annotations

import contextlib
import io
import math
import sys
from typing import Optional, Sequence

import numpy as np

from orthoglide_ros.formats.csvfile import CsvError, read_columns
from orthoglide_ros.formats.text import read_text
from orthoglide_ros.model.types import Path as FilePath
from orthoglide_ros.planning.gcode import read_gcode
from orthoglide_ros.planning.gcode_words import lines_of
from orthoglide_ros.planning.moves import EMPTY, ProgramError
from orthoglide_ros.planning.path import from_moves, from_waypoints, Path

# Largest program read (bytes).
MAX_PROGRAM_BYTES = 32 * 1024 * 1024
WAYPOINT_GROUPS = (('position', ('x', 'y', 'z'), True),
                   ('feed', ('feed',), False))
_NAME = '<program>'


def read_program(path: FilePath, start: Sequence[float], tolerance: float,
                 max_pieces: Optional[int] = None) -> Path:
    """
    Return the path of the program file ``path`` (``-``: standard input).

    ``tolerance`` (m): the blends' of waypoints and of G64 without P;
    ``max_pieces``: the most pieces the path may have. Raises
    :class:`ProgramError` (``line N`` where a line is to blame; a program
    that moves nothing: "zero-length program", EMPTY; one of more pieces:
    TOO_LARGE).
    """
    text = _read_text(path)
    first = next((line for line in lines_of(text) if line.strip()), '')
    cells = {c.strip().lower() for c in first.split(',')}
    if {'x', 'y', 'z'} <= cells:
        points, feeds, lines = _waypoints(text)
        origin = np.asarray(start, dtype=float)[None]
        return from_waypoints(np.vstack((origin, points)),
                              None if feeds is None
                              else np.r_[math.inf, feeds],
                              [0, *lines], tolerance, max_pieces)
    return from_moves(read_gcode(text, start), tolerance,
                      max_pieces=max_pieces)


def _read_text(path):
    try:
        return read_text(sys.stdin.buffer if path == '-' else path,
                         MAX_PROGRAM_BYTES)
    except ValueError as error:
        raise ProgramError(None, str(error)) from None


def _waypoints(text):
    """Return the waypoints (n, 3), feeds (n,) or None and their lines."""
    try:
        with _stdin(io.StringIO(text, newline='')):
            values, lines = read_columns('-', WAYPOINT_GROUPS, _NAME)
    except CsvError as error:
        raise ProgramError(None, error.detail) from None
    points = values['position']
    if len(points) == 0:
        raise ProgramError(None, 'zero-length program: no waypoint', EMPTY)
    feeds = values['feed']
    if feeds is not None:
        feeds = feeds[:, 0]
        bad = feeds <= 0.0
        if bad.any():
            k = int(np.argmax(bad))
            raise ProgramError(lines[k], f'feed {feeds[k]:g} m/s: must be '
                               'above 0')
    return points, feeds, list(lines)


@contextlib.contextmanager
def _stdin(stream):
    """Read ``stream`` as standard input within the block."""
    saved = sys.stdin
    sys.stdin = stream
    try:
        yield
    finally:
        sys.stdin = saved
