"""
The fastest motion along a path under the robot's own dynamics.

Time-optimal path parametrization by reachability analysis (TOPP-RA: Pham
and Pham, IEEE T-RO 34(3), 2018) on the package's inverse dynamics. Along a
path ``p(s)`` the platform's velocity is ``p' sdot`` and its acceleration
``p' u + p'' x`` with ``x = sdot^2``, ``u = sddot``, so every actuator force
of the rigid model (masses, payload, armature, gravity; eqs. 16 and 25) is
``f = a(s) u + b(s) x + c(s)``, found by three :func:`solve_batch` calls
over all gridpoints: ``a`` on a robot without gravity or friction at rest
with acceleration ``p'``, ``b`` on the same robot at velocity ``p'`` and
acceleration ``p''``, ``c`` the statics. The same calls give the actuator
rates ``lambdadot = lambda' sdot`` and ``lambdaddot = lambda' u + lambda''
x``.

What TOPP-RA lacks, added here:

- friction (viscous, Coulomb as tanh, per direction, Stribeck), a function
  of ``sdot`` (``lambdadot = lambda' sdot``): a fixed point, the friction
  of each gridpoint at the speed of the last solution, until the speeds
  agree;
- the grid holds both sides of every junction (the curvature jumps there:
  two gridpoints at one ``s``) and points around every actuator reversal
  (where Coulomb friction changes sign);
- TOPP-RA's interpolation discretization: each interval's ``u`` meets the
  constraints at both its ends; a stage with no solution refines the grid
  and plans again;
- a verification pass: every output sample re-solved with
  :func:`solve_batch` (the full model, friction and all), and wherever a
  limit is exceeded by more than VERIFY_SHARE the limits of the gridpoints
  around it are tightened by the excess and the plan made again, so that
  no sample exceeds a limit by more than ACCEPT_SHARE (0.1 %).

The two passes are TOPP-RA's: backward, the largest controllable ``x`` at
each gridpoint (the one-dimensional programme of each stage solved in
closed form: ``u`` is bounded by affine functions of ``x``); forward, the
largest ``u`` keeping the next ``x`` controllable. Within an interval ``u``
is constant, so the samples are exact quadratics in time.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from orthoglide_ros.model import mechanics, terms
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.types import Array
from orthoglide_ros.planning.gcode import ProgramError
from orthoglide_ros.planning.limits import Limits
from orthoglide_ros.planning.path import Path

# Intervals of the grid over the whole path, at least; each piece has at
# least MIN_INTERVALS, and an arc at least one per MAX_ARC_STEP (rad).
GRID_INTERVALS = 2000
MIN_INTERVALS = 4
MAX_ARC_STEP = math.radians(2.0)
# Gridpoints at these distances (m) either side of an actuator reversal.
REVERSAL_OFFSETS = (2e-5, 2e-4)
# A sample beyond a limit by this share tightens the limits and plans again;
# the plan is refused (a PlanningError) if one exceeds ACCEPT_SHARE.
VERIFY_SHARE = 2e-4
ACCEPT_SHARE = 1e-3
# Most samples of a motion.
MAX_SAMPLES = 20_000_000
# Rounds of planning: friction's fixed point, then verification.
FRICTION_ROUNDS = 8
FRICTION_AGREEMENT = 1e-3
VERIFY_ROUNDS = 16
# Grid refinements where a stage has no solution.
REFINEMENTS = 3
# |coefficient of u| below this: a row bounds x alone.
U_ZERO = 1e-10
# x (m^2/s^2) where nothing else bounds it (G at 1e6 m/s: never reached).
X_BIG = 1e12


class PlanningError(ProgramError):
    """A path the robot cannot follow within its limits (``line N``)."""


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
class _Grid:
    """Gridpoints along the path and the dynamics there."""

    index: Array        # (M,) piece
    w: Array            # (M,) m within the piece
    delta: Array        # (M - 1,) m to the next gridpoint (0: a junction)
    stop: Array         # (M,) bool: G at rest there
    feed: Array         # (M,) m/s


def plan(robot: Robot, path: Path, limits: Limits, rate: float,
         max_speed: float = math.inf,
         margin: float = mechanics.DEFAULT_SINGULARITY_MARGIN) -> Motion:
    """
    Return the fastest motion of G along ``path`` within ``limits``.

    From rest at the path's start to rest at its end, sampled at ``rate``
    (Hz; the duration rounded up to a whole number of periods, the last
    sample at the end); G's speed within each piece's feed and
    ``max_speed`` (m/s). Raises :class:`PlanningError` (a
    :class:`ProgramError`) naming the program's line where a point of the
    path is out of the workspace or nearer a singularity than ``margin``,
    beyond an actuator's position limits, or needs more than an
    actuator's ``max_effort`` at rest, and where nothing bounds the
    motion.
    """
    if not limits.bounding and max_speed == math.inf and all(
            piece.feed == math.inf for piece in path.pieces):
        raise PlanningError(None, 'nothing bounds the motion: no limit of '
                            'any actuator, no feed and no speed cap')
    models = _Models(robot, margin)
    intervals = GRID_INTERVALS
    for _ in range(REFINEMENTS + 1):
        grid = _grid(path, intervals)
        dyn = models.dynamics(path, grid.index, grid.w)
        grid, dyn = _add_reversals(models, path, grid, dyn)
        _check_rest(path, grid, dyn, limits)
        try:
            return _plan_on(models, path, grid, dyn, limits, rate, max_speed)
        except _StageFailure:
            intervals *= 4
    raise PlanningError(None, 'no motion found: the time-optimal '
                        'parametrization failed on every grid')


class _StageFailure(Exception):
    """A stage without a solution: the grid is refined."""


def _grid(path, intervals):
    """Gridpoints of every piece, both ends included, ends shared twice."""
    spacing = path.length / intervals
    index, w, stop, feed = [], [], [], []
    for k, piece in enumerate(path.pieces):
        n = max(MIN_INTERVALS, math.ceil(piece.length / spacing))
        if piece.kind == 'helix' and piece.radius > 0.0:
            n = max(n, math.ceil(abs(piece.angle) / MAX_ARC_STEP))
        elif piece.kind == 'bezier':
            n = max(n, 32)
        index.append(np.full(n + 1, k))
        w.append(np.linspace(0.0, piece.length, n + 1))
        flags = np.zeros(n + 1, dtype=bool)
        flags[0] = path.stops[k]
        flags[-1] = path.stops[k + 1]
        stop.append(flags)
        feed.append(np.full(n + 1, piece.feed))
    return _make_grid(np.concatenate(index), np.concatenate(w),
                      np.concatenate(stop), np.concatenate(feed))


def _make_grid(index, w, stop, feed):
    delta = np.where(index[1:] == index[:-1], np.diff(w), 0.0)
    return _Grid(index, w, delta, stop, feed)


@dataclass
class _Dynamics:
    """Per gridpoint: a, b, c of the forces, lambda, lambda', lambda'', |p'|."""

    position: Array
    a: Array
    b: Array
    c: Array
    lam: Array
    lam1: Array
    lam2: Array
    speed: Array

    def take(self, order):
        """Return the rows ``order`` (an index array) of every field."""
        return _Dynamics(*(getattr(self, f)[order] for f in _DYNAMICS))

    def join(self, other):
        """Return these rows followed by ``other``'s."""
        return _Dynamics(*(np.concatenate((getattr(self, f),
                                           getattr(other, f)))
                           for f in _DYNAMICS))


