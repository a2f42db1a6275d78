"""
Cubic Bezier curves followed by their arc length.

Corner blends, the G5 and G5.1 splines of a program and the curves fitted
through runs of chords are chains of cubic Bezier spans, each given by its
four control points (``control``, (..., 4, 3) m). A span is followed by
its arc length ``w``, not its own parameter ``tau``: its length has no
closed form, so each span keeps a table of the arc length at SUBSPANS + 1
equally spaced ``tau`` (Gauss-Legendre of 8 points on each part), and the
``tau`` of an arc length is found by Newton's method on that length,
exact to rounding where the span's speed ``|B'(tau)|`` is above 0
(:func:`least_speed`). Then ``dp/dw = B' / |B'|`` is the unit tangent and
``d2p/dw2`` the curvature vector: G's velocity ``p'(w) sdot`` is continuous
wherever its speed is.

Also the geometry the proofs of a blend need: de Casteljau's halves and
parts of a span (:func:`halves`, :func:`part`), and the largest distance
of a span to its chord, bounded by its control points (:func:`bulge`: the
span lies in their convex hull). Everything is vectorised over spans.
"""

from __future__ import annotations

import numpy as np

from orthoglide_ros.model.types import Array

# Equal parts of a span's parameter, each integrated by Gauss-Legendre of
# 8 points: the arc length to rounding where the span's least speed is
# at least 0.7 of its largest (the path splits those that are not).
SUBSPANS = 8
# Spans whose tables are made at once.
TABLE_BLOCK = 512
_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(8)
# Newton steps on the arc length at most, and its agreement (a share of
# the span's length).
NEWTON_STEPS = 8
NEWTON_AGREEMENT = 1e-14


def evaluate(control: Array, tau: Array) -> tuple[Array, Array, Array]:
    """
    Return ``B``, ``dB/dtau``, ``d2B/dtau2`` ((n, 3)) at ``tau`` (n,).

    ``control``: (4, 3), one span for all points, or (n, 4, 3), a span a
    point.
    """
    t = np.asarray(tau, dtype=float)[:, None]
    u = 1.0 - t
    p0, p1, p2, p3 = np.moveaxis(np.asarray(control), -2, 0)
    p = u ** 3 * p0 + 3 * u * u * t * p1 + 3 * u * t * t * p2 + t ** 3 * p3
    d1 = 3 * (u * u * (p1 - p0) + 2 * u * t * (p2 - p1) + t * t * (p3 - p2))
    d2 = 6 * (u * (p2 - 2 * p1 + p0) + t * (p3 - 2 * p2 + p1))
    return p, d1, d2


def speed(control: Array, tau: Array) -> Array:
    """Return ``|B'(tau)|``: ``control`` (n, 4, 3), ``tau`` (n, g): (n, g)."""
    hodograph = 3.0 * np.diff(control, axis=-2)[:, :, None, :]
    a, m, c = hodograph[:, 0], hodograph[:, 1], hodograph[:, 2]
    t = tau[..., None]
    u = 1.0 - t
    d1 = u * u * a + 2.0 * u * t * m + t * t * c
    return np.sqrt((d1 * d1).sum(-1))


def gauss_length(control: Array, low: Array, high: Array) -> Array:
    """Length (m) of each span ``control`` (n, 4, 3) from ``low`` to ``high``."""
    half = 0.5 * (high - low)
    nodes = (low + half)[:, None] + half[:, None] * _GAUSS_X[None]
    return half * (speed(control, nodes) @ _GAUSS_W)


def tables(control: Array) -> Array:
    """
    Return the arc length (m) at ``tau = j / SUBSPANS`` of each span.

    ``control`` (m, 4, 3); returns (m, SUBSPANS + 1), from 0 to each
    span's length. TABLE_BLOCK spans at a time.
    """
    m = len(control)
    out = np.zeros((m, SUBSPANS + 1))
    edges = np.arange(SUBSPANS + 1) / SUBSPANS
    for start in range(0, m, TABLE_BLOCK):
        block = control[start:start + TABLE_BLOCK]
        n = len(block)
        parts = gauss_length(np.repeat(block, SUBSPANS, axis=0),
                             np.tile(edges[:-1], n), np.tile(edges[1:], n))
        out[start:start + n, 1:] = np.cumsum(parts.reshape(n, SUBSPANS),
                                             axis=1)
    return out


