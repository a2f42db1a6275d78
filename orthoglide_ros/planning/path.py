"""
The geometric path of G: lines, exact arcs and helices, corner blends.

A :class:`Path` is a chain of pieces, each parametrised by ``w`` from 0 to
its length (m; the arc length but for a corner's Bezier blend, where it is
close to it), with the junctions where G must stop. :func:`from_moves`
builds one from a program's moves and decides every junction:

- a tangent junction (tangents within TANGENT rad) is passed at speed;
- an exact stop (G61.1) stops at every move's end;
- exact path (G61, the default) stops at a corner, and smooths a kink of at
  most KINK rad (CAM output rounded to the micrometre) within
  KINK_TOLERANCE: a tangent junction in all but its rounding;
- a blend (G64 P, CSV waypoints, a nav_msgs/Path) replaces the corner by
  the fastest curve within the tolerance of the programmed path: a
  circular arc tangent to two lines (trimming each by at most half its
  length; a circle sampled as a polyline becomes the circle again), a
  cubic Bezier tangent to any other pair; an about-turn stops.

:meth:`Path.evaluate` gives ``p``, ``dp/dw`` and ``d2p/dw2`` of any points,
vectorised: one formula serves lines and helices (a line is a helix of
radius zero).
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Optional, Sequence

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning.gcode import (BLEND, EXACT_PATH, EXACT_STOP, Move,
                                           ProgramError, ZERO_LENGTH)

# Tangents within this angle (rad) join smoothly: passed at speed.
TANGENT = 1e-9
# Exact path (G61): a kink of at most this (rad, 0.06 deg) is CAM rounding,
# smoothed within KINK_TOLERANCE (m) and passed at speed.
KINK = 1e-3
KINK_TOLERANCE = 1e-6
# A turn nearer than this to an about-turn (rad) is not blended: G stops.
ABOUT_TURN = 1e-6
# The points of a Bezier blend and of the path it replaces, compared.
BLEND_SAMPLES = 33


@dataclass(frozen=True)
class Piece:
    """
    One smooth piece of the path: a helix (a line or an arc) or a Bezier.

    A helix: ``p(phi) = centre + radius (cos phi e1 + sin phi e2) + rise
    (phi / angle) e3`` with ``e2 = e3 x e1``, ``phi = angle w / length``
    for ``w`` in [0, length]; a line has radius 0, angle 1, rise its length
    and e3 its direction. A Bezier: ``control`` (4, 3), ``w = length tau``.
    ``line``: the program's line (from 1); ``feed``: G's speed cap (m/s).
    """

    kind: str
    length: float
    line: int
    feed: float
    centre: Array = field(default_factory=lambda: np.zeros(3))
    e1: Array = field(default_factory=lambda: np.zeros(3))
    e3: Array = field(default_factory=lambda: np.zeros(3))
    radius: float = 0.0
    angle: float = 1.0
    rise: float = 0.0
    control: Optional[Array] = None

    def evaluate(self, w: Array) -> tuple[Array, Array, Array]:
        """Return ``p``, ``dp/dw``, ``d2p/dw2`` at ``w`` ((n,) m): (n, 3)."""
        w = np.asarray(w, dtype=float)
        if self.kind == 'bezier':
            return _bezier(self.control, w / self.length, self.length)
        return _helix(self.centre[None], self.e1[None], self.e3[None],
                      self.radius, self.angle, self.rise, self.length, w)

    def point(self, w: float) -> Array:
        """Return ``p(w)`` (3,)."""
        if self.kind == 'bezier':
            return self.evaluate(np.array([w]))[0][0]
        phi = self.angle * w / self.length
        return self.centre + self.radius * (
            math.cos(phi) * self.e1 + math.sin(phi) * _cross(self.e3,
                                                             self.e1)) \
            + (self.rise * w / self.length) * self.e3

    def tangent(self, w: float) -> Array:
        """Return the unit tangent at ``w`` (3,)."""
        if self.kind == 'bezier':
            d1 = self.evaluate(np.array([w]))[1][0]
        elif self.radius == 0.0:
            return self.e3
        else:
            phi = self.angle * w / self.length
            d1 = (self.angle * self.radius / self.length) * (
                math.cos(phi) * _cross(self.e3, self.e1)
                - math.sin(phi) * self.e1) + (self.rise / self.length) \
                * self.e3
        return d1 / math.sqrt(float(d1 @ d1))

    def sub(self, a: float, b: float) -> 'Piece':
        """Return the part from ``w = a`` to ``b`` of a helix, as a piece."""
        frac = a / self.length
        phi = self.angle * frac
        e2 = _cross(self.e3, self.e1)
        return Piece('helix', b - a, self.line, self.feed,
                     self.centre + self.rise * frac * self.e3,
                     math.cos(phi) * self.e1 + math.sin(phi) * e2, self.e3,
                     self.radius, self.angle * (b - a) / self.length,
                     self.rise * (b - a) / self.length)


def _cross(a, b):
    """Return ``a x b`` of (..., 3) arrays (np.cross is slow on small ones)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2,
                     a0 * b1 - a1 * b0), -1)


