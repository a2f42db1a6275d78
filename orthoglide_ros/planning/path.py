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
length too, so ``|dp/dw|`` is 1 everywhere and G's velocity is continuous
wherever its speed is. The pieces and their formulas are :mod:`pieces`';
the moves, :mod:`moves`' (:func:`from_waypoints` makes them of
waypoints).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Optional, Sequence

import numpy as np

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import bezier, blends, chords
from orthoglide_ros.planning.moves import (BLEND, EMPTY, EXACT_PATH,
                                           EXACT_STOP, Line, Move,
                                           NUMBER_BOUND, ProgramError,
                                           TOO_LARGE, ZERO_LENGTH)
from orthoglide_ros.planning.pieces import (bezier_piece, columns, cross,
                                            helix_values, HelixPiece,
                                            line_piece, move_piece, Piece)

# Tangents within this angle (rad) join smoothly: passed at speed.
TANGENT = 1e-9
# Exact path (G61): a kink of at most this (rad, 0.06 deg) is CAM rounding,
# smoothed within KINK_TOLERANCE (m) and passed at speed.
KINK = 1e-3
KINK_TOLERANCE = 1e-6
# A turn nearer than this to an about-turn (rad) is not blended: G stops.
ABOUT_TURN = blends.ABOUT_TURN
# Points of Bezier pieces evaluated at once.
BEZIER_BLOCK = 4096


def _turn(t1, t2):
    """Angle (rad) between unit vectors: atan2, exact near 0 and pi."""
    a0, a1, a2 = t1.tolist()
    b0, b1, b2 = t2.tolist()
    return math.atan2(math.hypot(a1 * b2 - a2 * b1, a2 * b0 - a0 * b2,
                                 a0 * b1 - a1 * b0),
                      a0 * b0 + a1 * b1 + a2 * b2)


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

    pieces: tuple[Piece, ...]
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
            values = helix_values(table['origin'][k], table['e1'][k],
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
        return out[0], out[1], out[2]

    @property
    def table(self) -> dict[str, Array]:
        """Return the pieces' fields as arrays, made once (:func:`columns`)."""
        table = self.__dict__.get('_cached_table')
        if table is None:
            table = columns(self.pieces)
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
            isinstance(moves[k], Line) and isinstance(moves[k + 1], Line)
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
        if isinstance(move, Line):
            direction = _unit(move.end - move.start)
            while (last + 1 < len(moves) and moves[last].mode != EXACT_STOP
                   and isinstance(moves[last + 1], Line)
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
    if not out:
        raise ProgramError(None, 'zero-length program: no piece of its path '
                           f'is longer than {ZERO_LENGTH * 1e3:g} m', EMPTY)
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
    if isinstance(first, HelixPiece) and isinstance(second, HelixPiece) \
            and first.radius == second.radius == 0.0:
        arc = blends.line_blend(first, second, tolerance, turn, room, vertex)
        if arc is None:
            return None
        origin, e1, e3, radius, trim = arc
        return HelixPiece(radius * turn, line, feed, origin, e1, e3, radius,
                          turn, 0.0), trim
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
    kept = [0]
    for k in range(1, len(points)):
        step = points[k] - points[kept[-1]]
        if math.sqrt(float(step @ step)) > ZERO_LENGTH:
            kept.append(k)
    if len(kept) < 2:
        raise ProgramError(None, 'zero-length program: no waypoint is away '
                           'from the first', EMPTY)
    keep = np.array(kept)
    chord_feeds = np.full(len(keep) - 1, math.inf) if feeds is None else \
        np.asarray(feeds, dtype=float)[keep[1:]]
    chord_lines = np.asarray(lines)[keep[1:]]
    if tolerance <= 0.0:
        _refuse_beyond(len(points), _corners(points[keep]) + 1, max_pieces)
        moves = [Line(points[i], points[k], int(line), feed, EXACT_PATH,
                      None) for i, k, line, feed in zip(
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
    sines = np.linalg.norm(cross(unit[:-1], unit[1:]), axis=1)
    return int((np.arctan2(sines, (unit[:-1] * unit[1:]).sum(1))
                > TANGENT).sum())
