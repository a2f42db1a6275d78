"""
The geometric path of G: lines, exact arcs and helices, corner blends.

A :class:`Path` is a chain of pieces, each parametrised by its arc length
``w`` from 0 to its length (m), with the junctions where G must stop.
:func:`from_moves` builds one from a program's moves and decides every
junction:

- a straight run (consecutive lines of one feed, each within TANGENT rad
  of the run's first direction, no exact stop between) is one line;
- a tangent junction (tangents within TANGENT rad) is passed at speed;
- an exact stop (G61.1) stops at every move's end;
- exact path (G61, the default) stops at a corner, and smooths a kink of at
  most KINK rad (CAM output rounded to the micrometre) within
  KINK_TOLERANCE: a tangent junction in all but its rounding;
- a blend (G64 P, CSV waypoints, a nav_msgs/Path) replaces the corner by
  the fastest curve within the tolerance of the programmed path: a
  circular arc tangent to two lines (trimming each by at most half its
  length; a circle sampled as a polyline becomes the circle again), a
  cubic Bezier tangent to any other pair, its distance to the programmed
  path proven within the tolerance (:func:`_proven_within`); an about-turn
  stops.

:meth:`Path.evaluate` gives ``p``, ``dp/dw`` and ``d2p/dw2`` of any points,
vectorised: one formula serves lines and helices (a line is a helix of
radius zero), written from the piece's start so that a huge radius (a
nearly straight blend) loses no precision. A Bezier is followed by its arc
length too (Newton's method on its Gauss-Legendre length), so ``|dp/dw|``
is 1 everywhere and G's velocity is continuous wherever its speed is.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field
import math
from typing import Optional, Sequence

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning.gcode import (BLEND, EMPTY, EXACT_PATH,
                                           EXACT_STOP, Move, NUMBER_BOUND,
                                           ProgramError, TOO_LARGE,
                                           ZERO_LENGTH)

# Tangents within this angle (rad) join smoothly: passed at speed.
TANGENT = 1e-9
# Exact path (G61): a kink of at most this (rad, 0.06 deg) is CAM rounding,
# smoothed within KINK_TOLERANCE (m) and passed at speed.
KINK = 1e-3
KINK_TOLERANCE = 1e-6
# A turn nearer than this to an about-turn (rad) is not blended: G stops.
ABOUT_TURN = 1e-6
# A Bezier's arc length: Gauss-Legendre of 8 points on each of
# BEZIER_SPANS equal spans of its parameter and on the part of a span up
# to a point (|B'| is smooth and above 0 there: exact to rounding).
BEZIER_SPANS = 64
_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(8)
# The proof that a Bezier blend is within its tolerance: the programmed
# path as at most PROOF_SEGMENTS chords a piece, the curve split in halves
# at most PROOF_DEPTH times into at most PROOF_CURVES parts.
PROOF_SEGMENTS = 64
PROOF_DEPTH = 16
PROOF_CURVES = 64
# A Bezier's trim is first found on its points at these parameters, then
# shortened until proven, at most PROOF_TRIES times.
_SAMPLES = np.linspace(0.0, 1.0, 33)
PROOF_TRIES = 12


@dataclass(frozen=True)
class Piece:
    """
    One smooth piece of the path: a helix (a line or an arc) or a Bezier.

    A helix: ``p(phi) = origin + radius ((cos phi - 1) e1 + sin phi e2) +
    rise (phi / angle) e3`` with ``e2 = e3 x e1``, ``phi = angle w /
    length`` for ``w`` in [0, length] (``e1`` points from the axis to the
    start); a line has radius 0, angle 1, rise its length and e3 its
    direction. A Bezier: ``control`` (4, 3) and ``table``, the arc length
    at each of BEZIER_SPANS + 1 equally spaced parameters. ``line``: the
    program's line (from 1); ``feed``: G's speed cap (m/s); ``lines``: a
    straight run's ``((w, line), ...)``, where each of its moves starts.
    """

    kind: str
    length: float
    line: int
    feed: float
    origin: Array = field(default_factory=lambda: np.zeros(3))
    e1: Array = field(default_factory=lambda: np.zeros(3))
    e3: Array = field(default_factory=lambda: np.zeros(3))
    radius: float = 0.0
    angle: float = 1.0
    rise: float = 0.0
    control: Optional[Array] = None
    table: Optional[Array] = None
    lines: Optional[tuple] = None

    def evaluate(self, w: Array) -> tuple[Array, Array, Array]:
        """Return ``p``, ``dp/dw``, ``d2p/dw2`` at ``w`` ((n,) m): (n, 3)."""
        w = np.asarray(w, dtype=float)
        if self.kind == 'bezier':
            return _bezier_by_length(self.control, self.table, w)
        return _helix(self.origin[None], self.e1[None], self.e3[None],
                      self.radius, self.angle, self.rise, self.length, w)

    def point(self, w: float) -> Array:
        """Return ``p(w)`` (3,): the helix formula on one point."""
        if self.kind == 'bezier':
            return self.evaluate(np.array([w]))[0][0]
        phi = self.angle * w / self.length
        half = math.sin(0.5 * phi)
        return self.origin + self.radius * (
            -2.0 * half * half * self.e1 + math.sin(phi) * _cross3(
                self.e3, self.e1)) + (self.rise * w / self.length) * self.e3

    def tangent(self, w: float) -> Array:
        """Return the unit tangent at ``w`` (3,)."""
        if self.kind == 'bezier':
            d1 = self.evaluate(np.array([w]))[1][0]
        elif self.radius == 0.0:
            return self.e3
        else:
            phi = self.angle * w / self.length
            d1 = (self.angle * self.radius / self.length) * (
                math.cos(phi) * _cross3(self.e3, self.e1)
                - math.sin(phi) * self.e1) + (self.rise / self.length) \
                * self.e3
        return d1 / math.sqrt(float(d1 @ d1))

    def line_at(self, w: float) -> int:
        """Return the program's line of the point at ``w``."""
        if self.lines is None:
            return self.line
        k = bisect.bisect_right([start for start, _ in self.lines], w) - 1
        return self.lines[max(k, 0)][1]

    def sub(self, a: float, b: float) -> 'Piece':
        """Return the part from ``w = a`` to ``b`` of a helix, as a piece."""
        phi = self.angle * a / self.length
        e2 = _cross3(self.e3, self.e1)
        lines = None if self.lines is None else tuple(
            (max(start - a, 0.0), line) for start, line in self.lines
            if start < b)
        return Piece('helix', b - a, self.line_at(a), self.feed,
                     self.point(a), math.cos(phi) * self.e1
                     + math.sin(phi) * e2, self.e3, self.radius,
                     self.angle * (b - a) / self.length,
                     self.rise * (b - a) / self.length, lines=lines)