_DYNAMICS = ('position', 'a', 'b', 'c', 'lam', 'lam1', 'lam2', 'speed')


class _Models:
    """The robot and the two it is split into, built once per plan."""

    def __init__(self, robot, margin):
        self.robot = robot
        self.statics = robot.frictionless()
        self.inertia = terms.inertial(robot)
        self.margin = margin

    def dynamics(self, path, index, w):
        """Return a, b, c and the rates: three batch solves over the points."""
        p, d1, d2 = path.evaluate(index, w)
        margin = self.margin
        try:
            statics = mechanics.solve_batch(self.statics, p, None, None,
                                            margin)
            along = mechanics.solve_batch(self.inertia, p, None, d1, margin)
            curving = mechanics.solve_batch(self.inertia, p, d1, d2, margin)
        except mechanics.WorkspaceError as error:
            row = error.row if error.row is not None else 0
            point = mechanics.format_vector(p[row])
            detail = error.detail.removeprefix(f'position {point} m ')
            raise PlanningError(path.pieces[index[row]].line,
                                f'the path at {point} m {detail}') from None
        return _Dynamics(p, along.force, curving.force, statics.force,
                         statics.lambda_, curving.lambdadot,
                         curving.lambdaddot, np.linalg.norm(d1, axis=1))

    def friction(self, dyn, x):
        """Friction (N, (M, 3)) at each gridpoint at the speeds ``sqrt(x)``."""
        if not self.robot.has_friction:
            return np.zeros_like(dyn.c)
        return mechanics.friction_force(self.robot,
                                        dyn.lam1 * np.sqrt(x)[:, None])


