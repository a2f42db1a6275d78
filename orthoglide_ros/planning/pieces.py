"""
The pieces of a path: helices (lines and arcs) and Bezier curves.

A piece is one smooth part of the path, parametrised by its arc length
``w`` from 0 to its ``length`` (m), one of two tagged types:

- a :class:`HelixPiece` (a line, an exact arc or a helix, a line blend):
  one formula serves them all, a line being a helix of radius zero;
- a :class:`BezierPiece` (a G5 spline, a corner blend, a fitted run of
  chords): cubic Bezier spans, each followed by its arc length
  (:mod:`bezier`), so that ``|dp/dw|`` is 1 everywhere.

:data:`Piece` is either. :func:`line_piece`, :func:`bezier_piece` and
:func:`move_piece` (a program's :mod:`moves`) make them; :mod:`path`
chains them and decides their junctions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import ClassVar, Optional, Sequence, Union

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import bezier
from orthoglide_ros.planning.moves import Line, Move, Spline

# A Bezier span whose speed varies more (its least over its largest
# below this) is halved, at most SPLIT_DEPTH times, so that its arc
# length is exact to rounding.
EVEN_SPEED = 0.7
SPLIT_DEPTH = 10
_AXES = np.eye(3)
# A Bezier piece's row in the helix columns of :func:`columns`.
_NOT_A_HELIX = (np.zeros(3), np.zeros(3), np.zeros(3), 0.0, 1.0, 0.0)


@dataclass(frozen=True)
class _Piece:
    """
    What every piece has: its ``length`` (m), ``line``, ``feed``, ``lines``.

    ``line``: the program's line (from 1); ``feed``: G's speed cap (m/s);
    ``lines``: ``(k, 2)``, where each of the moves a straight run or a
    fitted run is made of starts (``w``, its line), None for one move.
    """

    length: float
    line: int
    feed: float
    lines: Optional[Array] = field(default=None, kw_only=True)

    def line_at(self, w: float) -> int:
        """Return the program's line of the point at ``w``."""
        if self.lines is None:
            return self.line
        k = int(np.searchsorted(self.lines[:, 0], w, side='right')) - 1
        return int(self.lines[max(k, 0), 1])

    def _lines_within(self, a, b):
        """Return ``lines`` from ``w = a`` to ``b``, from 0 at ``a``."""
        if self.lines is None:
            return None
        keep = self.lines[:, 0] < b
        part = self.lines[keep].copy()
        part[:, 0] = np.maximum(part[:, 0] - a, 0.0)
        return part


@dataclass(frozen=True)
class HelixPiece(_Piece):
    """
    A helix: a line, an exact arc or helix, a blend between two lines.

    ``p(phi) = origin + radius ((cos phi - 1) e1 + sin phi e2) + rise (phi
    / angle) e3`` with ``e2 = e3 x e1``, ``phi = angle w / length`` for
    ``w`` in [0, length] (``e1`` points from the axis to the start); a
    line has radius 0, angle 1, rise its length and e3 its direction.
    """

    origin: Array
    e1: Array
    e3: Array
    radius: float
    angle: float
    rise: float

    kind: ClassVar[str] = 'helix'

    def evaluate(self, w: Array) -> tuple[Array, Array, Array]:
        """Return ``p``, ``dp/dw``, ``d2p/dw2`` at ``w`` ((n,) m): (n, 3)."""
        return helix_values(self.origin[None], self.e1[None],
                            self.e3[None], self.radius, self.angle,
                            self.rise, self.length,
                            np.asarray(w, dtype=float))

    def point(self, w: float) -> Array:
        """Return ``p(w)`` (3,): the helix formula on one point."""
        phi = self.angle * w / self.length
        half = math.sin(0.5 * phi)
        return self.origin + self.radius * (
            -2.0 * half * half * self.e1 + math.sin(phi) * _cross3(
                self.e3, self.e1)) + (self.rise * w / self.length) * self.e3

    def tangent(self, w: float) -> Array:
        """Return the unit tangent at ``w`` (3,)."""
        if self.radius == 0.0:
            return self.e3
        phi = self.angle * w / self.length
        d1 = (self.angle * self.radius / self.length) * (
            math.cos(phi) * _cross3(self.e3, self.e1)
            - math.sin(phi) * self.e1) + (self.rise / self.length) * self.e3
        return d1 / math.sqrt(float(d1 @ d1))

    def room(self, start: bool) -> float:
        """Return how much a blend may trim at its start (or end): half, m."""
        return 0.5 * self.length

    def sub(self, a: float, b: float) -> HelixPiece:
        """Return the part from ``w = a`` to ``b``, as a piece."""
        phi = self.angle * a / self.length
        e2 = _cross3(self.e3, self.e1)
        return HelixPiece(b - a, self.line_at(a), self.feed, self.point(a),
                          math.cos(phi) * self.e1 + math.sin(phi) * e2,
                          self.e3, self.radius,
                          self.angle * (b - a) / self.length,
                          self.rise * (b - a) / self.length,
                          lines=self._lines_within(a, b))


