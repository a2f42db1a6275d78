"""
TOPP-RA's reachability passes over a grid's stages (Pham and Pham 2018).

Each stage ``i`` (gridpoint ``i`` to ``i + 1``, ``delta_i`` apart along
the path) has the rows of both its gridpoints (the interpolation scheme:
at ``i + 1``, ``x + 2 delta u`` for ``x``): ``low <= alpha u + beta x <=
high`` per row, ``x = sdot^2``, ``u = sddot``. :func:`passes` runs the
backward pass (the largest controllable ``x`` of each gridpoint, each
stage's one-dimensional programme solved in closed form: ``u`` is bounded
by affine functions of ``x``) and the forward pass (the largest ``u``
keeping the next ``x`` controllable). The rows come as
:class:`StageRows` (:class:`constraints.Rows`: the robot's dynamics), so
that the passes know nothing of the robot, as toppra's solver wrapper and
reachability algorithm know nothing of its constraints. The rows are made
STAGE_BLOCK stages at a time and the loops run on Python floats
LIST_BLOCK stages at a time, so the memory is a few arrays of the grid's
size.
"""

from typing import NamedTuple, Protocol

import numpy as np

from orthoglide_ros.model.types import Array

# |coefficient of u| below this: a row bounds x alone.
U_ZERO = 1e-10
# x (m^2/s^2) where nothing else bounds it (G at 1e6 m/s: never reached).
X_BIG = 1e12
# Stages whose rows are made at once; stages made Python lists at once.
STAGE_BLOCK = 16_384
LIST_BLOCK = 8192


class StageRows(Protocol):
    """
    The constraints of a grid's gridpoints, as the passes read them.

    ``low <= alpha u + beta x <= high`` per row: ``alpha``, ``beta`` (M,
    k), ``bounds(friction, part)`` ``(low, high)`` of the gridpoints
    ``part`` with ``friction`` (N, (M, 3)); ``cap`` and ``cap_extra``
    (M,): bounds on ``x`` alone.
    """

    alpha: Array
    beta: Array
    cap: Array
    cap_extra: Array

    def bounds(self, friction: Array, part: slice) -> tuple[Array, Array]:
        """Return ``(low, high)`` of the gridpoints ``part``."""


class StageFailure(Exception):
    """A stage without a solution on the first plan: the grid is refined."""


class Unbounded(Exception):
    """Nothing bounds G's acceleration on ``stage``."""

    def __init__(self, stage: int) -> None:
        """Keep the stage (from its first gridpoint, from 0)."""
        super().__init__(stage)
        self.stage = stage


def passes(rows: StageRows, delta: Array, friction: Array,
           first: bool) -> tuple[Array, Array]:
    """
    Run the backward and forward passes: ``x`` (M,) and ``u`` (M - 1,).

    ``rows``: the gridpoints' constraints (:class:`StageRows`); ``delta``
    (M - 1,) m, 0 at a junction; ``friction`` (N, (M, 3)) at each
    gridpoint. ``first``: the first plan on this grid, where a stage
    without a solution means the grid is too coarse (:class:`StageFailure`);
    later (friction at other speeds) such a stage stops G. Raises
    :class:`Unbounded` where nothing bounds ``u``.
    """
    cap = np.minimum(rows.cap, rows.cap_extra)
    stages = _stages(rows, friction, delta, cap)
    mvc = _settled(stages, first)
    bound = _backward(delta, cap, mvc, stages.slope, stages.bottom)
    return _forward(delta, bound, stages.top, stages.slope, stages.bottom)


class _Stages(NamedTuple):
    """
    Each stage's programme in ``(u, x)``, and where it has no solution.

    Per row ``bottom + slope x <= u <= top + slope x`` ((M - 1, k));
    ``mvc`` (M - 1,): the largest ``x`` some ``u`` meets (negative: none);
    ``failed``: the moving stages no ``x >= 0`` meets.
    """

    top: Array
    slope: Array
    bottom: Array
    mvc: Array
    failed: Array


def _used(rows, friction):
    """Return the columns of the rows some gridpoint bounds."""
    low, high = rows.bounds(friction, slice(None))
    return np.nonzero((np.isfinite(high) | np.isfinite(low)).any(0))[0]