def _cross(a, b):
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


def _turn(t1, t2):
    """Angle (rad) between unit vectors: atan2, exact near 0 and pi."""
    a0, a1, a2 = t1.tolist()
    b0, b1, b2 = t2.tolist()
    return math.atan2(math.hypot(a1 * b2 - a2 * b1, a2 * b0 - a0 * b2,
                                 a0 * b1 - a1 * b0),
                      a0 * b0 + a1 * b1 + a2 * b2)


def _helix(origin, e1, e3, radius, angle, rise, length, w):
    """
    Evaluate the helix formula on arrays (every argument per point).

    ``cos phi - 1 = -2 sin^2(phi / 2)``: the offset from the start keeps
    its precision whatever the radius.
    """
    e2 = _cross(e3, e1)
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


def _bezier(control, tau):
    """Return a cubic Bezier and its derivatives by ``tau`` at ``tau`` (n,)."""
    t = tau[:, None]
    u = 1.0 - t
    p0, p1, p2, p3 = control
    p = u ** 3 * p0 + 3 * u * u * t * p1 + 3 * u * t * t * p2 + t ** 3 * p3
    d1 = 3 * (u * u * (p1 - p0) + 2 * u * t * (p2 - p1) + t * t * (p3 - p2))
    d2 = 6 * (u * (p2 - 2 * p1 + p0) + t * (p3 - 2 * p2 + p1))
    return p, d1, d2


def _speed(control, tau):
    """Return ``|B'(tau)|`` of a cubic Bezier, ``tau`` of any shape."""
    a, m, c = (3.0 * np.diff(control, axis=0))[..., None, None]
    u = 1.0 - tau
    d1 = u * u * a + 2.0 * u * tau * m + tau * tau * c
    return np.sqrt((d1 * d1).sum(0))


