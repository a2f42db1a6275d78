"""
The time law of a solution of the passes, and the motion sampled from it.

toppra's parametrizer: the passes give ``x = sdot^2`` at each gridpoint
and a constant ``u = sddot`` within each stage, so ``s(t)`` is an exact
quadratic in time within a stage (:class:`Timing`), smoothed for jerk
limits (:mod:`smoothing`). :func:`sample` evaluates it at a fixed rate,
the path at each ``s``, and re-solves every sample with
:func:`solve_batch` (the full model, friction and all) into a
:class:`Motion`, with what verification needs of each sample
(:class:`Samples`).
"""

from dataclasses import dataclass
import math
from typing import Iterator

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import smoothing as fir
from orthoglide_ros.planning.bounds import Bounds, PlanningError, SAMPLE_BLOCK
from orthoglide_ros.planning.constraints import Models
from orthoglide_ros.planning.grid import Grid, Indices
from orthoglide_ros.planning.path import Path

# Below this speed (m/s) along the path an actuator's rate lambda' is not
# found from its velocity (lambda' = lambdadot / sdot): taken as unbounded.
CREEP_SPEED = 1e-9


@dataclass(frozen=True)
class Motion:
    """
    The planned motion, sampled at a fixed rate.

    ``t`` (n,) s from 0 to ``duration``, the last sample exactly at the
    end; ``position``, ``velocity``, ``acceleration`` (n, 3) of G in the
    base frame (m, m/s, m/s^2); ``solution``: :func:`solve_batch` of them
    (lambda, lambdadot, lambdaddot, force, ...); ``gridpoints``: the
    grid's size; ``rounds``: the plans made (friction and verification).
    """

    t: Array
    position: Array
    velocity: Array
    acceleration: Array
    solution: mechanics.Solution
    gridpoints: int
    rounds: int

    @property
    def duration(self) -> float:
        """Return the duration of the motion (s)."""
        return float(self.t[-1])


@dataclass
class Samples:
    """
    Per sample: its gridpoints' span, its feed, its statics and friction.

    ``first``, ``last`` (n,): the gridpoints whose rows shaped it (the
    smoothing's span of the time law included); ``feed`` (n,): its
    piece's (m/s); ``static`` (n, 6): the forces at rest plus friction
    (N), then zeros (the accelerations'); ``smoothed_jerk`` (n, 3): the
    part of the jerk the smoothing's time law makes (``lambda' sdddot``,
    m/s^3).
    """

    first: Indices
    last: Indices
    feed: Array
    static: Array
    smoothed_jerk: Array


class Timing:
    """
    The time law ``s(t)`` of a solution, and its smoothing.

    Within a stage ``u`` is constant: ``s = s_i + sdot_i tau + u tau^2 /
    2`` (``s`` along the whole path, m). Unsmoothed, the duration is
    stretched to a whole number of periods (``sdot`` divided by the
    stretch, ``u`` by its square), the last sample at the end. Smoothed
    (jerk limits), the time law is its moving average over ``smoothing``
    (s, made up to a whole number of periods, :mod:`smoothing`), at the
    cost of ``T`` in duration and ``T`` at each stop.
    """

    def __init__(self, path: Path, grid: Grid, x: Array, u: Array,
                 rate: float, smoothing: float, bounds: Bounds) -> None:
        """
        Lay out the time law of ``x`` (M,), ``u`` (M - 1,) on ``grid``.

        Sampled at ``rate`` (Hz), averaged over ``smoothing`` (s; 0: not);
        the samples refused beyond ``bounds``; a stage G cannot cross
        (both its ends at rest) refused naming its line.
        """
        speed = np.sqrt(x)
        delta = grid.delta
        pace = speed[:-1] + speed[1:]
        moving = delta > 0.0
        if (moving & (pace <= 0.0)).any():
            i = int(np.argmax(moving & (pace <= 0.0)))
            raise PlanningError(grid.line(path, i), 'G cannot move '
                                'there within the limits')
        with np.errstate(divide='ignore', invalid='ignore'):
            dt = np.where(moving, 2.0 * delta / pace, 0.0)
        # Smoothed, G rests for T at each stop within the path: the moving
        # average then comes to rest there too.
        dwell = ~moving & grid.stop[:-1] & grid.stop[1:]
        times = np.concatenate(([0.0], np.cumsum(dt)))
        if smoothing > 0.0:
            periods, smoothing = fir.dwells(times[-1], dwell.sum(),
                                            smoothing, rate)
            dt = np.where(dwell, smoothing, dt)
            times = np.concatenate(([0.0], np.cumsum(dt)))
            self.smoothing = smoothing
            moving = moving | dwell
            stretch = 1.0
        else:
            duration = times[-1]
            periods = max(1, math.ceil(duration * rate
                                       - fir.PERIOD_ROUNDING))
            self.smoothing = 0.0
            stretch = periods / rate / duration
            times *= stretch
        bounds.samples(periods + 1, len(grid.w), rate)
        self.t = np.arange(periods + 1) / rate
        if smoothing == 0.0:
            times[-1] = self.t[-1]
        self.times = times
        self.speed = speed[:-1] / stretch
        self.u = u / (stretch * stretch)
        starts = np.concatenate(([0.0], np.cumsum(
            [piece.length for piece in path.pieces])))
        self.starts = starts
        self.feeds = np.array([piece.feed for piece in path.pieces])
        self.s = starts[grid.index] + grid.w
        self.grid = grid
        self.rate = rate
        self.moving = moving
        d = np.diff(times)
        self.integral = np.concatenate(([0.0], np.cumsum(
            self.s[:-1] * d + self.speed * d * d / 2 + self.u * d ** 3 / 6)))

    def blocks(self) -> Iterator[slice]:
        """Yield the samples SAMPLE_BLOCK at a time (slices)."""
        n = len(self.t)
        for start in range(0, n, SAMPLE_BLOCK):
            yield slice(start, min(n, start + SAMPLE_BLOCK))

    def stage(self, t: Array) -> Indices:
        """Return the stage of each time (s, within the motion)."""
        count = len(self.grid.delta)
        stage = np.clip(np.searchsorted(self.times, t, side='right') - 1, 0,
                        count - 1)
        # At a junction (a stage of no length) the next stage's.
        for _ in range(count):
            still = ~self.moving[stage] & (stage < count - 1)
            if not still.any():
                break
            stage[still] += 1
        return stage

    def law(self, t: Array) -> tuple[Array, Array, Array, Array, Indices]:
        """Return ``s, sdot, sddot, I, stage`` at ``t``: rest before, after."""
        inside = np.clip(t, 0.0, self.times[-1])
        stage = self.stage(inside)
        tau = inside - self.times[stage]
        v0, u = self.speed[stage], self.u[stage]
        s0 = self.s[stage]
        s = np.minimum(s0 + v0 * tau + 0.5 * u * tau * tau,
                       self.s[stage + 1])
        sdot = np.maximum(v0 + u * tau, 0.0)
        integral = self.integral[stage] + s0 * tau + v0 * tau * tau / 2 \
            + u * tau ** 3 / 6
        after = t > self.times[-1]
        before = t < 0.0
        integral = np.where(after, self.integral[-1] + self.s[-1]
                            * (t - self.times[-1]), integral)
        for values in (sdot, u):
            values[after | before] = 0.0
        s = np.where(before, 0.0, s)
        integral = np.where(before, 0.0, integral)
        return s, sdot, u, integral, stage