def _stages(rows, friction, delta, cap):
    """
    Return every stage's programme (:class:`_Stages`), STAGE_BLOCK at once.

    Its rows from both its gridpoints (:func:`_stage_rows`), its largest
    feasible ``x`` (:func:`_largest_feasible`) within ``cap`` (M,) and the
    bounds of rows on ``x`` alone. Raises :class:`Unbounded` on the first
    moving stage where nothing bounds ``u`` from above or below.
    """
    used = _used(rows, friction)
    count = len(delta)
    top, slope, bottom = (np.empty((count, 2 * len(used)))
                          for _ in range(3))
    mvc = np.empty(count)
    failed = np.zeros(count, dtype=bool)
    for begin in range(0, count, STAGE_BLOCK):
        part = slice(begin, min(count, begin + STAGE_BLOCK))
        blocked, x_alone = _stage_rows(rows, friction, used, delta, part,
                                       top, slope, bottom)
        free = (delta[part] > 0.0) & (np.isinf(top[part]).all(1)
                                      | np.isinf(bottom[part]).all(1))
        if free.any():
            raise Unbounded(begin + int(np.argmax(free)))
        mvc[part] = _largest_feasible(top[part], slope[part], bottom[part],
                                      slope[part], np.minimum(cap[part],
                                                              x_alone))
        failed[part] = ((mvc[part] < 0.0) | blocked) & (delta[part] > 0.0)
    return _Stages(top, slope, bottom, mvc, failed)


def _settled(stages, first):
    """
    Return each stage's largest feasible ``x``, a failed stage's 0.

    On the first plan a failed stage refines the grid
    (:class:`StageFailure`); later G stops there (``x`` 0).
    """
    mvc = stages.mvc
    if stages.failed.any():
        if first:
            raise StageFailure()
        mvc[stages.failed] = 0.0
    return mvc


def _stage_rows(rows, friction, used, delta, part, top, slope, bottom):
    """
    Fill ``top``, ``slope``, ``bottom`` of the stages ``part``.

    Per row, ``bottom + slope x <= u <= top + slope x``; a row whose
    ``alpha`` is 0 bounds ``x`` alone. Returns ``(blocked, x_alone)``:
    stages no ``x`` meets, the bound on ``x`` of such rows.
    """
    ends = slice(part.start, part.stop + 1)
    low, high = (v[:, used] for v in rows.bounds(friction, ends))
    twice = 2.0 * delta[part, None]
    alpha, beta = rows.alpha[ends][:, used], rows.beta[ends][:, used]
    alpha = np.hstack((alpha[:-1], alpha[1:] + twice * beta[1:]))
    beta = np.hstack((beta[:-1], beta[1:]))
    low = np.hstack((low[:-1], low[1:]))
    high = np.hstack((high[:-1], high[1:]))
    bounded = np.isfinite(high) | np.isfinite(low)
    bounded[delta[part] == 0.0] = False
    positive = (alpha > U_ZERO) & bounded
    negative = (alpha < -U_ZERO) & bounded
    alone = bounded & ~(positive | negative)
    with np.errstate(divide='ignore', invalid='ignore'):
        # alpha > 0: u <= (high - beta x) / alpha, u >= (low - beta x) /
        # alpha; alpha < 0 the other way round.
        slope[part] = np.where(positive | negative, -beta / alpha, 0.0)
        top[part] = np.where(positive, high / alpha,
                             np.where(negative, low / alpha, np.inf))
        bottom[part] = np.where(positive, low / alpha,
                                np.where(negative, high / alpha, -np.inf))
        x_alone = np.where(alone & (beta > 0.0), high / beta, np.inf)
        x_alone = np.minimum(x_alone, np.where(alone & (beta < 0.0),
                                               low / beta, np.inf))
        blocked = (alone & ((high < 0.0) | (low > 0.0))
                   & ((beta == 0.0) | (high < 0.0) & (beta <= 0.0)
                      | (low > 0.0) & (beta >= 0.0))).any(1)
    top[part][np.isnan(top[part])] = np.inf
    bottom[part][np.isnan(bottom[part])] = -np.inf
    return blocked, x_alone.min(1, initial=np.inf)