def _gauss_length(control, low, high):
    """Length (m) of the Bezier from ``low`` to ``high`` (each (n,))."""
    half = 0.5 * (high - low)
    nodes = (low + half)[:, None] + half[:, None] * _GAUSS_X[None]
    return half * (_speed(control, nodes) @ _GAUSS_W)


def _bezier_table(control):
    """Return the arc length at ``tau = j / BEZIER_SPANS``, j = 0..SPANS."""
    edges = np.arange(BEZIER_SPANS + 1) / BEZIER_SPANS
    return np.concatenate(([0.0], np.cumsum(_gauss_length(
        control, edges[:-1], edges[1:]))))


def _bezier_by_length(control, table, w):
    """
    Return ``p``, ``dp/dw``, ``d2p/dw2`` of a Bezier at arc lengths ``w``.

    ``tau(w)`` by Newton's method on the span's length (``table``), from
    its linear interpolation; then ``dp/dw = B' / |B'|`` (the unit
    tangent) and ``d2p/dw2 = (B'' - (B''.T) T) / |B'|^2`` (the curvature
    vector).
    """
    spans = len(table) - 1
    j = np.clip(np.searchsorted(table, w, side='right') - 1, 0, spans - 1)
    low = j / spans
    tau = low + (w - table[j]) / np.maximum(table[j + 1] - table[j],
                                            1e-300) / spans
    tau = np.clip(tau, low, low + 1.0 / spans)
    for _ in range(8):
        error = table[j] + _gauss_length(control, low, tau) - w
        if np.abs(error).max(initial=0.0) <= 1e-14 * table[-1]:
            break
        tau = np.clip(tau - error / _speed(control, tau[None])[0], low,
                      low + 1.0 / spans)
    p, d1, d2 = _bezier(control, tau)
    speed = np.linalg.norm(d1, axis=1)[:, None]
    unit = d1 / speed
    normal = d2 - (d2 * unit).sum(1)[:, None] * unit
    return p, unit, normal / (speed * speed)


def line_piece(start: Array, end: Array, line: int, feed: float,
               lines: Optional[tuple] = None) -> Piece:
    """Return the straight piece from ``start`` to ``end`` (m)."""
    start = np.asarray(start, dtype=float)
    delta = np.asarray(end, dtype=float) - start
    length = math.sqrt(float(delta @ delta))
    e3 = delta / length
    e1 = _cross3(e3, _AXES[int(np.argmin(np.abs(e3)))])
    return Piece('helix', length, line, feed, start,
                 e1 / math.sqrt(float(e1 @ e1)), e3, 0.0, 1.0, length,
                 lines=lines)


_AXES = np.eye(3)


def move_piece(move: Move) -> Piece:
    """Return a program move as a piece (a line, an arc or a helix)."""
    if move.kind == 'line':
        return line_piece(move.start, move.end, move.line, move.feed)
    e3 = move.normal
    offset = move.start - move.centre
    offset = offset - e3 * float(offset @ e3)
    radius = float(np.linalg.norm(offset))
    length = math.hypot(radius * move.angle, move.rise)
    return Piece('helix', length, move.line, move.feed, move.start.copy(),
                 offset / radius, e3, radius, move.angle, move.rise)