def parameter(control: Array, table: Array, w: Array) -> Array:
    """
    Return the ``tau`` (n,) of spans at their arc lengths ``w`` (n,) m.

    ``control`` (n, 4, 3), ``table`` (n, SUBSPANS + 1) (:func:`tables`):
    Newton's method on the length of the part of the table ``w`` falls
    in, from the table's linear interpolation.
    """
    n = len(w)
    rows = np.arange(n)
    j = np.clip((table <= w[:, None]).sum(1) - 1, 0, SUBSPANS - 1)
    low = j / SUBSPANS
    base = table[rows, j]
    step = np.maximum(table[rows, j + 1] - base, 1e-300)
    tau = np.clip(low + (w - base) / step / SUBSPANS, low,
                  low + 1.0 / SUBSPANS)
    scale = NEWTON_AGREEMENT * np.maximum(table[:, -1], 1e-300)
    for _ in range(NEWTON_STEPS):
        error = base + gauss_length(control, low, tau) - w
        if (np.abs(error) <= scale).all():
            break
        tau = np.clip(tau - error / speed(control, tau[:, None])[:, 0], low,
                      low + 1.0 / SUBSPANS)
    return tau


def by_length(control: Array, table: Array, w: Array
              ) -> tuple[Array, Array, Array]:
    """
    Return ``p``, ``dp/dw``, ``d2p/dw2`` of spans at their arc lengths ``w``.

    ``control`` (n, 4, 3), ``table`` (n, SUBSPANS + 1) and ``w`` (n,) m
    within each point's span: ``tau(w)`` (:func:`parameter`), then ``dp/dw
    = B' / |B'|`` and ``d2p/dw2 = (B'' - (B''.T) T) / |B'|^2``.
    """
    p, d1, d2 = evaluate(control, parameter(control, table, w))
    pace = np.linalg.norm(d1, axis=1)[:, None]
    unit = d1 / pace
    normal = d2 - (d2 * unit).sum(1)[:, None] * unit
    return p, unit, normal / (pace * pace)


def split(control: Array, tau: Array) -> tuple[Array, Array]:
    """Split spans (n, 4, 3) at ``tau`` (n,) (de Casteljau): the two parts."""
    t = np.asarray(tau, dtype=float)[:, None]
    p0, p1, p2, p3 = np.moveaxis(control, -2, 0)
    a, b, c = p0 + t * (p1 - p0), p1 + t * (p2 - p1), p2 + t * (p3 - p2)
    d, e = a + t * (b - a), b + t * (c - b)
    f = d + t * (e - d)
    return (np.stack((p0, a, d, f), 1), np.stack((f, e, c, p3), 1))


def part(control: Array, low: Array, high: Array) -> Array:
    """Return the parts of spans (n, 4, 3) from ``tau = low`` to ``high``."""
    _, right = split(control, low)
    with np.errstate(divide='ignore', invalid='ignore'):
        rest = np.where(low < 1.0, (high - low) / (1.0 - low), 1.0)
    left, _ = split(right, np.clip(rest, 0.0, 1.0))
    return left


def halves(curves: Array) -> Array:
    """Split each span (K, 4, 3) at its middle: (2K, 4, 3), left ones first."""
    left, right = split(curves, np.full(len(curves), 0.5))
    return np.concatenate((left, right))


def segment_distances(points: Array, a: Array, b: Array) -> Array:
    """Return the distance (m) of each of ``points`` (n, 3) to each segment."""
    ab = b - a
    ab2 = np.maximum((ab * ab).sum(-1), 1e-300)
    q = points[:, None]
    t = np.clip(((q - a) * ab).sum(-1) / ab2, 0.0, 1.0)
    return np.linalg.norm(q - a - t[..., None] * ab, axis=-1)


