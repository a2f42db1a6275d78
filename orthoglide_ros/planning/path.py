"""
The geometric path of G: lines, exact arcs, helices and splines, blends.

A :class:`Path` is a chain of pieces, each parametrised by its arc length
``w`` from 0 to its length (m), with the junctions where G must stop.
:func:`from_moves` builds one from a program's moves and decides every
junction:

- a straight run (consecutive lines of one feed, each within TANGENT rad
  of the run's first direction, no exact stop between) is one line;
- a run of chords under plain G64 (and CSV waypoints and a
  nav_msgs/Path) is followed as the curve it samples, within the
  tolerance of every programmed point (:mod:`chords`); its corners and
  long moves stay what they are;
- a tangent junction (tangents within TANGENT rad) is passed at speed;
- an exact stop (G61.1) stops at every move's end;
- exact path (G61, the default) stops at a corner, and smooths a kink of at
  most KINK rad (CAM output rounded to the micrometre) within
  KINK_TOLERANCE: a tangent junction in all but its rounding;
- a blend (G64, CSV waypoints, a nav_msgs/Path) replaces the corner by the
  fastest curve within the tolerance (:mod:`blends`): of the programmed
  path (G64 P), and of the corner's point too where that is a programmed
  point the path keeps (plain G64, waypoints); an about-turn stops.

:meth:`Path.evaluate` gives ``p``, ``dp/dw`` and ``d2p/dw2`` of any points,
vectorised: one formula serves lines and helices (a line is a helix of
radius zero), written from the piece's start so that a huge radius (a
nearly straight blend) loses no precision; another every span of every
Bezier piece (blends, G5 splines, fitted runs), each followed by its arc
length too (:mod:`bezier`), so ``|dp/dw|`` is 1 everywhere and G's
velocity is continuous wherever its speed is.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Optional, Sequence

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import bezier, blends, chords
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
ABOUT_TURN = blends.ABOUT_TURN
# A Bezier span whose speed varies more (its least over its largest
# below this) is halved, at most SPLIT_DEPTH times, so that its arc
# length is exact to rounding.
EVEN_SPEED = 0.7
SPLIT_DEPTH = 10
# Points of Bezier pieces evaluated at once.
BEZIER_BLOCK = 4096


@dataclass(frozen=True)
class Piece:
    """
    One smooth piece of the path: a helix (a line or an arc) or a Bezier.

    A helix: ``p(phi) = origin + radius ((cos phi - 1) e1 + sin phi e2) +
    rise (phi / angle) e3`` with ``e2 = e3 x e1``, ``phi = angle w /
    length`` for ``w`` in [0, length] (``e1`` points from the axis to the
    start); a line has radius 0, angle 1, rise its length and e3 its
    direction. A Bezier: its spans' ``control`` points (m, 4, 3), each
    span's arc length ``table`` (:func:`bezier.tables`), ``starts`` (m + 1,)
    where each span starts along the piece and its total ``turning``
    (rad). ``line``: the program's line (from 1); ``feed``: G's speed cap
    (m/s); ``lines``: ``(k, 2)``, where each of the moves a straight run
    or a fitted run is made of starts (``w``, its line).
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
    starts: Optional[Array] = None
    turning: float = 0.0
    lines: Optional[Array] = None

    def evaluate(self, w: Array) -> tuple[Array, Array, Array]:
        """Return ``p``, ``dp/dw``, ``d2p/dw2`` at ``w`` ((n,) m): (n, 3)."""
        w = np.asarray(w, dtype=float)
        if self.kind == 'bezier':
            j = self._span(w)
            return bezier.by_length(self.control[j], self.table[j],
                                    w - self.starts[j])
        return _helix(self.origin[None], self.e1[None], self.e3[None],
                      self.radius, self.angle, self.rise, self.length, w)

    def _span(self, w):
        """Return the span of each ``w`` of a Bezier piece."""
        return np.clip(np.searchsorted(self.starts, w, side='right') - 1, 0,
                       len(self.control) - 1)

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

    def room(self, start: bool) -> float:
        """
        Return how much a blend may trim at the piece's start (or end), m.

        Half the piece; of a fitted run (a Bezier piece of several moves),
        half its first (last) span: a blend takes no programmed point but
        the corner's.
        """
        if self.kind == 'bezier' and self.lines is not None:
            spans = np.diff(self.starts)
            return 0.5 * float(spans[0] if start else spans[-1])
        return 0.5 * self.length

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

    def sub(self, a: float, b: float) -> 'Piece':
        """Return the part from ``w = a`` to ``b``, as a piece."""
        lines = self._lines_within(a, b)
        if self.kind == 'bezier':
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
                control[0] = bezier.part(control[:1], taus[:1],
                                         np.ones(1))[0]
                control[-1] = bezier.part(control[-1:], np.zeros(1),
                                          taus[1:])[0]
            return bezier_piece(control, self.line_at(a), self.feed, lines)
        phi = self.angle * a / self.length
        e2 = _cross3(self.e3, self.e1)
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


