"""
An independent time-optimal solver: phase-plane integration on a fine grid.

The benchmarks' and the acceptance's second opinion on the planner
(:mod:`orthoglide_ros.planning.parametrization`), sharing none of its code:
along ``s`` each row is ``low <= a u + b x + c + g(x) <= high`` with ``x =
sdot^2``, ``u = sddot`` and ``g`` any function of the speed (friction);
the classic numerical integration (Bobrow, Dubowsky and Gibson 1985;
Pfeiffer and Johanni 1987) from rest to rest: the largest ``x`` where a
``u`` exists (bisection), a backward pass of the largest deceleration from
the end, a forward pass of the largest acceleration from the start, both
explicit in ``s`` on a grid fine enough that its error is below the
comparisons' (it converges as the step). Also a CNC-style kinematic
planner's rows: one Cartesian acceleration limit per axis.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np


@dataclass
class Rows:
    """
    The constraints at each gridpoint: ``(n, k)`` arrays and the grid.

    ``a``, ``b``, ``c``, ``low``, ``high``; ``extra(x)``: ``(n, k)`` of the
    speed-dependent term at ``x`` per gridpoint (None: none); ``cap``
    (n,): the bounds on ``x`` alone (0 where G must rest); ``s`` (n,):
    the gridpoints, a junction twice.
    """

    s: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    low: np.ndarray
    high: np.ndarray
    cap: np.ndarray
    extra: Optional[Callable[[np.ndarray, np.ndarray], np.ndarray]] = None


def _u_bounds(rows, i, x):
    """Return the smallest and largest ``u`` at gridpoints ``i`` and ``x``."""
    a, b, c = rows.a[i], rows.b[i], rows.c[i]
    extra = 0.0 if rows.extra is None else rows.extra(i, x)
    rest = b * np.asarray(x)[..., None] + c + extra
    with np.errstate(divide='ignore', invalid='ignore'):
        one = (rows.low[i] - rest) / a
        two = (rows.high[i] - rest) / a
    lower = np.where(a > 0.0, one, np.where(a < 0.0, two, -np.inf))
    upper = np.where(a > 0.0, two, np.where(a < 0.0, one, np.inf))
    still = (a == 0.0) & ((rest < rows.low[i]) | (rest > rows.high[i]))
    lower = np.where(still, np.inf, lower)
    return np.nanmax(lower, -1), np.nanmin(upper, -1)


def optimal_profile(rows: Rows) -> np.ndarray:
    """Return the time-optimal ``x = sdot^2`` at each gridpoint, rest to rest."""
    n = len(rows.s)
    every = np.arange(n)
    # The largest x with a u, by bisection on every gridpoint at once.
    top = np.minimum(rows.cap, 1e8)
    low, high = np.zeros(n), top.copy()
    for _ in range(60):
        middle = 0.5 * (low + high)
        fits = _feasible(rows, every, middle)
        low = np.where(fits, middle, low)
        high = np.where(fits, high, middle)
    limit = np.where(_feasible(rows, every, top), top, low)
    delta = np.diff(rows.s)
    back = limit.copy()
    back[-1] = 0.0
    for i in range(n - 2, -1, -1):
        if delta[i] == 0.0:
            back[i] = min(back[i], back[i + 1])
            continue
        slowest, _ = _u_bounds(rows, i + 1, back[i + 1])
        back[i] = min(back[i], max(back[i + 1] - 2.0 * delta[i] * slowest,
                                   0.0))
    x = np.zeros(n)
    for i in range(n - 1):
        if delta[i] == 0.0:
            x[i + 1] = min(x[i], back[i + 1])
            continue
        _, fastest = _u_bounds(rows, i, x[i])
        x[i + 1] = min(back[i + 1], max(x[i] + 2.0 * delta[i] * fastest,
                                        0.0))
    return x


def optimal_duration(rows: Rows) -> float:
    """
    Return the time-optimal rest-to-rest duration (s) along the rows.

    Raises ValueError where G cannot leave rest.
    """
    x = optimal_profile(rows)
    delta = np.diff(rows.s)
    pace = np.sqrt(x[1:]) + np.sqrt(x[:-1])
    moving = delta > 0.0
    if (moving & (pace == 0.0)).any():
        raise ValueError('stuck at rest: no motion found')
    return float(np.sum(2.0 * delta[moving] / pace[moving]))


def _feasible(rows, i, x):
    lower, upper = _u_bounds(rows, i, x)
    return lower <= upper


def cartesian_rows(s, d1, d2, feed, acceleration, stops):
    """
    Return the rows of a kinematic planner: ``|p''_k|`` of G per axis.

    ``|d1 u + d2 x| <= acceleration`` per axis (m/s^2), ``x <= (feed /
    |d1|)^2``; ``stops`` (n,) bool where G rests.
    """
    n = len(s)
    cap = np.where(stops, 0.0, (np.asarray(feed) / np.linalg.norm(
        d1, axis=1)) ** 2)
    bound = np.full((n, 3), acceleration)
    return Rows(s, d1, d2, np.zeros((n, 3)), -bound, bound,
                np.minimum(cap, 1e8))


def timed_law(s, x, rate):
    """
    Return ``t`` (samples at ``rate``) and ``s, sdot, sddot`` there.

    ``x`` at gridpoints ``s``; within an interval ``u`` is constant.
    """
    delta = np.diff(s)
    pace = np.sqrt(x[1:]) + np.sqrt(x[:-1])
    with np.errstate(divide='ignore', invalid='ignore'):
        dt = np.where(delta > 0.0, 2.0 * delta / pace, 0.0)
        u = np.where(delta > 0.0, (x[1:] - x[:-1]) / (2.0 * delta), 0.0)
    times = np.concatenate(([0.0], np.cumsum(dt)))
    t = np.arange(0.0, times[-1], 1.0 / rate)
    t = np.append(t, times[-1])
    k = np.clip(np.searchsorted(times, t, side='right') - 1, 0,
                len(delta) - 1)
    tau = t - times[k]
    v0 = np.sqrt(x[:-1])[k]
    return (t, np.minimum(s[k] + v0 * tau + 0.5 * u[k] * tau * tau,
                          s[k + 1]), v0 + u[k] * tau, u[k])


def fine_grid(path, per_metre):
    """
    Return ``(index, w, s, stops)``: a grid of every piece of ``path``.

    ``per_metre`` points a metre, 16 a piece at least, a junction twice:
    the piece, the length along it and along the path (m), where G rests.
    """
    index, w, s, stops = [], [], [], []
    start = 0.0
    for k, piece in enumerate(path.pieces):
        n = max(16, int(piece.length * per_metre))
        ws = np.linspace(0.0, piece.length, n + 1)
        index.append(np.full(n + 1, k))
        w.append(ws)
        s.append(start + ws)
        flags = np.zeros(n + 1, bool)
        flags[0], flags[-1] = path.stops[k], path.stops[k + 1]
        stops.append(flags)
        start += piece.length
    return tuple(map(np.concatenate, (index, w, s, stops)))


def kinematic_planner(path, rate, per_metre=4000):
    """
    Return ``motion(acceleration)``: a CNC-style planner's ``(t, p, v, a)``.

    The time-optimal motion along ``path`` within one Cartesian
    acceleration limit per axis (m/s^2, :func:`cartesian_rows`) and the
    programmed feed, on a :func:`fine_grid`, sampled at ``rate`` (Hz).
    """
    index, w, s, stops = fine_grid(path, per_metre)
    _, d1, d2 = path.evaluate(index, w)
    feed = np.array([path.pieces[k].feed for k in index])
    lengths = np.array([piece.length for piece in path.pieces])

    def motion(acceleration):
        rows = cartesian_rows(s, d1, d2, feed, acceleration, stops)
        t, law, sdot, sddot = timed_law(s, optimal_profile(rows), rate)
        k = np.clip(np.searchsorted(s, law, side='right') - 1, 0,
                    len(s) - 2)
        p, e1, e2 = path.evaluate(index[k], np.clip(
            w[k] + law - s[k], 0.0, lengths[index[k]]))
        return (t, p, e1 * sdot[:, None],
                e1 * sddot[:, None] + e2 * (sdot ** 2)[:, None])
    return motion