def _largest_feasible(h, n, low, m, start):
    """
    Return the largest ``x`` of each stage where some ``u`` meets every row.

    ``u <= h + n x`` and ``u >= low + m x`` per row: the gap ``min(h + n
    x) - max(low + m x)`` is concave and piecewise linear in ``x``, so
    Newton's method from ``start`` (an upper bound) reaches its last zero
    in finitely many steps. -1 where no ``x >= 0`` has a ``u``.
    """
    x = np.minimum(start, X_BIG)
    rows = np.arange(len(x))
    active = np.ones(len(x), dtype=bool)
    for _ in range(200):
        hx = h + n * x[:, None]
        j = np.argmin(hx, 1)
        lx = low + m * x[:, None]
        k = np.argmax(lx, 1)
        top, bottom = hx[rows, j], lx[rows, k]
        with np.errstate(invalid='ignore'):
            gap = top - bottom
            active &= gap < -1e-12 * (np.abs(top) + np.abs(bottom))
        if not active.any():
            return x
        slope = n[rows, j] - m[rows, k]
        with np.errstate(divide='ignore', invalid='ignore'):
            target = x - gap / slope
        # Concave: where the gap rises to the left, or its tangent's zero
        # is below 0, no x in [0, x] has a u.
        failed = active & ((slope >= 0.0) | (target < 0.0))
        # A step below the rounding of x: there (a hair below, to be on
        # the feasible side).
        settled = active & ~failed & (x - target <= 1e-12 * x)
        x = np.where(active, target, x)
        x[settled] *= 1.0 - 1e-12
        x[failed] = -1.0
        active &= ~(failed | settled)
    return x


def _backward(delta, cap, mvc, slope, bottom):
    """
    Return the largest controllable ``x`` of every gridpoint, from the end.

    From ``k_{i+1}``: ``x_i + 2 delta u <= k_{i+1}`` with ``u >= bottom +
    slope x_i`` per row gives ``x_i <= (k_{i+1} - 2 delta bottom) / (1 + 2
    delta slope)``. A loop of Python floats (faster than numpy's per
    stage), LIST_BLOCK stages of the arrays at a time.
    """
    count = len(delta)
    k = np.zeros(count + 1)
    after = 0.0
    for end in range(count, 0, -LIST_BLOCK):
        part = slice(max(0, end - LIST_BLOCK), end)
        twice = 2.0 * delta[part, None]
        with np.errstate(divide='ignore', invalid='ignore'):
            rate = 1.0 + twice * slope[part]
            valid = np.isfinite(bottom[part]) & (rate > 0.0)
            shifts = np.where(valid, twice * bottom[part], -np.inf).tolist()
            scales = np.where(valid, 1.0 / rate, 1.0).tolist()
        d, c, m = delta[part].tolist(), cap[part].tolist(), mvc[part].tolist()
        out = [0.0] * len(d)
        for i in range(len(d) - 1, -1, -1):
            if d[i] == 0.0:
                after = min(after, c[i])
            else:
                best = m[i]
                for a, b in zip(shifts[i], scales[i]):
                    value = (after - a) * b
                    if value < best:
                        best = value
                after = best if best > 0.0 else 0.0
            out[i] = after
        k[part] = out
    return k


def _forward(delta, k, top, slope, bottom):
    """
    From rest, the largest ``u`` of each stage keeping ``x`` controllable.

    Where G is on the controllable bound ``k[i]``, it stays on it if the
    largest acceleration there reaches ``k[i + 1]`` (the backward pass made
    sure the smallest does not overshoot it): known for LIST_BLOCK stages
    at once, the rest a loop of Python floats.
    """
    count = len(delta)
    x = np.zeros(count + 1)
    u = np.zeros(count)
    xi = 0.0
    for begin in range(0, count, LIST_BLOCK):
        part = slice(begin, min(count, begin + LIST_BLOCK))
        bound = k[begin:part.stop + 1]
        with np.errstate(invalid='ignore'):
            fastest = (top[part] + slope[part] * bound[:-1, None]).min(1)
            follows = (bound[:-1] + 2.0 * delta[part] * fastest
                       >= bound[1:]) & (delta[part] > 0.0)
        d, f, kk = delta[part].tolist(), follows.tolist(), bound.tolist()
        tops, slopes, bottoms = (a[part].tolist()
                                 for a in (top, slope, bottom))
        xs, us = [0.0] * len(d), [0.0] * len(d)
        for i in range(len(d)):
            if d[i] == 0.0:
                xi = xs[i] = min(xi, kk[i + 1])
                continue
            twice = 2.0 * d[i]
            if f[i] and xi == kk[i]:
                us[i] = (kk[i + 1] - xi) / twice
                xi = xs[i] = kk[i + 1]
                continue
            rows = list(zip(tops[i], slopes[i], bottoms[i]))
            ui = min(min(t + m * xi for t, m, _ in rows),
                     (kk[i + 1] - xi) / twice)
            least = max(b + m * xi for _, m, b in rows)
            if ui < least:
                ui = least
            following = min(max(xi + twice * ui, 0.0), kk[i + 1])
            us[i] = (following - xi) / twice
            xi = xs[i] = following
        x[part.start + 1:part.stop + 1] = xs
        u[part] = us
    return x, u