def _helix(centre, e1, e3, radius, angle, rise, length, w):
    """Evaluate the helix formula on arrays (every argument per point)."""
    e2 = _cross(e3, e1)
    k = angle / length
    phi = k * w
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    radius = np.reshape(radius, (-1, 1))
    k = np.reshape(k, (-1, 1))
    p = centre + radius * (c * e1 + s * e2) + np.reshape(
        rise / length, (-1, 1)) * w[:, None] * e3
    d1 = k * radius * (c * e2 - s * e1) + np.reshape(rise / length,
                                                     (-1, 1)) * e3
    d2 = -k * k * radius * (c * e1 + s * e2)
    return p, d1, d2


def _bezier(control, tau, length):
    """Evaluate a cubic Bezier at ``tau`` in [0, 1], derivatives by ``w``."""
    t = tau[:, None]
    u = 1.0 - t
    p0, p1, p2, p3 = control
    p = u ** 3 * p0 + 3 * u * u * t * p1 + 3 * u * t * t * p2 + t ** 3 * p3
    d1 = 3 * (u * u * (p1 - p0) + 2 * u * t * (p2 - p1) + t * t * (p3 - p2))
    d2 = 6 * (u * (p2 - 2 * p1 + p0) + t * (p3 - 2 * p2 + p1))
    return p, d1 / length, d2 / (length * length)


def _bezier_length(control):
    """Length of a cubic Bezier (m): 16-point Gauss-Legendre."""
    x, weights = np.polynomial.legendre.leggauss(16)
    d1 = _bezier(control, 0.5 * (x + 1.0), 1.0)[1]
    return float(0.5 * weights @ np.linalg.norm(d1, axis=1))


def line_piece(start: Array, end: Array, line: int, feed: float) -> Piece:
    """Return the straight piece from ``start`` to ``end`` (m)."""
    start = np.asarray(start, dtype=float)
    delta = np.asarray(end, dtype=float) - start
    length = math.sqrt(float(delta @ delta))
    e3 = delta / length
    e1 = _cross(e3, _AXES[int(np.argmin(np.abs(e3)))])
    return Piece('helix', length, line, feed, start,
                 e1 / math.sqrt(float(e1 @ e1)), e3, 0.0, 1.0, length)


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
    return Piece('helix', length, move.line, move.feed, move.centre,
                 offset / radius, e3, radius, move.angle, move.rise)