@dataclass(frozen=True)
class Path:
    """
    The pieces G follows, in order, and where it stops.

    ``pieces``: the :class:`Piece` list; ``stops``: (len(pieces) + 1,) bool,
    ``stops[k]`` True where G is at rest at the start of piece k (always at
    the start and at the end, the last entry); ``start_line``: the line
    that wrote the first point (None: where G starts, ``--start``);
    ``moves``: the moves (or segments of waypoints) it was made of.
    """

    pieces: tuple
    stops: Array
    start_line: Optional[int] = None
    moves: int = 0

    @property
    def length(self) -> float:
        """Return the sum of the pieces' lengths (m)."""
        return float(sum(p.length for p in self.pieces))

    @property
    def start(self) -> Array:
        """Return the first point (m)."""
        return self.pieces[0].point(0.0)

    @property
    def end(self) -> Array:
        """Return the last point (m)."""
        last = self.pieces[-1]
        return last.point(last.length)

    def line_at(self, index: int, w: float) -> Optional[int]:
        """Return the program's line of piece ``index`` at ``w`` (the start's)."""
        if index == 0 and w == 0.0:
            return self.start_line
        return self.pieces[index].line_at(w)

    def evaluate(self, index: Array, w: Array) -> tuple[Array, Array, Array]:
        """
        Return ``p``, ``dp/dw``, ``d2p/dw2`` ((n, 3)) at pieces ``index``, ``w``.

        Vectorised over the points: the helices in one formula, the Beziers
        in another.
        """
        index = np.asarray(index, dtype=int)
        w = np.asarray(w, dtype=float)
        table = self.table
        out = [np.empty((len(w), 3)) for _ in range(3)]
        helix = table['helix'][index]
        if helix.any():
            k = index[helix]
            values = _helix(table['origin'][k], table['e1'][k],
                            table['e3'][k], table['radius'][k],
                            table['angle'][k], table['rise'][k],
                            table['length'][k], w[helix])
            for o, v in zip(out, values):
                o[helix] = v
        for k in np.unique(index[~helix]):
            at = index == k
            values = self.pieces[k].evaluate(w[at])
            for o, v in zip(out, values):
                o[at] = v
        return tuple(out)

    @property
    def table(self) -> dict:
        """
        Return the pieces' fields as arrays, made once.

        ``helix`` (bool), ``origin``, ``e1``, ``e3`` (n, 3), ``radius``,
        ``angle``, ``rise``, ``length`` (n,).
        """
        table = self.__dict__.get('_cached_table')
        if table is None:
            pieces = self.pieces
            table = {
                'helix': np.array([p.kind == 'helix' for p in pieces]),
                'origin': np.array([p.origin for p in pieces]),
                'e1': np.array([p.e1 for p in pieces]),
                'e3': np.array([p.e3 for p in pieces]),
                'radius': np.array([p.radius for p in pieces]),
                'angle': np.array([p.angle for p in pieces]),
                'rise': np.array([p.rise for p in pieces]),
                'length': np.array([p.length for p in pieces])}
            object.__setattr__(self, '_cached_table', table)
        return table


def from_moves(moves: Sequence[Move], tolerance: float,
               start_line: Optional[int] = None,
               max_pieces: Optional[int] = None) -> Path:
    """
    Return the path of a program's moves, every junction decided.

    ``tolerance`` (m): the blends' where a move's own is None (G64 without
    P, waypoints); ``start_line``: the line of the first point (None: not
    the program's). See the module's docstring for the rules. Raises
    :class:`ProgramError` (TOO_LARGE) where the moves make more than
    ``max_pieces`` pieces before any corner is blended.
    """
    if not moves:
        raise ProgramError(None, 'zero-length program: no move', EMPTY)
    pieces, ends = _straight_runs(moves)
    if max_pieces is not None and len(pieces) > max_pieces:
        raise ProgramError(None, f'{len(moves)} moves make a path of '
                           f'{len(pieces)} pieces at least: more than '
                           f'{max_pieces}', TOO_LARGE)
    n = len(pieces)
    trim = np.zeros((n, 2))         # taken off each piece's start, end
    blends = [None] * (n - 1)
    stops = np.zeros(n + 1, dtype=bool)
    stops[0] = stops[n] = True
    for k in range(n - 1):
        first, second = pieces[k], pieces[k + 1]
        turn = _turn(first.tangent(first.length), second.tangent(0.0))
        move = ends[k]
        within = move.tolerance if move.tolerance is not None else tolerance
        if move.mode == EXACT_STOP:
            stops[k + 1] = True
        elif turn <= TANGENT:
            continue
        elif move.mode == EXACT_PATH or (move.mode == BLEND and within <= 0):
            if turn <= KINK:
                blends[k] = (KINK_TOLERANCE, turn)
            else:
                stops[k + 1] = True
        elif turn >= math.pi - ABOUT_TURN:
            stops[k + 1] = True
        else:
            blends[k] = (within, turn)
    for k, blend in enumerate(blends):
        if blend is None:
            continue
        room = min(pieces[k].length, pieces[k + 1].length) * 0.5
        made = _blend(pieces[k], pieces[k + 1], blend[0], blend[1], room)
        if made is None:
            stops[k + 1] = True
            blends[k] = None
        else:
            blends[k] = made
            trim[k, 1] = trim[k + 1, 0] = made[1]
    out = []
    out_stops = []
    for k, piece in enumerate(pieces):
        a, b = trim[k, 0], piece.length - trim[k, 1]
        if b - a > ZERO_LENGTH * 1e3:
            out.append(piece if a == 0.0 and b == piece.length
                       else piece.sub(a, b))
            out_stops.append(stops[k])
        if k < n - 1 and blends[k] is not None:
            out.append(blends[k][0])
            out_stops.append(False)
    out_stops.append(True)
    out_stops[0] = True
    return Path(tuple(out), np.array(out_stops), start_line, len(moves))