@dataclass(frozen=True)
class BezierPiece(_Piece):
    """
    Cubic Bezier spans, each followed by its arc length.

    ``control``: the spans' control points (m, 4, 3); ``table``: each
    span's arc length table (:func:`bezier.tables`); ``starts`` (m + 1,):
    where each span starts along the piece, its length last; ``turning``:
    the total turning of its tangent (rad).
    """

    control: Array
    table: Array
    starts: Array
    turning: float

    kind: ClassVar[str] = 'bezier'

    def evaluate(self, w: Array) -> tuple[Array, Array, Array]:
        """Return ``p``, ``dp/dw``, ``d2p/dw2`` at ``w`` ((n,) m): (n, 3)."""
        w = np.asarray(w, dtype=float)
        j = self._span(w)
        return bezier.by_length(self.control[j], self.table[j],
                                w - self.starts[j])

    def _span(self, w):
        """Return the span of each ``w``."""
        return np.clip(np.searchsorted(self.starts, w, side='right') - 1, 0,
                       len(self.control) - 1)

    def point(self, w: float) -> Array:
        """Return ``p(w)`` (3,)."""
        return self.evaluate(np.array([w]))[0][0]

    def tangent(self, w: float) -> Array:
        """Return the unit tangent at ``w`` (3,)."""
        d1 = self.evaluate(np.array([w]))[1][0]
        return d1 / math.sqrt(float(d1 @ d1))

    def room(self, start: bool) -> float:
        """
        Return how much a blend may trim at the piece's start (or end), m.

        Half the piece; of a fitted run (several moves), half its first
        (last) span: a blend takes no programmed point but the corner's.
        """
        if self.lines is not None:
            spans = np.diff(self.starts)
            return 0.5 * float(spans[0] if start else spans[-1])
        return 0.5 * self.length

    def sub(self, a: float, b: float) -> BezierPiece:
        """Return the part from ``w = a`` to ``b``, as a piece."""
        first = int(self._span(np.array([a]))[0])
        last = int(np.clip(np.searchsorted(self.starts, b) - 1, first,
                           len(self.control) - 1))
        taus = bezier.parameter(
            self.control[[first, last]], self.table[[first, last]],
            np.array([a, b]) - self.starts[[first, last]])
        control = self.control[first:last + 1].copy()
        if first == last:
            control[0] = bezier.part(control[:1], taus[:1], taus[1:])[0]
        else:
            control[0] = bezier.part(control[:1], taus[:1], np.ones(1))[0]
            control[-1] = bezier.part(control[-1:], np.zeros(1), taus[1:])[0]
        return bezier_piece(control, self.line_at(a), self.feed,
                            self._lines_within(a, b))


# Any piece: the path tells them apart by their type.
Piece = Union[HelixPiece, BezierPiece]
# One value, or one per point.
Scalars = Union[float, Array]


def cross(a: Array, b: Array) -> Array:
    """Return ``a x b`` of (..., 3) arrays (np.cross is slow on small ones)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2,
                     a0 * b1 - a1 * b0), -1)


def _cross3(a, b):
    """Return ``a x b`` of two (3,) arrays, in Python floats (fast)."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2,
                     a0 * b1 - a1 * b0))


def helix_values(origin: Array, e1: Array, e3: Array, radius: Scalars,
                 angle: Scalars, rise: Scalars, length: Scalars, w: Array
                 ) -> tuple[Array, Array, Array]:
    """
    Evaluate the helix formula on arrays: ``p``, ``dp/dw``, ``d2p/dw2``.

    ``origin``, ``e1``, ``e3`` (n, 3) or (1, 3); ``radius``, ``angle``,
    ``rise``, ``length`` (n,) or floats; ``w`` (n,). ``cos phi - 1 = -2
    sin^2(phi / 2)``: the offset from the start keeps its precision
    whatever the radius.
    """
    e2 = cross(e3, e1)
    k = angle / length
    phi = k * w
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    half = np.sin(0.5 * phi)[:, None]
    radius = np.reshape(radius, (-1, 1))
    k = np.reshape(k, (-1, 1))
    p = origin + radius * (-2.0 * half * half * e1 + s * e2) + np.reshape(
        rise / length, (-1, 1)) * w[:, None] * e3
    d1 = k * radius * (c * e2 - s * e1) + np.reshape(rise / length,
                                                     (-1, 1)) * e3
    d2 = -k * k * radius * (c * e1 + s * e2)
    return p, d1, d2