def bulge(control: Array) -> Array:
    """
    Return a bound (m) on each span's distance to its chord (n,).

    The span lies in the convex hull of its control points and the
    distance to a segment is convex: the largest distance of its two
    inner control points to the chord bounds it.
    """
    a, b = control[:, 0], control[:, 3]
    ab = b - a
    ab2 = np.maximum((ab * ab).sum(-1), 1e-300)[:, None]
    out = np.zeros(len(control))
    for k in (1, 2):
        q = control[:, k] - a
        t = np.clip((q * ab).sum(-1)[:, None] / ab2, 0.0, 1.0)
        out = np.maximum(out, np.linalg.norm(q - t * ab, axis=1))
    return out


def turning(control: Array) -> Array:
    """
    Return the angle (rad) between each span's end tangents (n,).

    From ``P1 - P0`` to ``P3 - P2``: the span's turning where it does not
    wind (all of a fitted run's, a blend's, a G5's but the wildest).
    """
    hodograph = np.diff(control, axis=-2)
    a, c = hodograph[:, 0], hodograph[:, 2]
    return np.arctan2(np.linalg.norm(np.cross(a, c), axis=1),
                      (a * c).sum(1))


def least_speed(control: Array) -> tuple[Array, Array]:
    """
    Return the least and the largest ``|B'(tau)|`` over [0, 1] of each span.

    ``B' = A + B tau + C tau^2``: ``|B'|^2`` is a quartic, its extremes at
    the ends or at the real roots of its derivative, a cubic (the
    eigenvalues of its companion matrices, all spans at once).
    """
    hodograph = 3.0 * np.diff(control, axis=-2)
    a, m, c = hodograph[:, 0], hodograph[:, 1], hodograph[:, 2]
    first, second, third = a, 2.0 * (m - a), a - 2.0 * m + c
    dot = lambda x, y: (x * y).sum(-1)          # noqa: E731
    # d|B'|^2/dtau = k0 + k1 tau + k2 tau^2 + k3 tau^3
    k0 = 2.0 * dot(first, second)
    k1 = 2.0 * (dot(second, second) + 2.0 * dot(first, third))
    k2 = 6.0 * dot(second, third)
    k3 = 4.0 * dot(third, third)
    candidates = [np.zeros(len(control)), np.ones(len(control))]
    scale = np.maximum.reduce([np.abs(k0), np.abs(k1), np.abs(k2),
                               np.abs(k3), np.full(len(k0), 1e-300)])
    cubic = np.abs(k3) > 1e-12 * scale
    if cubic.any():
        companion = np.zeros((int(cubic.sum()), 3, 3))
        companion[:, 1, 0] = companion[:, 2, 1] = 1.0
        companion[:, 0, 2] = -k0[cubic] / k3[cubic]
        companion[:, 1, 2] = -k1[cubic] / k3[cubic]
        companion[:, 2, 2] = -k2[cubic] / k3[cubic]
        roots = np.linalg.eigvals(companion)
        for r in roots.T:
            real = np.where(np.abs(r.imag) <= 1e-9, r.real, 0.0)
            full = np.zeros(len(control))
            full[cubic] = np.clip(real, 0.0, 1.0)
            candidates.append(full)
    square = ~cubic & (np.abs(k2) > 1e-12 * scale)
    if square.any():    # the cubic's lower terms: a quadratic, a line
        disc = np.maximum(k1 * k1 - 4.0 * k2 * k0, 0.0)
        with np.errstate(divide='ignore', invalid='ignore'):
            for sign in (1.0, -1.0):
                r = (-k1 + sign * np.sqrt(disc)) / (2.0 * k2)
                candidates.append(np.where(square, np.clip(
                    np.nan_to_num(r), 0.0, 1.0), 0.0))
    line = ~cubic & ~square & (np.abs(k1) > 1e-12 * scale)
    with np.errstate(divide='ignore', invalid='ignore'):
        candidates.append(np.where(line, np.clip(np.nan_to_num(-k0 / k1),
                                                 0.0, 1.0), 0.0))
    taus = np.stack(candidates, 1)
    speeds = speed(control, taus)
    return speeds.min(1), speeds.max(1)