def _straight_runs(moves):
    """
    Return the pieces of ``moves``, each straight run one line.

    Returns ``(pieces, ends)``: ``ends[k]`` the move whose end is piece
    k's (its path control mode decides the junction after it). A run:
    lines of one feed, each within TANGENT of the run's first direction
    (so every junction of the run is within TANGENT times its length of
    the one line), no exact stop between.
    """
    pieces, ends = [], []
    k = 0
    while k < len(moves):
        move = moves[k]
        last = k
        if move.kind == 'line':
            direction = _unit(move.end - move.start)
            while (last + 1 < len(moves) and moves[last].mode != EXACT_STOP
                   and moves[last + 1].kind == 'line'
                   and moves[last + 1].feed == move.feed
                   and _turn(direction, _unit(moves[last + 1].end
                                              - moves[last + 1].start))
                   <= TANGENT):
                last += 1
        if last == k:
            pieces.append(move_piece(move))
        else:
            run = moves[k:last + 1]
            lines = tuple((float((m.start - move.start) @ direction), m.line)
                          for m in run)
            pieces.append(line_piece(move.start, moves[last].end, move.line,
                                     move.feed, lines))
        ends.append(moves[last])
        k = last + 1
    return pieces, ends


def _unit(vector):
    return vector / math.sqrt(float(vector @ vector))


def _blend(first, second, tolerance, turn, room):
    """
    Return ``(piece, trim)``: the corner's blend within ``tolerance``, or None.

    ``trim`` (m) is taken off the end of ``first`` and the start of
    ``second``, at most ``room``. A Bezier's trim: the largest (to 0.1 %,
    by bisection) whose points at 33 parameters are within ``tolerance``,
    then shortened by 2 % at a time until the whole curve is proven within
    it (:func:`_proven_within`).
    """
    if first.radius == 0.0 and second.radius == 0.0 and \
            first.kind == second.kind == 'helix':
        return _line_blend(first, second, tolerance, turn, room)

    def sampled(trim):
        control = _bezier_control(first, second, trim)
        return control is not None and _near(
            _bezier(control, _SAMPLES)[0], *_chords(first, second, trim,
                                                    tolerance), tolerance)
    low, high = (room, room) if sampled(room) else (0.0, room)
    for _ in range(40):
        if high - low <= 1e-3 * high:
            break
        trim = 0.5 * (low + high)
        low, high = (trim, high) if sampled(trim) else (low, trim)
    trim = low
    for _ in range(PROOF_TRIES):
        control = _bezier_control(first, second, trim)
        if control is None:
            return None
        if _proven_within(control, *_chords(first, second, trim, tolerance),
                          tolerance):
            table = _bezier_table(control)
            return Piece('bezier', float(table[-1]),
                         first.line_at(first.length),
                         min(first.feed, second.feed), control=control,
                         table=table), trim
        trim *= 0.98
    return None


def _line_blend(first, second, tolerance, turn, room):
    """
    Return the circular arc tangent to two lines, within ``tolerance``.

    Its frame from the first line's direction ``t1`` and the second's
    component across it, so the arc leaves along ``t1`` and arrives along
    ``t2`` to rounding however small the turn.
    """
    t1, t2 = first.e3, second.e3
    # The arc's largest distance to the lines, at its middle, is
    # trim tan(turn / 4) cos(turn / 2).
    trim = min(room, tolerance / (math.tan(0.25 * turn)
                                  * math.cos(0.5 * turn)))
    if trim <= ZERO_LENGTH * 1e3:
        return None
    corner = first.point(first.length)
    radius = trim / math.tan(0.5 * turn)
    inward = t2 - t1 * float(t1 @ t2)
    inward = _unit(inward - t1 * float(t1 @ inward))
    e1 = -inward
    piece = Piece('helix', radius * turn, first.line_at(first.length),
                  min(first.feed, second.feed), corner - trim * t1, e1,
                  _cross3(e1, t1), radius, turn, 0.0)
    return piece, trim