def _add_reversals(models, path, grid, dyn):
    """Add gridpoints around every zero of lambda' within a piece."""
    inside = grid.delta > 0.0
    change = (np.sign(dyn.lam1[1:]) * np.sign(dyn.lam1[:-1]) < 0) & \
        inside[:, None]
    if not change.any():
        return grid, dyn
    stage, joint = np.nonzero(change)
    l0, l1 = dyn.lam1[stage, joint], dyn.lam1[stage + 1, joint]
    zero = grid.w[stage] + grid.delta[stage] * l0 / (l0 - l1)
    offsets = np.array((0.0, *REVERSAL_OFFSETS,
                        *(-o for o in REVERSAL_OFFSETS)))
    w = (zero[:, None] + offsets).ravel()
    at = np.repeat(stage, len(offsets))
    keep = (w > grid.w[at]) & (w < grid.w[at + 1])
    w, at = w[keep], at[keep]
    index = grid.index[at]
    extra = models.dynamics(path, index, w)
    order = np.lexsort((np.r_[grid.w, w], np.r_[grid.index, index]))
    all_w = np.r_[grid.w, w][order]
    all_index = np.r_[grid.index, index][order]
    stop = np.r_[grid.stop, np.zeros(len(w), bool)][order]
    feed = np.r_[grid.feed, grid.feed[at]][order]
    dyn = dyn.join(extra).take(order)
    # Junction duplicates differ in their piece; equal (piece, w) once.
    keep = np.r_[True, (all_index[1:] != all_index[:-1])
                 | (np.diff(all_w) > 0.0)]
    return (_make_grid(all_index[keep], all_w[keep], stop[keep], feed[keep]),
            dyn.take(np.nonzero(keep)[0]))


def _check_rest(path, grid, dyn, limits):
    """Refuse positions beyond the position limits or statics beyond effort."""
    low, high = limits.position[:, 0], limits.position[:, 1]
    for bad, why in (
            ((dyn.lam < low) | (dyn.lam > high), lambda row, j: (
                f'is at lambda = {dyn.lam[row, j]:.6g} m, beyond its position '
                f'limits [{low[j]:g}, {high[j]:g}] m')),
            (np.abs(dyn.c) > limits.effort, lambda row, j: (
                f'needs {dyn.c[row, j]:.6g} N at rest, beyond its max_effort '
                f'{limits.effort[j]:g} N'))):
        if bad.any():
            row, j = np.argwhere(bad)[0]
            raise PlanningError(
                path.pieces[grid.index[row]].line,
                f'at {mechanics.format_vector(dyn.position[row])} m '
                f'{limits.names[j]} {why(row, j)}')


