"""
Runs of chords followed as the curve they sample.

CAM writes a curve as a run of short G1 chords. Under plain ``G64`` (and
for CSV waypoints and a ``nav_msgs/Path``) the planner follows the curve,
not the chords, so that G keeps the curve's speed instead of slowing at
every vertex. As Siemens' COMPCAD does (the points smoothed within the
tolerance, then a spline through them), :func:`analyse` takes a chain of
chords (consecutive lines in that mode) and decides, in this order:

1. **Points nearer each other than half the tolerance are one**
   (:func:`decimate`): each dropped point is within ``slack`` (< tol / 2)
   of the point kept for it; where the feed changes a point is kept.
2. **Collinear chords are one line** (within TANGENT of the line's first
   direction, one feed), as elsewhere.
3. **Where a run breaks** (:func:`breaks`): at a corner, a turn of at
   least CORNER_ANGLE, or of at least CORNER_FLOOR and more than
   CORNER_RATIO times each neighbouring turn (a turn beside a chain's end
   counts its neighbour outside the chain, a missing one 0); where one
   chord is more than LONG_RATIO times longer than the next (a long move
   beside short ones stays a line); where the feed changes; around a chord
   whose curve would leave it by more than CHORD_SAGITTA (``h theta / 8``
   from its turns: a coarse polygon, not a sampled curve).
4. **A run** (at least MIN_RUN chords between breaks) becomes one smooth
   curve: its inner points smoothed within ``min(SMOOTH_SHARE tol, tol -
   slack)`` (:func:`smooth`, the largest smoothing that keeps every point
   within it: rounded coordinates stop bending the curve), then a C2
   cubic spline through them by chord length (scipy's ``CubicSpline``),
   its ends the run's end points exactly. An end that is not a corner is
   tangent to what it meets (the line beside it, the arc or spline before
   or after the chain, or the circle through the vertex and its neighbours
   where two runs meet), so that it is passed at speed; other ends are
   not-a-knot. A run whose curve is not regular (its speed below
   SPEED_SHARE of its chord's) or bulges (beyond BULGE_SHARE of a chord or
   2 CHORD_SAGITTA) stays lines.
5. The rest (short runs, long moves) stays lines, their corners blended
   by the path as before.

Every programmed point is within the tolerance of the curve, by
construction: a run's point within ``budget`` of the point the spline
passes through, a dropped point within ``slack`` more; a corner blended
within ``tol - slack`` of its vertex (the path's blends). Time and memory
are linear in the points (banded systems, one spline a run). scipy is
imported where used: a path without runs does not load it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Optional

import numpy as np
import numpy.typing as npt

from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import bezier
from orthoglide_ros.planning.moves import ZERO_LENGTH

# Turns that make a corner (rad), see the module's docstring.
CORNER_ANGLE = math.radians(30.0)
CORNER_FLOOR = math.radians(5.0)
CORNER_RATIO = 4.0
# A chord this many times longer than the next breaks a run.
LONG_RATIO = 4.0
# A chord whose curve would leave it by more (m) is not a sampled curve's.
CHORD_SAGITTA = 1e-4
# Fewest chords a run has.
MIN_RUN = 3
# Points nearer than this share of the tolerance are one; the smoothing
# moves a point by at most this share of it.
DROP_SHARE = 0.5
SMOOTH_SHARE = 0.5
# Smoothing: log10 of its weight (no unit), bisected this many times
# between these bounds.
SMOOTH_RANGE = (-3.0, 6.0)
SMOOTH_STEPS = 10
# A run's curve is refused (the run stays lines) where a span's speed
# dips below this share of its chord's length or it leaves its chord by
# more than this share of it.
SPEED_SHARE = 0.1
BULGE_SHARE = 0.25
# Tangents within this angle (rad) are one direction, a turn nearer an
# about-turn stops (path's TANGENT, ABOUT_TURN).
TANGENT = 1e-9
ABOUT_TURN = 1e-6


@dataclass
class Chain:
    """
    What :func:`analyse` made of a chain of chords.

    ``kept`` (k,): the indices of the points kept, the first and the last
    among them; ``slack`` (k,): the largest distance (m) of a point dropped
    for each; ``bounds`` (p + 1,): where each of its ``p`` pieces starts
    and the last ends, over the kept points; ``curves``: the pieces that
    are a run's curve, by their index: its spans' control points (m, 4,
    3) and its total turning (rad), the others lines; ``corners``: the
    junctions between two lines surely blended (a count, for the bound on
    the pieces).
    """

    kept: npt.NDArray[np.intp]
    slack: Array
    bounds: npt.NDArray[np.intp] = field(default_factory=lambda: np.zeros(1, dtype=int))
    curves: dict = field(default_factory=dict)
    corners: int = 0

    @property
    def count(self) -> int:
        """Return how many pieces the chain makes."""
        return len(self.bounds) - 1

    @property
    def pieces(self) -> list:
        """Return ``(first, last, control, turning)`` of each piece."""
        return [(a, b, *self.curves.get(k, (None, 0.0))) for k, (a, b) in
                enumerate(zip(self.bounds[:-1].tolist(),
                              self.bounds[1:].tolist()))]


def analyse(points: Array, feeds: Array, tolerance: float,
            before: Optional[Array] = None,
            after: Optional[Array] = None) -> Chain:
    """
    Return what the chain of chords through ``points`` (n + 1, 3) becomes.

    ``feeds`` (n,): each chord's (m/s); ``tolerance`` (m) above 0;
    ``before``, ``after``: the unit tangents of what the chain meets at its
    start and end where that junction may be passed smoothly (None: a
    stop, a path's end, another mode).
    """
    kept, slack = decimate(points, feeds, DROP_SHARE * tolerance)
    q = points[kept]
    if len(q) == 2 and not np.linalg.norm(q[1] - q[0]) > 0.0:
        return Chain(kept, slack)       # a loop within the tolerance
    chord_feeds = feeds[kept[:-1]]
    vertex = _straight(q, chord_feeds)
    ends = q[vertex]
    steps = np.diff(ends, axis=0)
    lengths = np.linalg.norm(steps, axis=1)
    units = steps / lengths[:, None]
    turns = np.zeros(len(vertex))
    turns[1:-1] = _turns(units[:-1], units[1:])
    if before is not None:
        turns[0] = _turns(before[None], units[:1])[0]
    if after is not None:
        turns[-1] = _turns(units[-1:], after[None])[0]
    corner, broken = breaks(turns, lengths, chord_feeds[vertex[:-1]],
                            before is not None, after is not None)
    bounds = np.flatnonzero(broken)
    runs = [(a, b) for a, b in zip(bounds[:-1].tolist(),
                                   bounds[1:].tolist()) if b - a >= MIN_RUN]
    in_run = np.zeros(len(lengths), dtype=bool)
    for a, b in runs:
        in_run[a:b] = True
    fitted = {}
    for a, b in runs:
        start = _end_tangent(a, corner, in_run, ends, units, before, True)
        end = _end_tangent(b, corner, in_run, ends, units, after, False)
        curve = _fit(q[vertex[a]:vertex[b] + 1],
                     slack[vertex[a]:vertex[b] + 1], tolerance, start, end)
        if curve is not None:
            fitted[a] = (b, curve)
    # Every line's start, but those within a fitted run.
    line = np.ones(len(lengths), dtype=bool)
    for a, (b, _) in fitted.items():
        line[a + 1:b] = False
        line[a] = False
    starts = np.flatnonzero(line | np.isin(np.arange(len(lengths)),
                                           list(fitted)))
    chain = Chain(kept, slack, vertex[np.append(starts, len(lengths))])
    chain.curves = {int(np.searchsorted(starts, a)): curve
                    for a, (_, curve) in fitted.items()}
    # Junctions of two lines (vertex v between lines v - 1 and v) blended.
    both = line[1:] & line[:-1]
    v = np.flatnonzero(both) + 1
    within = tolerance - slack[vertex[v]]
    with np.errstate(divide='ignore'):
        trim = np.minimum(0.5 * np.minimum(lengths[v - 1], lengths[v]),
                          within / np.tan(0.25 * turns[v]))
    blended = (turns[v] > TANGENT) & (turns[v] < math.pi - ABOUT_TURN) & (
        within > 0.0) & (trim > ZERO_LENGTH * 1e3)
    chain.corners = int(blended.sum())
    return chain


def decimate(points: Array, feeds: Array, distance: float
             ) -> tuple[npt.NDArray[np.intp], Array]:
    """
    Return the points kept, as indices, and each one's ``slack`` (m).

    Greedy along the chain: a point nearer than ``distance`` to the last
    point kept is dropped (its ``slack``: the largest distance of a point
    dropped for it), unless the feed changes there; the first and the last
    are kept, the last in place of a point kept just before it.
    """
    n = len(points) - 1
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    if steps.min(initial=math.inf) >= distance:
        return np.arange(n + 1), np.zeros(n + 1)
    rows = points.tolist()
    kept, slack, owned = [0], [0.0], [[]]
    for i in range(1, n):
        gap = math.dist(rows[i], rows[kept[-1]])
        if gap < distance and feeds[i - 1] == feeds[i]:
            slack[-1] = max(slack[-1], gap)
            owned[-1].append(i)
        else:
            kept.append(i)
            slack.append(0.0)
            owned.append([])
    last = rows[n]
    if len(kept) > 1 and math.dist(rows[kept[-1]], last) < distance \
            and feeds[kept[-1] - 1] == feeds[n - 1]:
        dropped = [kept.pop(), *owned.pop()]
        slack.pop()
        end = max(math.dist(rows[i], last) for i in dropped)
    else:
        end = 0.0
    kept.append(n)
    slack.append(end)
    return np.array(kept), np.array(slack)


def _straight(points, feeds):
    """
    Return the indices of ``points`` that end a line: collinear chords joined.

    Consecutive chords of one feed, each within TANGENT of the line's first
    direction, are one line.
    """
    steps = np.diff(points, axis=0)
    units = steps / np.linalg.norm(steps, axis=1)[:, None]
    joins = np.zeros(len(units), dtype=bool)       # with the chord before
    joins[1:] = (_turns(units[:-1], units[1:]) <= TANGENT) & (
        feeds[1:] == feeds[:-1])
    starts = np.flatnonzero(~joins)
    more = []
    for k in starts[joins[np.minimum(starts + 1, len(units) - 1)]]:
        stop = k + 1
        while stop < len(units) and joins[stop]:
            stop += 1
        while stop > k + 1:     # against the line's first direction
            off = _turns(np.broadcast_to(units[k], (stop - k - 1, 3)),
                         units[k + 1:stop]) > TANGENT
            if not off.any():
                break
            k = k + 1 + int(np.argmax(off))
            more.append(k)
    return np.unique(np.concatenate((starts, more, [len(units)]))
                     ).astype(int)


def _turns(first, second):
    """Return the angles (rad) between unit vectors (k, 3): atan2, exact."""
    cross = np.cross(first, second)
    return np.arctan2(np.linalg.norm(cross, axis=1),
                      (first * second).sum(1))


def breaks(turns: Array, lengths: Array, feeds: Array, before: bool,
           after: bool) -> tuple[npt.NDArray[np.bool_],
                                 npt.NDArray[np.bool_]]:
    """
    Return where a chain's lines make a corner and where a run breaks.

    ``turns`` (k + 1,) at each vertex of ``k`` lines (the ends' with what
    the chain meets, 0 where it meets nothing: ``before``, ``after``
    False), ``lengths`` and ``feeds`` (k,). Returns ``(corner, broken)``,
    (k + 1,) bool each; the chain's ends always break.
    """
    near = np.zeros(len(turns) + 2)
    near[1:-1] = turns
    neighbours = np.maximum(near[:-2], near[2:])
    corner = (turns >= CORNER_ANGLE) | (
        (turns >= CORNER_FLOOR) & (turns > CORNER_RATIO * neighbours))
    corner[0] &= before
    corner[-1] &= after
    broken = corner.copy()
    broken[0] = broken[-1] = True
    ratio = lengths[1:] / lengths[:-1]
    broken[1:-1] |= (ratio > LONG_RATIO) | (ratio < 1.0 / LONG_RATIO) | (
        feeds[1:] != feeds[:-1])
    smooth = np.where(corner, 0.0, turns)
    sagitta = lengths * np.maximum(smooth[:-1], smooth[1:]) / 8.0
    coarse = sagitta > CHORD_SAGITTA
    broken[:-1] |= coarse
    broken[1:] |= coarse
    return corner, broken


def _end_tangent(v, corner, in_run, ends, units, outside, start):
    """
    Return the unit tangent a run must have at its end vertex ``v``, or None.

    None at a corner and where the chain meets nothing smooth; else the
    tangent of what is beside it: the line before (after) it, ``outside``
    at the chain's end, or, between two runs, the circle through ``v`` and
    its neighbours.
    """
    last = len(units)
    if corner[v]:
        return None
    if v == 0 or v == last:
        return outside
    if not (in_run[v - 1] if start else in_run[v]):
        return units[v - 1] if start else units[v]
    before = ends[v] - ends[v - 1]
    after = ends[v + 1] - ends[v]
    a, b = np.linalg.norm(before), np.linalg.norm(after)
    tangent = before / a * b + after / b * a
    return tangent / np.linalg.norm(tangent)


def _fit(points, slack, tolerance, start, end):
    """
    Return ``(control, turning)`` of a run's curve, or None (it stays lines).

    ``points`` (N + 1, 3), ``slack`` (N + 1,) of each; ``start``, ``end``:
    the unit tangents at its ends, or None (not-a-knot).
    """
    from scipy.interpolate import CubicSpline     # where used: 23 MB
    budget = np.minimum(SMOOTH_SHARE * tolerance, tolerance - slack)
    budget[[0, -1]] = 0.0
    q = smooth(points, budget, start, end)
    steps = np.linalg.norm(np.diff(q, axis=0), axis=1)
    u = np.concatenate(([0.0], np.cumsum(steps)))
    spline = CubicSpline(u, q, axis=0, bc_type=(
        'not-a-knot' if start is None else (1, start),
        'not-a-knot' if end is None else (1, end)))
    d, c, b = spline.c[3], spline.c[2], spline.c[1]
    h = steps[:, None]
    control = np.stack((q[:-1], d + c * h / 3.0,
                        d + 2.0 * c * h / 3.0 + b * h * h / 3.0, q[1:]), 1)
    least, _ = bezier.least_speed(control)
    bulge = bezier.bulge(control)
    if (least < SPEED_SHARE * steps).any() or (
            bulge > np.minimum(BULGE_SHARE * steps,
                               2.0 * CHORD_SAGITTA)).any():
        return None
    return control, float(bezier.turning(control).sum())


def smooth(points: Array, budget: Array, start: Optional[Array] = None,
           end: Optional[Array] = None) -> Array:
    """
    Return ``points`` (N + 1, 3) smoothed, each within its ``budget`` (m).

    The minimiser of ``sum |q_i - p_i|^2 + lambda sum |D_i q|^2``, ``D_i``
    the third difference at point ``i`` for its spacing (:func:`_penalty`):
    a curve of constant curvature keeps its shape to its ends, a zig-zag of
    the points is damped by ``1 + 64 lambda`` (``lambda`` has no unit); the
    ends fixed, a tangent ``start`` (``end``) given as the first (last)
    curvature. A banded system (scipy's ``solveh_banded``) for each
    ``lambda``, the largest (by bisection on its logarithm over
    SMOOTH_RANGE) that keeps every point within its budget and no chord
    shorter than half its length; ``points`` where none does.
    """
    from scipy.linalg import solveh_banded       # where used: 29 MB
    n = len(points) - 1
    if n < 3:
        return points
    h = np.linalg.norm(np.diff(points, axis=0), axis=1)
    matrix, right = _penalty(points, h, start, end)
    best = points

    def solve(logarithm):
        lam = 10.0 ** logarithm
        banded = lam * matrix
        banded[-1] += 1.0
        inner = solveh_banded(banded, points[1:-1] - lam * right,
                              check_finite=False)
        q = np.vstack((points[:1], inner, points[-1:]))
        moved = np.linalg.norm(q - points, axis=1)
        steps = np.linalg.norm(np.diff(q, axis=0), axis=1)
        fits = np.isfinite(q).all() and (moved <= budget).all() and (
            steps >= 0.5 * h).all()
        return q, fits

    low, high = SMOOTH_RANGE
    for _ in range(SMOOTH_STEPS):
        middle = 0.5 * (low + high)
        q, fits = solve(middle)
        if fits:
            best, low = q, middle
        else:
            high = middle
    return best


def _penalty(points, h, start, end):
    """
    Return the smoothing's ``sum D^T D`` (banded, upper) and its constants.

    Over the inner points 1..N-1: ``(4, N - 1)`` for ``solveh_banded`` and
    the ``(N - 1, 3)`` term the fixed ends and tangents add. With ``S_i``
    the second divided difference at point ``i`` (its curvature vector,
    exact for any spacing), ``D_i = hbar^2 (S_i+1 - S_i)``, ``hbar`` the
    mean of the chords it spans: a third difference; at a tangent end,
    ``S_0 = 2 ((q_1 - q_0) / h_0 - t) / h_0`` (``S_N`` likewise).
    """
    n = len(points) - 1
    total = h[:-1] + h[1:]
    # S_i = a q_i-1 + b q_i + c q_i+1, i = 1..N-1
    a, c = 2.0 / (total * h[:-1]), 2.0 / (total * h[1:])
    b = -a - c
    scale = ((h[:-2] + h[1:-1] + h[2:]) / 3.0) ** 2
    coefficient = np.stack((-a[:-1], a[1:] - b[:-1], b[1:] - c[:-1], c[1:]),
                           1) * scale[:, None]
    first = np.arange(0, n - 2)         # the stencil's first point
    constant = np.zeros((n - 2, 3))
    rows = [(coefficient, first, constant)]
    if start is not None:
        k = 2.0 / h[0] ** 2
        rows.append((np.array([[a[0] + k, b[0] - k, c[0], 0.0]])
                     * (0.5 * total[0]) ** 2, np.array([0]),
                     (2.0 / h[0] * start * (0.5 * total[0]) ** 2)[None]))
    if end is not None:
        k = 2.0 / h[-1] ** 2
        rows.append((np.array([[0.0, -a[-1], k - b[-1], -k - c[-1]]])
                     * (0.5 * total[-1]) ** 2, np.array([n - 3]),
                     (2.0 / h[-1] * end * (0.5 * total[-1]) ** 2)[None]))
    coefficient = np.vstack([r[0] for r in rows])
    first = np.concatenate([r[1] for r in rows])
    constant = np.vstack([r[2] for r in rows])
    index = first[:, None] + np.arange(4)               # points
    fixed = (index == 0) | (index == n)
    constant = constant + (np.where(fixed, coefficient, 0.0)[..., None]
                           * points[index]).sum(1)
    column = index - 1                                  # unknowns
    c = np.where(fixed, 0.0, coefficient)
    column = np.where(fixed, 0, column)
    unknown = n - 1
    banded = np.zeros((4, unknown))
    right = np.zeros((unknown, 3))
    for i in range(4):
        np.add.at(right, column[:, i], c[:, i, None] * constant)
        for j in range(i, 4):
            np.add.at(banded[3 - (j - i)], column[:, j], c[:, i] * c[:, j])
    return banded, right