def _bezier_control(first, second, trim):
    """
    Return the control points (4, 3) of the Bezier replacing the corner.

    From ``trim`` before the corner to ``trim`` after it, tangent to both
    pieces; None where it cannot be followed by its arc length (its
    hodograph's control points not on one side of a plane, where ``|B'|``
    might vanish) or turns about.
    """
    if trim <= ZERO_LENGTH * 1e3:
        return None
    a = first.point(first.length - trim)
    b = second.point(trim)
    ta = first.tangent(first.length - trim)
    tb = second.tangent(trim)
    chord = float(np.linalg.norm(b - a))
    turn = _turn(ta, tb)
    if chord <= 0.0 or turn >= math.pi - ABOUT_TURN:
        return None
    # Arms of the Bezier nearest a circular arc of that turn.
    arm = (2.0 / 3.0) * chord * (math.tan(0.25 * turn) / math.sin(0.5 * turn)
                                 if turn > 1e-8 else 0.5)
    control = np.array([a, a + arm * ta, b - arm * tb, b])
    if (np.diff(control, axis=0) @ _unit(ta + tb)).min() <= 1e-9 * chord:
        return None
    return control


def _chords(first, second, trim, tolerance):
    """
    Return the programmed path beside a corner as chords, and their slack.

    The last ``trim`` of ``first`` and the first of ``second`` as segments
    ``(a, b)`` ((k, 3) each), each within ``slack`` (k,) of its part of a
    helix: ``radius dphi^2 / 8``, the error of linear interpolation, at
    most a hundredth of ``tolerance`` unless PROOF_SEGMENTS do not reach.
    """
    starts, ends, slack = [], [], []
    for piece, low in ((first, first.length - trim), (second, 0.0)):
        sweep = abs(piece.angle) * trim / piece.length
        count = 1 if piece.radius == 0.0 else min(PROOF_SEGMENTS, max(
            1, math.ceil(sweep * math.sqrt(piece.radius
                                           / (0.08 * tolerance)))))
        points = piece.evaluate(np.linspace(low, low + trim, count + 1))[0]
        starts.append(points[:-1])
        ends.append(points[1:])
        slack.append(np.full(count, piece.radius * (sweep / count) ** 2 / 8))
    return tuple(np.concatenate(v) for v in (starts, ends, slack))


def _distances(points, a, b):
    """Return the distance (m) of each of ``points`` (n, 3) to each segment."""
    ab = b - a
    ab2 = np.maximum((ab * ab).sum(1), 1e-300)
    q = points[:, None]
    t = np.clip(((q - a) * ab).sum(2) / ab2, 0.0, 1.0)
    return np.linalg.norm(q - a - t[..., None] * ab, axis=2)


def _near(points, a, b, slack, tolerance):
    """Whether no point of the curve is surely beyond ``tolerance``."""
    return not ((_distances(points, a, b) - slack).min(1) > tolerance).any()


def _proven_within(control, a, b, slack, tolerance):
    """
    Whether the Bezier ``control`` is proven within ``tolerance`` of the path.

    The programmed path as chords ``(a, b)`` (:func:`_chords`): the
    distance of any point ``q`` to the path is at most ``dist(q, chord) +
    slack``. The distance to a segment is convex, so over a part of the
    curve, which lies in the convex hull of its control points, it is
    largest at one of them: ``max_i dist(Q_i, chord) + slack`` of the best
    chord bounds the whole part. The curve is halved (de Casteljau) until
    every part's bound is within ``tolerance``; not proven (False) where a
    point of the curve is beyond it, or after PROOF_DEPTH halvings or with
    more than PROOF_CURVES parts.
    """
    curves = control[None]
    for _ in range(PROOF_DEPTH):
        distance = _distances(curves.reshape(-1, 3), a, b).reshape(
            len(curves), 4, -1)
        # The first control point of each part is on the curve.
        if ((distance[:, 0] - slack).min(1) > tolerance).any():
            return False
        curves = curves[(distance.max(1) + slack).min(1) > tolerance]
        if len(curves) == 0:
            return True
        if 2 * len(curves) > PROOF_CURVES:
            return False
        curves = _halves(curves)
    return False