def _plan_on(models, path, grid, dyn, limits, rate, max_speed):
    """Plan on one grid: friction's fixed point, then verification rounds."""
    rows = _Rows(dyn, grid, limits, max_speed)
    x = np.zeros(len(grid.w))
    rounds = 0
    for _ in range(FRICTION_ROUNDS if models.robot.has_friction else 1):
        rounds += 1
        previous = x
        x, u = _passes(rows, grid, models.friction(dyn, x), path,
                       rounds == 1)
        if np.abs(x - previous).max() <= FRICTION_AGREEMENT * max(
                x.max(), 1e-12):
            break
    timing = _Timing(path, grid, x, u, rate, 0.0)
    smoothing = 0.0
    if np.isfinite(limits.jerk).any():
        smoothing = _first_smoothing(models, path, timing, limits)
    for _ in range(VERIFY_ROUNDS):
        timing = _Timing(path, grid, x, u, rate, smoothing)
        motion, samples = _sample(models, path, timing, rounds)
        worst, longer = rows.tighten(motion, samples, max_speed, x)
        if worst <= VERIFY_SHARE:
            return motion
        rounds += 1
        smoothing *= longer
        x, u = _passes(rows, grid, models.friction(dyn, x), path, False)
    timing = _Timing(path, grid, x, u, rate, smoothing)
    motion, samples = _sample(models, path, timing, rounds)
    worst, _ = rows.tighten(motion, samples, max_speed, x)
    if worst <= ACCEPT_SHARE:
        return motion
    raise PlanningError(None, f'no motion found within the limits: a sample '
                        f'still exceeds one by {worst:.3%} after '
                        f'{rounds} rounds')


def _first_smoothing(models, path, timing, limits):
    """
    Return the first smoothing time (s) for jerk limits.

    The moving average over ``T`` of the time law makes the jerk of
    ``lambdaddot`` about its change over ``T`` divided by ``T``: ``T =
    max_j (range of lambdaddot_j) / max_jerk_j``.
    """
    motion, _ = _sample(models, path, timing, 0)
    accelerations = motion.solution.lambdaddot
    spread = accelerations.max(0) - accelerations.min(0)
    return float(max(np.max(spread / limits.jerk), 1.0 / timing.rate))


# The families of two-sided rows of a gridpoint: each actuator's force,
# then its acceleration.
FORCE, ACCELERATION = 0, 3


