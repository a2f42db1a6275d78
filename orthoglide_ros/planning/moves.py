"""
Planning's base: the moves a path is made of, and the refusal of a program.

A program, whichever its form, is a list of moves of G in the base frame
(m, m/s): :mod:`gcode` turns G-code into them, :func:`path.from_waypoints`
CSV waypoints and a nav_msgs/Path; :mod:`path` makes a path of them. A move
is one of three tagged types, each with its own geometry and nothing
optional: a :class:`Line`, an :class:`Arc` (an exact arc or helix) and a
:class:`Spline` (a cubic Bezier); :data:`Move` is any of them. Each has
the common fields of :class:`_Move` and its kind (``'line'``, ``'arc'``,
``'spline'``) as a class constant.

A program the planner refuses raises :class:`ProgramError`, its reason a
field (EMPTY, TOO_LARGE, INVALID) for callers that react to it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Optional, Union

from orthoglide_ros.model.types import Array

# Largest magnitude of any number (a word's, in program units; a waypoint's
# and a limit's): far beyond any machine, it keeps every square finite.
NUMBER_BOUND = 1e9
# A move shorter than this (m) moves nothing and is dropped.
ZERO_LENGTH = 1e-12

# The path control modes of a move's end.
EXACT_STOP = 'exact_stop'       # G61.1
EXACT_PATH = 'exact_path'       # G61
BLEND = 'blend'                 # G64

# Where a refusal comes from, for callers that react to it (the node's
# reasons): a program that moves nothing, one larger than a bound of the
# planner, any other.
EMPTY = 'empty'
TOO_LARGE = 'too_large'
INVALID = 'invalid'


class ProgramError(ValueError):
    """
    A program the planner refuses: the message names the line (``line N``).

    ``line``: the program's line (from 1), None where no line is to blame;
    ``detail``: the message without it; ``reason``: EMPTY, TOO_LARGE,
    INVALID (or a subclass's), for callers that react to it.
    """

    reason = INVALID

    def __init__(self, line: Optional[int], message: str,
                 reason: Optional[str] = None) -> None:
        """Keep ``line`` (from 1, or None), the message without it, why."""
        super().__init__(message if line is None
                         else f'line {line}: {message}')
        self.line = line
        self.detail = message
        if reason is not None:
            self.reason = reason


@dataclass(frozen=True)
class _Move:
    """
    What every move has, in the base frame (m, m/s).

    ``start``, ``end``: (3,) arrays of G (m); ``line``: the program's line
    (from 1); ``feed``: the speed cap of G (m/s; ``math.inf`` for G0 and
    for waypoints without one); ``mode``: the path control at its end
    (EXACT_STOP, EXACT_PATH, BLEND) and ``tolerance``: a blend's (m; None:
    the planner's).
    """

    start: Array
    end: Array
    line: int
    feed: float
    mode: str
    tolerance: Optional[float]


@dataclass(frozen=True)
class Line(_Move):
    """A straight move (G0, G1, a segment between waypoints)."""

    kind: ClassVar[str] = 'line'


@dataclass(frozen=True)
class Arc(_Move):
    """
    An exact arc or helix (G2, G3).

    ``centre`` (m, on the start's level along the normal), ``normal`` (the
    plane's unit normal e3), ``angle`` (rad, signed about ``normal``: a
    full turn is 2 pi) and ``rise`` (m along ``normal``, a helix's).
    """

    centre: Array
    normal: Array
    angle: float
    rise: float

    kind: ClassVar[str] = 'arc'


@dataclass(frozen=True)
class Spline(_Move):
    """A cubic Bezier (G5, G5.1 raised): its ``control`` points (4, 3), m."""

    control: Array

    kind: ClassVar[str] = 'spline'


# Any move: the path tells them apart by their type.
Move = Union[Line, Arc, Spline]