def _halves(curves):
    """Split each cubic Bezier (K, 4, 3) at its middle: (2K, 4, 3)."""
    p0, p1, p2, p3 = (curves[:, k] for k in range(4))
    m01, m12, m23 = (p0 + p1) / 2, (p1 + p2) / 2, (p2 + p3) / 2
    m012, m123 = (m01 + m12) / 2, (m12 + m23) / 2
    middle = (m012 + m123) / 2
    left = np.stack((p0, m01, m012, middle), 1)
    right = np.stack((middle, m123, m23, p3), 1)
    return np.concatenate((left, right))


def from_waypoints(points: Array, feeds: Optional[Array], lines: Sequence[int],
                   tolerance: float, max_pieces: Optional[int] = None
                   ) -> Path:
    """
    Return the path through ``points`` (n, 3) m: lines, corners blended.

    Segment k ends at ``points[k + 1]`` with that row's ``feeds`` (m/s, or
    none) and ``lines``; consecutive equal points are one; ``lines[0]``:
    the first point's line (0: not the program's). Corners are blended
    within ``tolerance`` (m), stopped where it is 0. Raises
    :class:`ProgramError` where a coordinate is beyond NUMBER_BOUND, where
    no point is away from the first, and (TOO_LARGE) where the path would
    have more than ``max_pieces`` pieces, counted before any is made.
    """
    points = np.asarray(points, dtype=float)
    far = ~(np.abs(points) <= NUMBER_BOUND).all(1)
    if far.any():
        k = int(np.argmax(far))
        raise ProgramError(lines[k] or None, f'the point {points[k].tolist()}'
                           f' m is beyond {NUMBER_BOUND:,.0f} m')
    keep = [0]
    for k in range(1, len(points)):
        step = points[k] - points[keep[-1]]
        if math.sqrt(float(step @ step)) > ZERO_LENGTH:
            keep.append(k)
    if len(keep) < 2:
        raise ProgramError(None, 'zero-length program: no waypoint is away '
                           'from the first', EMPTY)
    if max_pieces is not None:
        count = _least_pieces(points[keep], tolerance)
        if count > max_pieces:
            raise ProgramError(None, f'{len(points)} points make a path of '
                               f'{count} pieces at least (lines and corner '
                               f'blends): more than {max_pieces}', TOO_LARGE)
    moves = [Move('line', points[i], points[k], lines[k],
                  math.inf if feeds is None else float(feeds[k]),
                  BLEND if tolerance > 0.0 else EXACT_PATH, tolerance)
             for i, k in zip(keep[:-1], keep[1:])]
    return from_moves(moves, tolerance, lines[0] or None, max_pieces)


def _least_pieces(points, tolerance):
    """
    Return a lower bound of the pieces of the polyline ``points``.

    Its segments less those within TANGENT of the one before (a straight
    run is one piece at least), plus a blend at each other corner that
    :func:`from_moves` blends (``tolerance`` above 0, not an about-turn,
    room for a trim): vectorised, before any piece is made.
    """
    step = np.diff(points, axis=0)
    length = np.linalg.norm(step, axis=1)
    unit = step / length[:, None]
    cross = np.linalg.norm(_cross(unit[:-1], unit[1:]), axis=1)
    turn = np.arctan2(cross, (unit[:-1] * unit[1:]).sum(1))
    corner = turn > TANGENT
    if tolerance <= 0.0:
        return 1 + int(corner.sum())
    with np.errstate(divide='ignore'):
        trim = np.minimum(0.5 * np.minimum(length[:-1], length[1:]),
                          tolerance / (np.tan(0.25 * turn)
                                       * np.cos(0.5 * turn)))
    blended = corner & (turn < math.pi - ABOUT_TURN) & (
        trim > ZERO_LENGTH * 1e3)
    return 1 + int(corner.sum()) + int(blended.sum())