class _Rows:
    """
    The constraints of every gridpoint, two-sided and affine in ``(u, x)``.

    ``low <= alpha u + beta x <= high`` (M, 6): per actuator its force
    (``high = max_effort - c - friction``, ``low = -max_effort - c -
    friction``: the room the motion has beside statics and friction), then
    its acceleration (the deceleration's bound where it slows the actuator
    down); ``cap`` (M,): the bounds on ``x`` alone (the actuators'
    velocities, G's speed, a stop's 0). Where a sample exceeded a limit,
    verification scales that room down by ``scale_high``, ``scale_low``
    (the share of the sample's own room that keeps it within) and bounds
    ``x`` by ``cap_extra`` (a share of the ``x`` that exceeded).
    """

    def __init__(self, dyn, grid, limits, max_speed):
        lam1 = dyn.lam1
        self.alpha = np.hstack((dyn.a, lam1))
        self.beta = np.hstack((dyn.b, dyn.lam2))
        up, down = _acceleration_bounds(limits, lam1 >= 0.0)
        self.high = np.hstack((limits.effort - dyn.c, up))
        self.low = np.hstack((-limits.effort - dyn.c, -down))
        self.scale_high = np.ones_like(self.high)
        self.scale_low = np.ones_like(self.low)
        with np.errstate(divide='ignore', invalid='ignore'):
            cap = np.where(lam1 != 0.0, (limits.velocity / np.abs(lam1)) ** 2,
                           np.inf).min(1)
            cap = np.minimum(cap, (np.minimum(grid.feed, max_speed)
                                   / dyn.speed) ** 2)
        self.cap = np.where(grid.stop, 0.0, np.minimum(cap, X_BIG))
        self.cap_extra = np.full_like(self.cap, np.inf)
        self.limits = limits

    def bounds(self, friction):
        """Return ``(low, high)`` with ``friction`` (N, (M, 3)) at each point."""
        f = np.hstack((friction, np.zeros_like(friction)))
        high = self.high - f
        low = self.low - f
        return (np.where(low < 0.0, low * self.scale_low, low),
                np.where(high > 0.0, high * self.scale_high, high))

    def tighten(self, motion, samples, max_speed, x):
        """
        Check every sample; tighten the rows where one exceeds a limit.

        ``samples``: what :func:`_sample` tells of each sample (the
        gridpoints whose rows shaped it, its feed, its statics and
        friction, its jerk's share from the smoothing); ``x``: the
        solution's. Returns ``(worst, longer)``: the largest excess over a
        limit as a share of it (negative: all within), and the factor by
        which the smoothing time must grow (1: none).
        """
        worst = -np.inf
        longer = 1.0
        scale_high = np.ones_like(self.scale_high)
        scale_low = np.ones_like(self.scale_low)
        cap = np.full_like(self.cap, np.inf)
        sol = motion.solution
        signed = np.hstack((sol.force, sol.lambdaddot))
        for value, bound, family, rising in _checks(motion, samples,
                                                    self.limits, max_speed):
            with np.errstate(divide='ignore', invalid='ignore'):
                share = np.where(np.isfinite(bound), value / bound - 1.0,
                                 -np.inf)
            worst = max(worst, float(share.max(initial=-np.inf)))
            for sample, j in np.argwhere(share > VERIFY_SHARE):
                points = slice(samples.first[sample],
                               samples.last[sample] + 1)
                ratio = bound[sample, j] / value[sample, j]
                if family == JERK:
                    if samples.smoothed_jerk[sample, j] >= 0.5 * value[
                            sample, j]:
                        longer = max(longer, min(1.5, 1.02 / ratio))
                    else:       # the jump of lambda'' x at a junction
                        cap[points] = np.minimum(cap[points],
                                                 x[points] * ratio)
                    continue
                if family is None:
                    cap[points] = np.minimum(cap[points],
                                             x[points] * ratio * ratio)
                    continue
                column = family + j
                total = signed[sample, column]
                static = samples.static[sample, column]
                room = math.copysign(bound[sample, j], total) - static
                if room * total > 0.0 and abs(total - static) > abs(room):
                    share_left = room / (total - static)
                    scale = scale_high if total > 0.0 else scale_low
                    scale[points, column] = np.minimum(
                        scale[points, column], share_left)
                else:   # statics and friction alone: slower, less friction
                    cap[points] = np.minimum(cap[points], x[points] * 0.81)
        margin = 1.0 - 0.5 * VERIFY_SHARE
        self.scale_high *= np.where(scale_high < 1.0, scale_high * margin,
                                    1.0)
        self.scale_low *= np.where(scale_low < 1.0, scale_low * margin, 1.0)
        self.cap_extra = np.minimum(self.cap_extra, cap)
        return worst, longer


JERK = 'jerk'


def _acceleration_bounds(limits, forward):
    """Return the |lambdaddot| bounds (up, down) for each direction."""
    acc = limits.acceleration
    dec = np.where(np.isfinite(limits.deceleration), limits.deceleration,
                   acc)
    return np.where(forward, acc, dec), np.where(forward, dec, acc)


def _checks(motion, samples, limits, max_speed):
    """Yield ``(value, bound, family, rising)`` of every limit per sample."""
    sol = motion.solution
    n = len(motion.t)
    force = sol.force
    yield (np.abs(force), np.broadcast_to(limits.effort, (n, 3)), FORCE,
           force >= 0.0)
    yield (np.abs(sol.lambdadot), np.broadcast_to(limits.velocity, (n, 3)),
           None, None)
    up, down = _acceleration_bounds(limits, sol.lambdadot >= 0.0)
    rising = sol.lambdaddot >= 0.0
    yield (np.abs(sol.lambdaddot), np.where(rising, up, down), ACCELERATION,
           rising)
    speed = np.linalg.norm(motion.velocity, axis=1)[:, None]
    yield (speed, np.minimum(samples.feed, max_speed)[:, None], None, None)
    if np.isfinite(limits.jerk).any():
        jerk = np.zeros((n, 3))
        jerk[1:] = np.abs(np.diff(sol.lambdaddot, axis=0)) / np.diff(
            motion.t)[:, None]
        yield (jerk, np.broadcast_to(limits.jerk, (n, 3)), JERK, None)