def line_piece(start: Array, end: Array, line: int, feed: float,
               lines: Optional[Array] = None) -> Piece:
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


def bezier_piece(control: Array, line: int, feed: float,
                 lines: Optional[Array] = None) -> Piece:
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
    return Piece('bezier', float(starts[-1]), line, feed, control=control,
                 table=table, starts=starts,
                 turning=float(bezier.turning(control).sum()), lines=lines)


def move_piece(move: Move) -> Piece:
    """Return a program move as a piece (a line, an arc, a helix, a spline)."""
    if move.kind == 'line':
        return line_piece(move.start, move.end, move.line, move.feed)
    if move.kind == 'spline':
        return bezier_piece(move.control, move.line, move.feed)
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

        Vectorised over the points: the helices in one formula, the spans
        of every Bezier piece in another (BEZIER_BLOCK points at a time:
        its Newton steps' work is larger).
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
        rows = np.flatnonzero(~helix)
        for start in range(0, len(rows), BEZIER_BLOCK):
            at = rows[start:start + BEZIER_BLOCK]
            k, along = index[at], w[at]
            span = np.clip(np.searchsorted(
                table['span_s'], table['piece_s'][k] + along,
                side='right') - 1, table['span_first'][k],
                table['span_first'][k + 1] - 1)
            values = bezier.by_length(table['control'][span],
                                      table['tables'][span],
                                      along - table['span_start'][span])
            for o, v in zip(out, values):
                o[at] = v
        return tuple(out)

    @property
    def table(self) -> dict:
        """
        Return the pieces' fields as arrays, made once.

        ``helix`` (bool), ``origin``, ``e1``, ``e3`` (n, 3), ``radius``,
        ``angle``, ``rise``, ``length``, ``turning``, ``spans`` (n,), and the
        spans of the Bezier pieces, in order: ``control`` (S, 4, 3),
        ``tables`` (S, SUBSPANS + 1), ``span_start`` (S,) along its piece
        and ``span_s`` along the path, ``span_turning`` (S,) rad,
        ``span_first`` (n + 1,) each piece's first, ``piece_s`` (n,) where
        each piece starts along the path.
        """
        table = self.__dict__.get('_cached_table')
        if table is None:
            pieces = self.pieces
            curves = [p for p in pieces if p.kind == 'bezier']
            spans = np.array([0 if p.control is None else len(p.control)
                              for p in pieces])
            lengths = np.array([p.length for p in pieces])
            piece_s = np.concatenate(([0.0], np.cumsum(lengths)[:-1]))
            span_start = np.concatenate(
                [p.starts[:-1] for p in curves] or [np.zeros(0)])
            control = np.concatenate(
                [p.control for p in curves] or [np.zeros((0, 4, 3))])
            table = {
                'helix': np.array([p.kind == 'helix' for p in pieces]),
                'origin': np.array([p.origin for p in pieces]),
                'e1': np.array([p.e1 for p in pieces]),
                'e3': np.array([p.e3 for p in pieces]),
                'radius': np.array([p.radius for p in pieces]),
                'angle': np.array([p.angle for p in pieces]),
                'rise': np.array([p.rise for p in pieces]),
                'length': lengths,
                'turning': np.array([p.turning for p in pieces]),
                'spans': spans,
                'control': control,
                'tables': np.concatenate(
                    [p.table for p in curves]
                    or [np.zeros((0, bezier.SUBSPANS + 1))]),
                'span_start': span_start,
                'span_turning': bezier.turning(control),
                'span_s': np.repeat(piece_s, spans) + span_start,
                'span_first': np.concatenate(([0], np.cumsum(spans))),
                'piece_s': piece_s}
            object.__setattr__(self, '_cached_table', table)
        return table


def from_moves(moves: Sequence[Move], tolerance: float,
               start_line: Optional[int] = None,
               max_pieces: Optional[int] = None) -> Path:
    """
    Return the path of a program's moves, every junction decided.

    ``tolerance`` (m): the blends' where a move's own is None (G64 without
    P, waypoints), and the distance of the programmed points to the curves
    runs of chords become there; ``start_line``: the line of the first
    point (None: not the program's). See the module's docstring for the
    rules. Raises :class:`ProgramError` (TOO_LARGE) where the moves make
    more than ``max_pieces`` pieces before any corner is blended (counted
    before the pieces of runs of chords are made).
    """
    if not moves:
        raise ProgramError(None, 'zero-length program: no move', EMPTY)

    def chained(k):     # the junction after move k is within a chain
        return k + 1 < len(moves) and _fitted(moves[k], tolerance) and \
            moves[k].kind == moves[k + 1].kind == 'line'
    groups = []         # straight runs' (pieces, ends), or chains
    k = 0
    while k < len(moves):
        last = k
        if chained(k):
            while chained(last):
                last += 1
            groups.append(_chain(moves, k, last, tolerance))
        else:
            while last + 1 < len(moves) and not chained(last + 1):
                last += 1
            groups.append(_straight_runs(moves[k:last + 1]))
        k = last + 1
    count = sum(g.chain.count if isinstance(g, _Chain) else len(g[0])
                for g in groups)
    if max_pieces is not None and count > max_pieces:
        raise ProgramError(None, f'{len(moves)} moves make a path of '
                           f'{count} pieces at least: more than '
                           f'{max_pieces}', TOO_LARGE)
    pieces, ends, slack = [], [], []
    for group in groups:
        if not isinstance(group, _Chain):
            pieces += group[0]
            ends += group[1]
            slack += [0.0] * len(group[0])
            continue
        made, made_slack = _chain_pieces(group.points, group.chain,
                                         group.feeds, group.lines)
        if slack:   # points merged into the chain's start, or all of it
            merged = group.chain.slack if not made else group.chain.slack[:1]
            slack[-1] = max(slack[-1], float(merged.max()))
        pieces += made
        ends += [group.modes[k - 1]
                 for k in group.chain.kept[group.chain.bounds[1:]]]
        slack += made_slack
    if not pieces:
        raise ProgramError(None, 'zero-length program: every point is '
                           'within the tolerance of the first', EMPTY)
    return _join(pieces, ends, slack, tolerance, start_line, len(moves))


def _fitted(move, tolerance):
    """Whether the junction after ``move`` is plain G64's: runs are fitted."""
    return move.mode == BLEND and move.tolerance is None and tolerance > 0.0


@dataclass
class _Chain:
    """A chain of lines of plain G64 (:mod:`chords`), its moves' fields."""

    points: Array       # (n + 1, 3) m
    chain: chords.Chain
    feeds: Array        # (n,) m/s
    lines: Array        # (n,)
    modes: list         # (n,) (mode, tolerance)


def _chain(moves, first, last, tolerance):
    """
    Analyse the chain of lines ``moves[first:last + 1]`` (:mod:`chords`).

    With the tangents of the moves before and after it where their
    junction with it is plain G64's.
    """
    run = moves[first:last + 1]
    points = np.array([run[0].start, *(m.end for m in run)])
    feeds = np.array([m.feed for m in run])
    before = after = None
    if first > 0 and _fitted(moves[first - 1], tolerance):
        previous = move_piece(moves[first - 1])
        before = previous.tangent(previous.length)
    if last + 1 < len(moves) and _fitted(run[-1], tolerance):
        after = move_piece(moves[last + 1]).tangent(0.0)
    return _Chain(points, chords.analyse(points, feeds, tolerance, before,
                                         after), feeds,
                  np.array([m.line for m in run]),
                  [(m.mode, m.tolerance) for m in run])


def _chain_pieces(points, chain, feeds, lines):
    """
    Return the pieces a chain of chords made and the slack after each.

    ``points`` (n + 1, 3) of its chords, ``feeds`` and ``lines`` (n,) of
    each; a piece's ``lines`` where each of its chords starts (by the
    share of the chords' length).
    """
    kept = chain.kept
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    along = np.concatenate(([0.0], np.cumsum(steps)))
    pieces, slack = [], []
    for first, last, control, _ in chain.pieces:
        a, b = kept[first], kept[last]
        if control is None:
            piece = line_piece(points[a], points[b], int(lines[a]), feeds[a])
        else:
            piece = bezier_piece(control, int(lines[a]), feeds[a])
        if b - a > 1:
            share = (along[a:b] - along[a]) / (along[b] - along[a])
            piece = replace(piece, lines=np.stack(
                (share * piece.length, lines[a:b]), 1))
        pieces.append(piece)
        slack.append(float(chain.slack[last]))
    return pieces, slack


def _straight_runs(moves):
    """
    Return the pieces of ``moves``, each straight run one line.

    Returns ``(pieces, ends)``: ``ends[k]`` the path control (mode,
    tolerance) of the move whose end is piece k's (it decides the
    junction after it). A run: lines of one feed, each within TANGENT of
    the run's first direction (so every junction of the run is within
    TANGENT times its length of the one line), no exact stop between.
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
            lines = np.array([(float((m.start - move.start) @ direction),
                               m.line) for m in run])
            pieces.append(line_piece(move.start, moves[last].end, move.line,
                                     move.feed, lines))
        ends.append((moves[last].mode, moves[last].tolerance))
        k = last + 1
    return pieces, ends


def _unit(vector):
    return vector / math.sqrt(float(vector @ vector))


def _join(pieces, ends, slack, tolerance, start_line, moves):
    """
    Return the path of ``pieces``, every junction decided and blended.

    ``ends[k]``: the path control (mode, tolerance) of piece k's end;
    ``slack[k]``: how far programmed points merged into the junction after
    piece k lie from it (m).
    """
    n = len(pieces)
    trim = np.zeros((n, 2))         # taken off each piece's start, end
    made = [None] * (n - 1)
    stops = np.zeros(n + 1, dtype=bool)
    stops[0] = stops[n] = True
    for k in range(n - 1):
        first, second = pieces[k], pieces[k + 1]
        turn = _turn(first.tangent(first.length), second.tangent(0.0))
        mode, own = ends[k]
        within = own if own is not None else tolerance
        vertex = within - slack[k] if own is None and mode == BLEND else None
        if mode == EXACT_STOP:
            stops[k + 1] = True
        elif turn <= TANGENT:
            continue
        elif mode == EXACT_PATH or (mode == BLEND and within <= 0):
            if turn <= KINK:
                made[k] = _blend(first, second, KINK_TOLERANCE, turn, None)
            stops[k + 1] = made[k] is None
        elif turn >= math.pi - ABOUT_TURN or (
                vertex is not None and vertex <= 0.0):
            stops[k + 1] = True
        else:
            made[k] = _blend(first, second, within, turn, vertex)
            stops[k + 1] = made[k] is None
        if made[k] is not None:
            trim[k, 1] = trim[k + 1, 0] = made[k][1]
    out = []
    out_stops = []
    for k, piece in enumerate(pieces):
        a, b = trim[k, 0], piece.length - trim[k, 1]
        if b - a > ZERO_LENGTH * 1e3:
            out.append(piece if a == 0.0 and b == piece.length
                       else piece.sub(a, b))
            out_stops.append(stops[k])
        if k < n - 1 and made[k] is not None:
            out.append(made[k][0])
            out_stops.append(False)
    out_stops.append(True)
    out_stops[0] = True
    return Path(tuple(out), np.array(out_stops), start_line, moves)


def _blend(first, second, tolerance, turn, vertex):
    """
    Return ``(piece, trim)``: the corner's blend (:mod:`blends`), or None.

    ``trim`` (m) is taken off the end of ``first`` and the start of
    ``second``, at most what each has room for (:meth:`Piece.room`).
    """
    room = min(first.room(False), second.room(True))
    line = first.line_at(first.length)
    feed = min(first.feed, second.feed)
    if first.kind == second.kind == 'helix' and \
            first.radius == second.radius == 0.0:
        arc = blends.line_blend(first, second, tolerance, turn, room, vertex)
        if arc is None:
            return None
        origin, e1, e3, radius, trim = arc
        return Piece('helix', radius * turn, line, feed, origin, e1, e3,
                     radius, turn, 0.0), trim
    curve = blends.curve_blend(first, second, tolerance, turn, room, vertex)
    if curve is None:
        return None
    return bezier_piece(curve[0], line, feed), curve[1]


def from_waypoints(points: Array, feeds: Optional[Array], lines: Sequence[int],
                   tolerance: float, max_pieces: Optional[int] = None
                   ) -> Path:
    """
    Return the path through ``points`` (n, 3) m: a smooth curve or lines.

    Segment k ends at ``points[k + 1]`` with that row's ``feeds`` (m/s, or
    none) and ``lines``; consecutive equal points are one; ``lines[0]``:
    the first point's line (0: not the program's). With ``tolerance``
    (m) above 0, a chain of chords as plain G64's (:mod:`chords`: runs
    followed as the curve they sample, within it of every point, corners
    blended within it); at 0, G stops at every corner. Raises
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
    keep = np.array(keep)
    chord_feeds = np.full(len(keep) - 1, math.inf) if feeds is None else \
        np.asarray(feeds, dtype=float)[keep[1:]]
    chord_lines = np.asarray(lines)[keep[1:]]
    if tolerance <= 0.0:
        _refuse_beyond(len(points), _corners(points[keep]) + 1, max_pieces)
        moves = [Move('line', points[i], points[k], int(line), feed,
                      EXACT_PATH) for i, k, line, feed in zip(
                          keep[:-1], keep[1:], chord_lines, chord_feeds)]
        return from_moves(moves, tolerance, lines[0] or None, max_pieces)
    chain = chords.analyse(points[keep], chord_feeds, tolerance)
    _refuse_beyond(len(points), chain.count + chain.corners, max_pieces)
    pieces, slack = _chain_pieces(points[keep], chain, chord_feeds,
                                  chord_lines)
    if not pieces:
        raise ProgramError(None, 'zero-length program: every waypoint is '
                           'within the tolerance of the first', EMPTY)
    return _join(pieces, [(BLEND, None)] * len(pieces), slack, tolerance,
                 lines[0] or None, len(keep) - 1)


def _refuse_beyond(points, count, max_pieces):
    if max_pieces is not None and count > max_pieces:
        raise ProgramError(None, f'{points} points make a path of {count} '
                           f'pieces at least (lines and corner blends): '
                           f'more than {max_pieces}', TOO_LARGE)


def _corners(points):
    """Return the corners of the polyline ``points``: turns above TANGENT."""
    step = np.diff(points, axis=0)
    unit = step / np.linalg.norm(step, axis=1)[:, None]
    cross = np.linalg.norm(_cross(unit[:-1], unit[1:]), axis=1)
    return int((np.arctan2(cross, (unit[:-1] * unit[1:]).sum(1))
                > TANGENT).sum())