def line_piece(start: Array, end: Array, line: int, feed: float,
               lines: Optional[Array] = None) -> HelixPiece:
    """Return the straight piece from ``start`` to ``end`` (m)."""
    start = np.asarray(start, dtype=float)
    delta = np.asarray(end, dtype=float) - start
    length = math.sqrt(float(delta @ delta))
    e3 = delta / length
    e1 = _cross3(e3, _AXES[int(np.argmin(np.abs(e3)))])
    return HelixPiece(length, line, feed, start,
                      e1 / math.sqrt(float(e1 @ e1)), e3, 0.0, 1.0, length,
                      lines=lines)


def bezier_piece(control: Array, line: int, feed: float,
                 lines: Optional[Array] = None) -> BezierPiece:
    """
    Return the piece of Bezier spans ``control`` ((m, 4, 3) or (4, 3), m).

    A span whose speed varies by more than EVEN_SPEED is halved (de
    Casteljau), at most SPLIT_DEPTH times: the same curve, its arc length
    exact to rounding on each part.
    """
    control = np.asarray(control, dtype=float).reshape(-1, 4, 3)
    for _ in range(SPLIT_DEPTH):
        least, most = bezier.least_speed(control)
        uneven = least < EVEN_SPEED * most
        if not uneven.any():
            break
        left, right = bezier.split(control[uneven], np.full(
            int(uneven.sum()), 0.5))
        spans = np.empty((len(control) + len(left), 4, 3))
        at = np.flatnonzero(uneven) + np.arange(len(left))
        spans[at], spans[at + 1] = left, right
        keep = np.ones(len(spans), dtype=bool)
        keep[at] = keep[at + 1] = False
        spans[keep] = control[~uneven]
        control = spans
    table = bezier.tables(control)
    starts = np.concatenate(([0.0], np.cumsum(table[:, -1])))
    return BezierPiece(float(starts[-1]), line, feed, control, table, starts,
                       float(bezier.turning(control).sum()), lines=lines)


def move_piece(move: Move) -> Piece:
    """Return a program move as a piece (a line, an arc, a helix, a spline)."""
    if isinstance(move, Line):
        return line_piece(move.start, move.end, move.line, move.feed)
    if isinstance(move, Spline):
        return bezier_piece(move.control, move.line, move.feed)
    e3 = move.normal
    offset = move.start - move.centre
    offset = offset - e3 * float(offset @ e3)
    radius = float(np.linalg.norm(offset))
    length = math.hypot(radius * move.angle, move.rise)
    return HelixPiece(length, move.line, move.feed, move.start.copy(),
                      offset / radius, e3, radius, move.angle, move.rise)


def columns(pieces: Sequence[Piece]) -> dict[str, Array]:
    """
    Return the fields of ``pieces`` as arrays, for vectorised evaluation.

    ``helix`` (bool), ``origin``, ``e1``, ``e3`` (n, 3), ``radius``,
    ``angle``, ``rise``, ``length``, ``turning``, ``spans`` (n,), and the
    spans of the Bezier pieces, in order: ``control`` (S, 4, 3),
    ``tables`` (S, SUBSPANS + 1), ``span_start`` (S,) along its piece
    and ``span_s`` along the path, ``span_turning`` (S,) rad,
    ``span_first`` (n + 1,) each piece's first, ``piece_s`` (n,) where
    each piece starts along the path. A Bezier piece's row in the helix
    columns is _NOT_A_HELIX (never read), a helix's turning 0.
    """
    curves = [p for p in pieces if isinstance(p, BezierPiece)]
    spans = np.array([len(p.control) if isinstance(p, BezierPiece) else 0
                      for p in pieces], dtype=np.int64)
    helices = [(p.origin, p.e1, p.e3, p.radius, p.angle, p.rise)
               if isinstance(p, HelixPiece) else _NOT_A_HELIX
               for p in pieces]
    lengths = np.array([p.length for p in pieces])
    piece_s = np.concatenate(([0.0], np.cumsum(lengths)[:-1]))
    span_start = np.concatenate([p.starts[:-1] for p in curves]
                                or [np.zeros(0)])
    control = np.concatenate([p.control for p in curves]
                             or [np.zeros((0, 4, 3))])
    return {
        'helix': np.array([isinstance(p, HelixPiece) for p in pieces]),
        **{name: np.array([h[k] for h in helices]) for k, name in enumerate(
            ('origin', 'e1', 'e3', 'radius', 'angle', 'rise'))},
        'length': lengths,
        'turning': np.array([p.turning if isinstance(p, BezierPiece)
                             else 0.0 for p in pieces]),
        'spans': spans,
        'control': control,
        'tables': np.concatenate([p.table for p in curves]
                                 or [np.zeros((0, bezier.SUBSPANS + 1))]),
        'span_start': span_start,
        'span_turning': bezier.turning(control),
        'span_s': np.repeat(piece_s, spans) + span_start,
        'span_first': np.concatenate(([0], np.cumsum(spans))),
        'piece_s': piece_s}