def _passes(rows, grid, friction, path, first):
    """
    Run TOPP-RA's backward and forward passes: ``x`` (M,) and ``u`` (M - 1,).

    Each stage's rows are its gridpoints' (the interpolation scheme: at
    ``i + 1``, ``x + 2 delta u`` for ``x``). ``first``: the first plan on
    this grid, where a stage without a solution means the grid is too
    coarse (:class:`_StageFailure`); later (friction at other speeds)
    such a stage stops G.
    """
    low, high = rows.bounds(friction)
    delta = grid.delta
    twice = 2.0 * delta[:, None]
    alpha = np.hstack((rows.alpha[:-1], rows.alpha[1:] + twice
                       * rows.beta[1:]))
    beta = np.hstack((rows.beta[:-1], rows.beta[1:]))
    low = np.hstack((low[:-1], low[1:]))
    high = np.hstack((high[:-1], high[1:]))
    bounded = np.isfinite(high) | np.isfinite(low)
    bounded[delta == 0.0] = False
    used = bounded.any(0)
    alpha, beta = alpha[:, used], beta[:, used]
    low, high, bounded = low[:, used], high[:, used], bounded[:, used]
    cap = np.minimum(rows.cap, rows.cap_extra)
    positive = (alpha > U_ZERO) & bounded
    negative = (alpha < -U_ZERO) & bounded
    alone = bounded & ~(positive | negative)
    with np.errstate(divide='ignore', invalid='ignore'):
        # alpha > 0: u <= (high - beta x) / alpha, u >= (low - beta x) /
        # alpha; alpha < 0 the other way round.
        slope = np.where(positive | negative, -beta / alpha, 0.0)
        top = np.where(positive, high / alpha,
                       np.where(negative, low / alpha, np.inf))
        bottom = np.where(positive, low / alpha,
                          np.where(negative, high / alpha, -np.inf))
        x_alone = np.where(alone & (beta > 0.0), high / beta, np.inf)
        x_alone = np.minimum(x_alone, np.where(alone & (beta < 0.0),
                                               low / beta, np.inf))
        blocked = (alone & ((high < 0.0) | (low > 0.0))
                   & ((beta == 0.0) | (high < 0.0) & (beta <= 0.0)
                      | (low > 0.0) & (beta >= 0.0))).any(1)
    top = np.where(np.isnan(top), np.inf, top)
    bottom = np.where(np.isnan(bottom), -np.inf, bottom)
    free = (delta > 0.0) & (np.isinf(top).all(1) | np.isinf(bottom).all(1))
    if free.any():
        i = int(np.argmax(free))
        raise PlanningError(
            path.pieces[grid.index[i]].line, 'nothing bounds the '
            'acceleration of G along the path there: give the actuators '
            'effort or acceleration limits (max_effort, max_acceleration)')
    start = np.minimum(cap[:-1], x_alone.min(1, initial=np.inf))
    mvc = _largest_feasible(top, slope, bottom, slope, start)
    failed = ((mvc < 0.0) | blocked) & (delta > 0.0)
    if failed.any():
        if first:
            raise _StageFailure()
        mvc[failed] = 0.0
    with np.errstate(divide='ignore', invalid='ignore'):
        rate = 1.0 + twice * slope
        valid = np.isfinite(bottom) & (rate > 0.0)
        shift = np.where(valid, twice * bottom, -np.inf).tolist()
        scale = np.where(valid, 1.0 / rate, 1.0).tolist()
    k = _backward(delta.tolist(), cap.tolist(), mvc.tolist(), shift, scale)
    # Where G is on the controllable bound, it stays on it if the largest
    # acceleration there reaches the next bound (the backward pass made
    # sure the smallest does not overshoot it): known for every stage at
    # once.
    bound = np.array(k)
    with np.errstate(invalid='ignore'):
        fastest = (top + slope * bound[:-1, None]).min(1)
        follows = (bound[:-1] + twice[:, 0] * fastest >= bound[1:]) & (
            delta > 0.0)
    return _forward(delta.tolist(), k, top.tolist(), slope.tolist(),
                    bottom.tolist(), follows.tolist())


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