def sample(models: Models, path: Path, timing: Timing, rounds: int,
           block: slice) -> tuple[Motion, Samples]:
    """
    Sample the motion at the timing's rate: ``(Motion, Samples)``.

    The samples ``block`` (a slice) of the motion; the first at rest, the
    last exactly at the end, at rest; ``rounds``: the plans made.
    """
    t = timing.t[block]
    grid = timing.grid
    first_sample = block.start == 0
    last_sample = block.start + len(t) == len(timing.t)
    if timing.smoothing > 0.0:
        span = timing.smoothing
        s, sdot, sddot, third, stage = fir.average(timing.law, t, span)
        first = timing.stage(np.clip(t - span, 0.0, timing.times[-1]))
    else:
        s, sdot, sddot, _, stage = timing.law(t)
        third = np.zeros_like(t)
        first = stage
    if first_sample:
        sdot[0] = 0.0
        if timing.smoothing > 0.0:
            sddot[0] = 0.0
    piece: Indices = np.clip(np.searchsorted(timing.starts, s,
                                             side='right') - 1, 0,
                             len(path.pieces) - 1)
    lengths = timing.starts[1:] - timing.starts[:-1]
    w = np.clip(s - timing.starts[piece], 0.0, lengths[piece])
    if last_sample:
        sdot[-1] = sddot[-1] = 0.0
        piece[-1], w[-1] = len(path.pieces) - 1, lengths[-1]
    p, d1, d2 = path.evaluate(piece, w)
    v = d1 * sdot[:, None] + 0.0        # (+ 0.0: no negative zeros)
    a = d1 * sddot[:, None] + d2 * (sdot * sdot)[:, None] + 0.0
    solution = mechanics.solve_batch(models.robot, p, v, a, 0.0)
    with np.errstate(divide='ignore', invalid='ignore'):
        rates = np.where(sdot[:, None] > CREEP_SPEED, solution.lambdadot
                         / sdot[:, None], np.inf)
        smoothed = np.where(third[:, None] == 0.0, 0.0,
                            np.abs(rates * third[:, None]))
    feeds = timing.feeds[piece]
    static = mechanics.solve_batch(models.statics, p, None, None, 0.0).force
    if models.robot.has_friction:
        static = static + mechanics.friction_force(models.robot,
                                                   solution.lambdadot)
    samples = Samples(np.minimum(first, stage), np.maximum(first, stage) + 1,
                      feeds, np.hstack((static, np.zeros_like(static))),
                      smoothed)
    return Motion(t, p, v, a, solution, len(grid.w), rounds), samples