@dataclass(frozen=True)
class Path:
    """
    The pieces G follows, in order, and where it stops.

    ``pieces``: the :class:`Piece` list; ``stops``: (len(pieces) + 1,) bool,
    ``stops[k]`` True where G is at rest at the start of piece k (always at
    the start and at the end, the last entry).
    """

    pieces: tuple
    stops: Array

    @property
    def length(self) -> float:
        """Return the sum of the pieces' parameter lengths (m)."""
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

    def evaluate(self, index: Array, w: Array) -> tuple[Array, Array, Array]:
        """
        Return ``p``, ``dp/dw``, ``d2p/dw2`` ((n, 3)) at pieces ``index``, ``w``.

        Vectorised over the points: the helices in one formula, the Beziers
        in another.
        """
        index = np.asarray(index, dtype=int)
        w = np.asarray(w, dtype=float)
        table = self._table
        out = [np.empty((len(w), 3)) for _ in range(3)]
        helix = table['helix'][index]
        if helix.any():
            k = index[helix]
            values = _helix(table['centre'][k], table['e1'][k],
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
    def _table(self):
        table = self.__dict__.get('_cached_table')
        if table is None:
            pieces = self.pieces
            table = {
                'helix': np.array([p.kind == 'helix' for p in pieces]),
                'centre': np.array([p.centre for p in pieces]),
                'e1': np.array([p.e1 for p in pieces]),
                'e3': np.array([p.e3 for p in pieces]),
                'radius': np.array([p.radius for p in pieces]),
                'angle': np.array([p.angle for p in pieces]),
                'rise': np.array([p.rise for p in pieces]),
                'length': np.array([p.length for p in pieces])}
            object.__setattr__(self, '_cached_table', table)
        return table


def from_moves(moves: Sequence[Move], tolerance: float) -> Path:
    """
    Return the path of a program's moves, every junction decided.

    ``tolerance`` (m): the blends' where a move's own is None (G64 without
    P, waypoints). See the module's docstring for the rules.
    """
    if not moves:
        raise ProgramError(None, 'zero-length program: no move')
    pieces = [move_piece(m) for m in moves]
    n = len(pieces)
    trim = np.zeros((n, 2))         # taken off each piece's start, end
    blends = [None] * (n - 1)
    stops = np.zeros(n + 1, dtype=bool)
    stops[0] = stops[n] = True
    for k in range(n - 1):
        first, second = pieces[k], pieces[k + 1]
        t1 = first.tangent(first.length)
        t2 = second.tangent(0.0)
        turn = math.acos(max(-1.0, min(1.0, float(t1 @ t2))))
        move = moves[k]
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
    return Path(tuple(out), np.array(out_stops))


def _blend(first, second, tolerance, turn, room):
    """
    Return ``(piece, trim)``: the corner's blend within ``tolerance``, or None.

    ``trim`` (m) is taken off the end of ``first`` and the start of
    ``second``, at most ``room``.
    """
    if first.radius == 0.0 and second.radius == 0.0 and \
            first.kind == second.kind == 'helix':
        return _line_blend(first, second, tolerance, turn, room)
    if _fits(first, second, room, tolerance):
        return _bezier_blend(first, second, room)
    low, high = 0.0, room
    for _ in range(40):
        if high - low <= 1e-3 * high:
            break
        trim = 0.5 * (low + high)
        if _fits(first, second, trim, tolerance):
            low = trim
        else:
            high = trim
    return _bezier_blend(first, second, low) if low > 0.0 else None


def _fits(first, second, trim, tolerance):
    """Whether the Bezier blend of ``trim`` stays within ``tolerance``."""
    candidate = _bezier_blend(first, second, trim)
    return candidate is not None and _deviation(
        candidate[0], first, second, trim) <= tolerance


def _line_blend(first, second, tolerance, turn, room):
    """Return the circular arc tangent to two lines, within ``tolerance``."""
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
    inward /= math.sqrt(float(inward @ inward))
    tangent_point = corner - trim * t1
    centre = tangent_point + radius * inward
    e3 = _cross(t1, t2)
    e3 /= math.sqrt(float(e3 @ e3))
    feed = min(first.feed, second.feed)
    piece = Piece('helix', radius * turn, first.line, feed, centre, -inward,
                  e3, radius, turn, 0.0)
    return piece, trim


def _bezier_blend(first, second, trim):
    """Return the cubic Bezier from ``trim`` before the corner to after it."""
    if trim <= ZERO_LENGTH * 1e3:
        return None
    a = first.point(first.length - trim)
    b = second.point(trim)
    ta = first.tangent(first.length - trim)
    tb = second.tangent(trim)
    chord = float(np.linalg.norm(b - a))
    turn = math.acos(max(-1.0, min(1.0, float(ta @ tb))))
    if chord <= 0.0 or turn >= math.pi - ABOUT_TURN:
        return None
    # Arms of the Bezier nearest a circular arc of that turn.
    arm = (2.0 / 3.0) * chord * (math.tan(0.25 * turn) / math.sin(0.5 * turn)
                                 if turn > 1e-8 else 0.5)
    control = np.array([a, a + arm * ta, b - arm * tb, b])
    length = _bezier_length(control)
    piece = Piece('bezier', length, first.line, min(first.feed, second.feed),
                  control=control)
    return piece, trim


def _deviation(piece, first, second, trim):
    """Largest distance (m) of ``piece`` from the two pieces' trimmed parts."""
    w = np.linspace(0.0, piece.length, BLEND_SAMPLES)
    points = piece.evaluate(w)[0]
    dense = 8 * BLEND_SAMPLES
    original = np.vstack((
        first.evaluate(np.linspace(first.length - trim, first.length,
                                   dense))[0],
        second.evaluate(np.linspace(0.0, trim, dense))[0]))
    return float(polyline_distance(points, original).max())


def polyline_distance(points: Array, polyline: Array) -> Array:
    """Distance (m) of each of ``points`` (n, 3) to a polyline (m, 3)."""
    a = polyline[:-1][None]
    ab = (polyline[1:] - polyline[:-1])[None]
    ap = points[:, None] - a
    denominator = np.maximum((ab * ab).sum(-1), 1e-300)
    t = np.clip((ap * ab).sum(-1) / denominator, 0.0, 1.0)
    return np.linalg.norm(ap - t[..., None] * ab, axis=-1).min(1)


def from_waypoints(points: Array, feeds: Optional[Array], lines: Sequence[int],
                   tolerance: float) -> Path:
    """
    Return the path through ``points`` (n, 3) m: lines, corners blended.

    Segment k ends at ``points[k + 1]`` with that row's ``feeds`` (m/s, or
    none) and ``lines``; consecutive equal points are one. Corners are
    blended within ``tolerance`` (m), stopped where it is 0. Raises
    :class:`ProgramError` where no point is away from the first.
    """
    points = np.asarray(points, dtype=float)
    moves = []
    here = points[0]
    for k in range(1, len(points)):
        if np.linalg.norm(points[k] - here) <= ZERO_LENGTH:
            continue
        feed = math.inf if feeds is None else float(feeds[k])
        moves.append(Move('line', here, points[k], lines[k], feed,
                          BLEND if tolerance > 0.0 else EXACT_PATH,
                          tolerance))
        here = points[k]
    if not moves:
        raise ProgramError(None, 'zero-length program: no waypoint is away '
                           'from the first')
    return from_moves(moves, tolerance)