def _backward(delta, cap, mvc, shift, scale):
    """Return the largest controllable ``x`` of every gridpoint, from the end."""
    count = len(delta)
    k = [0.0] * (count + 1)
    for i in range(count - 1, -1, -1):
        after = k[i + 1]
        if delta[i] == 0.0:
            k[i] = min(after, cap[i])
            continue
        best = mvc[i]
        for a, b in zip(shift[i], scale[i]):
            value = (after - a) * b
            if value < best:
                best = value
        k[i] = best if best > 0.0 else 0.0
    return k


def _forward(delta, k, top, slope, bottom, follows):
    """
    From rest, the largest ``u`` of each stage keeping ``x`` controllable.

    ``follows[i]``: G on the bound ``k[i]`` can reach ``k[i + 1]``.
    """
    count = len(delta)
    x = [0.0] * (count + 1)
    u = [0.0] * count
    for i in range(count):
        xi = x[i]
        if delta[i] == 0.0:
            x[i + 1] = min(xi, k[i + 1])
            continue
        twice = 2.0 * delta[i]
        if follows[i] and xi == k[i]:
            x[i + 1] = k[i + 1]
            u[i] = (k[i + 1] - xi) / twice
            continue
        rows = list(zip(top[i], slope[i], bottom[i]))
        ui = min(min(t + m * xi for t, m, _ in rows), (k[i + 1] - xi) / twice)
        least = max(b + m * xi for _, m, b in rows)
        if ui < least:
            ui = least
        following = min(max(xi + twice * ui, 0.0), k[i + 1])
        u[i] = (following - xi) / twice
        x[i + 1] = following
    return np.array(x), np.array(u)


class _Timing:
    """
    The time law ``s(t)`` of a solution, and its smoothing.

    Within a stage ``u`` is constant: ``s = s_i + sdot_i tau + u tau^2 /
    2`` (``s`` along the whole path, m). Unsmoothed, the duration is
    stretched to a whole number of periods (``sdot`` divided by the
    stretch, ``u`` by its square), the last sample at the end. Smoothed
    (jerk limits), the time law is its moving average over ``smoothing``
    (s, made up to a whole number of periods): ``s~(t) = (I(t) - I(t -
    T)) / T`` with ``I`` the integral of ``s``, so that ``sdot~ = (s(t) -
    s(t - T)) / T`` and ``sddot~ = (sdot(t) - sdot(t - T)) / T`` are
    continuous and the jerk of the time law is ``(sddot(t) - sddot(t -
    T)) / T``: Biagiotti and Melchiorri's FIR filter, at the cost of
    ``T`` in duration.
    """

    def __init__(self, path, grid, x, u, rate, smoothing):
        speed = np.sqrt(x)
        delta = grid.delta
        pace = speed[:-1] + speed[1:]
        moving = delta > 0.0
        if (moving & (pace <= 0.0)).any():
            i = int(np.argmax(moving & (pace <= 0.0)))
            raise PlanningError(path.pieces[grid.index[i]].line, 'G cannot '
                                'move there within the limits')
        with np.errstate(divide='ignore', invalid='ignore'):
            dt = np.where(moving, 2.0 * delta / pace, 0.0)
        # Smoothed, G rests for T at each stop within the path: the moving
        # average then comes to rest there too.
        dwell = ~moving & grid.stop[:-1] & grid.stop[1:]
        times = np.concatenate(([0.0], np.cumsum(dt)))
        duration = times[-1] + dwell.sum() * smoothing
        if smoothing > 0.0:
            periods = max(1, math.ceil((duration + smoothing) * rate - 1e-9))
            # The rest of a period goes to the smoothing: the dwells grow
            # with it.
            smoothing = (periods / rate - times[-1]) / (1 + dwell.sum())
            dt = np.where(dwell, smoothing, dt)
            times = np.concatenate(([0.0], np.cumsum(dt)))
            self.smoothing = smoothing
            moving = moving | dwell
            stretch = 1.0
        else:
            periods = max(1, math.ceil(duration * rate - 1e-9))
            self.smoothing = 0.0
            stretch = periods / rate / duration
            times *= stretch
        if periods > MAX_SAMPLES:
            raise PlanningError(None, f'the motion lasts {periods / rate:.6g}'
                                f' s: more than {MAX_SAMPLES} samples at '
                                f'{rate:g} Hz')
        self.t = np.arange(periods + 1) / rate
        if smoothing == 0.0:
            times[-1] = self.t[-1]
        self.times = times
        self.speed = speed[:-1] / stretch
        self.u = u / (stretch * stretch)
        starts = np.concatenate(([0.0], np.cumsum(
            [piece.length for piece in path.pieces])))
        self.starts = starts
        self.s = starts[grid.index] + grid.w
        self.grid = grid
        self.rate = rate
        self.moving = moving
        d = np.diff(times)
        self.integral = np.concatenate(([0.0], np.cumsum(
            self.s[:-1] * d + self.speed * d * d / 2 + self.u * d ** 3 / 6)))

    def stage(self, t):
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

    def law(self, t):
        """Return ``s, sdot, sddot, I, stage`` at ``t`` (rest before, after)."""
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


def _sample(models, path, timing, rounds):
    """
    Sample the motion at the timing's rate: ``(Motion, _Samples)``.

    The last sample is exactly at the end, at rest.
    """
    t = timing.t
    grid = timing.grid
    if timing.smoothing > 0.0:
        span = timing.smoothing
        s1, v1, a1, i1, stage = timing.law(t)
        s0, v0, a0, i0, early = timing.law(t - span)
        s = (i1 - i0) / span
        sdot = (s1 - s0) / span
        sddot = (v1 - v0) / span
        third = (a1 - a0) / span
        first = timing.stage(np.clip(t - span, 0.0, timing.times[-1]))
    else:
        s, sdot, sddot, _, stage = timing.law(t)
        third = np.zeros_like(t)
        first = stage
    sdot[0] = sdot[-1] = sddot[-1] = 0.0
    if timing.smoothing > 0.0:
        sddot[0] = 0.0
    piece = np.clip(np.searchsorted(timing.starts, s, side='right') - 1, 0,
                    len(path.pieces) - 1)
    lengths = timing.starts[1:] - timing.starts[:-1]
    w = np.clip(s - timing.starts[piece], 0.0, lengths[piece])
    piece[-1], w[-1] = len(path.pieces) - 1, lengths[-1]
    p, d1, d2 = path.evaluate(piece, w)
    v = d1 * sdot[:, None] + 0.0        # (+ 0.0: no negative zeros)
    a = d1 * sddot[:, None] + d2 * (sdot * sdot)[:, None] + 0.0
    solution = mechanics.solve_batch(models.robot, p, v, a, 0.0)
    with np.errstate(divide='ignore', invalid='ignore'):
        rates = np.where(sdot[:, None] > 1e-9, solution.lambdadot
                         / sdot[:, None], np.inf)
        smoothed = np.where(third[:, None] == 0.0, 0.0,
                            np.abs(rates * third[:, None]))
    feeds = np.array([pc.feed for pc in path.pieces])[piece]
    static = mechanics.solve_batch(models.statics, p, None, None, 0.0).force
    if models.robot.has_friction:
        static = static + mechanics.friction_force(models.robot,
                                                   solution.lambdadot)
    samples = _Samples(np.minimum(first, stage), np.maximum(first, stage) + 1,
                       feeds, np.hstack((static, np.zeros_like(static))),
                       smoothed)
    return Motion(t, p, v, a, solution, len(grid.w), rounds), samples


@dataclass
class _Samples:
    """
    Per sample: its gridpoints' span, its feed, its statics and friction.

    ``static`` (n, 6): the forces at rest plus friction (N), then zeros
    (the accelerations'); ``smoothed_jerk`` (n, 3): the part of the jerk
    the smoothing's time law makes (``lambda' sdddot``, m/s^3).
    """

    first: Array
    last: Array
    feed: Array
    static: Array
    smoothed_jerk: Array
