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

The two passes are TOPP-RA's (:mod:`reachability`). Within an interval
``u`` is constant, so the samples are exact quadratics in time. Memory and
time are linear in the gridpoints and the samples: the gridpoints are
counted before the grid is made and the samples before they are made, and
both are refused (TOO_LARGE) beyond the caller's bounds; the dynamics and
the samples are computed SAMPLE_BLOCK at a time.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import time

import numpy as np

from orthoglide_ros.model import mechanics, terms
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.types import Array
from orthoglide_ros.planning.moves import ProgramError, TOO_LARGE
from orthoglide_ros.planning.limits import Limits
from orthoglide_ros.planning import reachability
from orthoglide_ros.planning.path import Path

# Intervals of the grid over the whole path, at least; each piece at least
# MIN_INTERVALS, an arc one per MAX_ARC_STEP (rad), a Bezier piece one per
# MAX_ARC_STEP of its turning more and BEZIER_INTERVALS at least.
GRID_INTERVALS = 2000
MIN_INTERVALS = 4
MAX_ARC_STEP = math.radians(2.0)
BEZIER_INTERVALS = 32
# Gridpoints at these distances (m) either side of an actuator reversal.
REVERSAL_OFFSETS = (2e-5, 2e-4)
# A sample beyond a limit by this share tightens the limits and plans again;
# the plan is refused (a PlanningError) if one exceeds ACCEPT_SHARE.
VERIFY_SHARE = 2e-4
ACCEPT_SHARE = 1e-3
# The memory a plan may take: at most GRIDPOINT_BYTES a gridpoint (the
# grid, its dynamics and rows, the passes, the path's pieces) and
# SAMPLE_BYTES a sample of the motion (240 held, its output's chunk and
# each block's work apart), and the path, made before, at most MOVE_BYTES a
# move or pose (its text, moves and pieces), as benchmarks/bench_plan.py
# --memory measures (doc/measurements.md). By default (plan's max_bytes,
# max_samples) 900 MB: with the interpreter's 50, within 1 GB.
GRIDPOINT_BYTES = 1000
SAMPLE_BYTES = 300
MOVE_BYTES = 3000
MAX_BYTES = 900_000_000
MAX_SAMPLES = 20_000_000
# Samples made, solved and checked at once; gridpoints solved at once.
SAMPLE_BLOCK = 16_384
# Rounds of planning: friction's fixed point, then verification.
FRICTION_ROUNDS = 8
FRICTION_AGREEMENT = 1e-3
VERIFY_ROUNDS = 16
# Grid refinements where a stage has no solution.
REFINEMENTS = 3


class PlanningError(ProgramError):
    """
    A path the robot cannot follow within its limits (``line N``).

    ``reason``: INFEASIBLE, or TOO_LARGE where the path needs more
    gridpoints, or its motion more samples, than the caller allows.
    """

    reason = 'infeasible'


INFEASIBLE = PlanningError.reason
TIMEOUT = 'timeout'


def most_pieces(max_bytes: int) -> int:
    """
    Return the most pieces a path planned within ``max_bytes`` may have.

    Each piece has MIN_INTERVALS + 1 gridpoints at least, and half a move
    at least (a move makes a piece and a blend at most).
    """
    return max_bytes // (GRIDPOINT_BYTES * (MIN_INTERVALS + 1)
                         + MOVE_BYTES // 2)


class _Bounds:
    """A plan's bounds: its samples, its memory (bytes), its time (s)."""

    def __init__(self, max_samples, max_bytes, seconds):
        self.max_samples = max_samples
        self.max_bytes = max_bytes
        self.seconds = seconds
        self.deadline = time.monotonic() + seconds

    def gridpoints(self, count, why):
        """Refuse ``count`` gridpoints beyond the memory (TOO_LARGE)."""
        if count * GRIDPOINT_BYTES + 2 * SAMPLE_BYTES > self.max_bytes:
            raise PlanningError(None, f'{why} {count:,} gridpoints: more '
                                f'than the {self.max_bytes / 1e6:.4g} MB left '
                                f'for the plan hold ({GRIDPOINT_BYTES} bytes '
                                'each)', TOO_LARGE)

    def samples(self, count, gridpoints, rate):
        """Refuse a motion of ``count`` samples beyond the bounds."""
        room = min(self.max_samples, (self.max_bytes - gridpoints
                                      * GRIDPOINT_BYTES) // SAMPLE_BYTES)
        if count > room:
            raise PlanningError(None, f'the motion lasts {(count - 1) / rate:.6g}'
                                f' s: {count:,} samples at {rate:g} Hz, more '
                                f'than the {room:,} this planner may hold',
                                TOO_LARGE)

    def clock(self):
        """Refuse a plan past its time (TIMEOUT)."""
        if time.monotonic() > self.deadline:
            raise PlanningError(None, f'planning took more than '
                                f'{self.seconds:g} s', TIMEOUT)


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
         margin: float = mechanics.DEFAULT_SINGULARITY_MARGIN, *,
         max_samples: int = MAX_SAMPLES, max_bytes: int = MAX_BYTES,
         max_seconds: float = math.inf) -> Motion:
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
    motion; (TOO_LARGE) before it is made where the grid (GRIDPOINT_BYTES
    a gridpoint) or the motion (SAMPLE_BYTES a sample, at most
    ``max_samples``) would not fit in what the path (MOVE_BYTES a move)
    leaves of ``max_bytes``; (TIMEOUT) after ``max_seconds``, checked
    between its steps.
    """
    if not limits.bounding and max_speed == math.inf and all(
            piece.feed == math.inf for piece in path.pieces):
        raise PlanningError(None, 'nothing bounds the motion: no limit of '
                            'any actuator, no feed and no speed cap')
    models = _Models(robot, margin)
    bounds = _Bounds(max_samples, max_bytes - MOVE_BYTES * path.moves,
                     max_seconds)
    intervals = GRID_INTERVALS
    for refinement in range(REFINEMENTS + 1):
        counts = _grid_counts(path, intervals)
        bounds.gridpoints(int(counts.sum()) + len(counts), (
            f'the path of {len(path.pieces)} pieces and {path.length:.6g} m '
            'needs' + (f', its grid refined {refinement} times,'
                       if refinement else '')))
        grid = _grid(path, counts, intervals)
        dyn = models.dynamics(path, grid.index, grid.w, bounds)
        grid, dyn = _add_reversals(models, path, grid, dyn, bounds)
        _check_rest(path, grid, dyn, limits)
        rows = _Rows(dyn, grid, limits, max_speed)
        dyn = None      # its memory: the rows hold what the passes use
        try:
            return _plan_on(models, path, grid, rows, limits, rate,
                            max_speed, bounds)
        except reachability.StageFailure:
            intervals *= 4
    raise PlanningError(None, 'no motion found: the time-optimal '
                        'parametrization failed on every grid')


def _grid_counts(path, intervals):
    """
    Return the intervals of each piece: (pieces,) int, counted, not made.

    ``intervals`` over the whole path, at least MIN_INTERVALS a piece, one
    per MAX_ARC_STEP of an arc; a Bezier piece its share and one per
    MAX_ARC_STEP of its turning, BEZIER_INTERVALS at least (:func:`_grid`).
    """
    table = path.table
    with np.errstate(over='ignore'):
        share = table['length'] * (intervals / path.length)
        counts = np.maximum(MIN_INTERVALS, np.ceil(share))
        arcs = table['helix'] & (table['radius'] > 0.0)
        counts = np.where(arcs, np.maximum(counts, np.ceil(
            np.abs(table['angle']) / MAX_ARC_STEP)), counts)
        curved = np.maximum(BEZIER_INTERVALS, np.ceil(
            share + table['turning'] / MAX_ARC_STEP))
    counts = np.where(table['helix'], counts, curved)
    return np.minimum(counts, 2.0 ** 62).astype(np.int64)


def _grid(path, counts, intervals):
    """
    Gridpoints of every piece, both ends included, ends shared twice.

    Even along a helix; along a Bezier piece, even in its share of
    ``intervals`` plus its turning over MAX_ARC_STEP: dense where it bends.
    """
    sizes = counts + 1
    last = np.cumsum(sizes) - 1
    first = last - counts
    table = path.table
    lengths, per_metre = table['length'], intervals / path.length
    index = np.repeat(np.arange(len(counts)), sizes)
    w = (np.arange(last[-1] + 1) - first[index]) * (lengths / counts)[index]
    for k in np.flatnonzero(~table['helix']):
        spans = slice(table['span_first'][k], table['span_first'][k + 1])
        bounds = np.append(table['span_start'][spans], lengths[k])
        cost = bounds * per_metre + np.r_[0.0, np.cumsum(
            table['span_turning'][spans])] / MAX_ARC_STEP
        w[first[k]:last[k] + 1] = np.interp(
            np.linspace(0.0, cost[-1], counts[k] + 1), cost, bounds)
    w[last] = lengths
    stop = np.zeros(len(w), dtype=bool)
    stop[first] = path.stops[:-1]
    stop[last] |= path.stops[1:]
    feed = np.array([piece.feed for piece in path.pieces])[index]
    return _make_grid(index, w, stop, feed)


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

    def dynamics(self, path, index, w, bounds):
        """
        Return a, b, c and the rates: three batch solves over the points.

        SAMPLE_BLOCK points at a time, into arrays made once.
        """
        out = _Dynamics(*(np.empty((len(w), 3)) for _ in _DYNAMICS[:-1]),
                        np.empty(len(w)))
        for start in range(0, len(w), SAMPLE_BLOCK):
            bounds.clock()
            rows = slice(start, start + SAMPLE_BLOCK)
            p, d1, d2 = path.evaluate(index[rows], w[rows])
            margin = self.margin
            try:
                statics = mechanics.solve_batch(self.statics, p, None, None,
                                                margin)
                along = mechanics.solve_batch(self.inertia, p, None, d1,
                                              margin)
                curving = mechanics.solve_batch(self.inertia, p, d1, d2,
                                                margin)
            except mechanics.WorkspaceError as error:
                row = start + (error.row or 0)
                point = mechanics.format_vector(p[row - start])
                detail = error.detail.removeprefix(f'position {point} m ')
                line, what = _at(path, index[row], w[row])
                raise PlanningError(line, f'{what} at {point} m {detail}') \
                    from None
            for name, value in zip(_DYNAMICS, (
                    p, along.force, curving.force, statics.force,
                    statics.lambda_, curving.lambdadot, curving.lambdaddot,
                    np.linalg.norm(d1, axis=1))):
                getattr(out, name)[rows] = value
        return out

    def friction(self, lam1, x):
        """Friction (N, (M, 3)) at each gridpoint at the speeds ``sqrt(x)``."""
        if not self.robot.has_friction:
            return np.zeros_like(lam1)
        return mechanics.friction_force(self.robot,
                                        lam1 * np.sqrt(x)[:, None])


def _at(path, index, w):
    """Return ``(line, words)`` naming a gridpoint: the path's start apart."""
    if index == 0 and w == 0.0:
        return path.line_at(0, 0.0), 'the start of the path'
    return path.line_at(int(index), float(w)), 'the path'


def _stage_line(path, grid, i):
    """Return the program's line of stage ``i`` (from gridpoint ``i``)."""
    return path.pieces[grid.index[i]].line_at(float(grid.w[i]))


def _add_reversals(models, path, grid, dyn, bounds):
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
    bounds.gridpoints(len(grid.w) + len(w), f'the path needs, with '
                      f'{len(w):,} around the reversals of its actuators,')
    index = grid.index[at]
    extra = models.dynamics(path, index, w, bounds)
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
            line, what = _at(path, grid.index[row], grid.w[row])
            where = 'the start of the path ' if what != 'the path' else ''
            raise PlanningError(
                line, f'{where}at {mechanics.format_vector(dyn.position[row])}'
                f' m {limits.names[j]} {why(row, j)}')


def _plan_on(models, path, grid, rows, limits, rate, max_speed, bounds):
    """Plan on one grid: friction's fixed point, then verification rounds."""
    x = np.zeros(len(grid.w))
    rounds = 0
    for _ in range(FRICTION_ROUNDS if models.robot.has_friction else 1):
        rounds += 1
        previous = x
        bounds.clock()
        x, u = _passes(rows, grid, models.friction(rows.lam1, x), path,
                       rounds == 1)
        if np.abs(x - previous).max() <= FRICTION_AGREEMENT * max(
                x.max(), 1e-12):
            break
    smoothing = 0.0
    if np.isfinite(limits.jerk).any():
        smoothing = _first_smoothing(models, path, _Timing(
            path, grid, x, u, rate, 0.0, bounds), limits)
    for attempt in range(VERIFY_ROUNDS + 1):
        timing = _Timing(path, grid, x, u, rate, smoothing, bounds)
        motion, verdict = _verify(models, path, timing, rounds, rows,
                                  max_speed, x, bounds)
        if verdict.worst <= (VERIFY_SHARE if attempt < VERIFY_ROUNDS
                             else ACCEPT_SHARE):
            return motion
        if attempt == VERIFY_ROUNDS:
            break
        motion = None       # its memory, before the next is made
        rows.tighten(verdict)
        rounds += 1
        smoothing *= verdict.longer
        bounds.clock()
        x, u = _passes(rows, grid, models.friction(rows.lam1, x), path,
                       False)
    raise PlanningError(None, f'no motion found within the limits: a sample '
                        f'still exceeds one by {verdict.worst:.3%} after '
                        f'{rounds} rounds')


def _verify(models, path, timing, rounds, rows, max_speed, x, bounds):
    """
    Sample the motion and check every sample: ``(Motion, _Verdict)``.

    SAMPLE_BLOCK samples at a time (:func:`_sample`), each block checked
    (:meth:`_Rows.check`) and written into the motion's arrays, made once.
    """
    n = len(timing.t)
    triples = [np.empty((n, 3)) for _ in range(9)]
    solution = mechanics.Solution(*triples[3:], np.empty(n), np.empty(n))
    verdict = _Verdict(rows)
    before = None
    for start in range(0, n, SAMPLE_BLOCK):
        bounds.clock()
        block = slice(start, min(n, start + SAMPLE_BLOCK))
        motion, samples = _sample(models, path, timing, rounds, block)
        rows.check(motion, samples, max_speed, x, verdict, before)
        for whole, part in zip(triples[:3] + list(solution), (
                motion.position, motion.velocity, motion.acceleration,
                *motion.solution)):
            whole[block] = part
        before = (motion.t[-1], motion.solution.lambdaddot[-1])
    return Motion(timing.t, *triples[:3], solution, len(timing.grid.w),
                  rounds), verdict


def _first_smoothing(models, path, timing, limits):
    """
    Return the first smoothing time (s) for jerk limits.

    The moving average over ``T`` of the time law makes the jerk of
    ``lambdaddot`` about its change over ``T`` divided by ``T``: ``T =
    max_j (range of lambdaddot_j) / max_jerk_j``.
    """
    high, low = np.full(3, -np.inf), np.full(3, np.inf)
    for start in range(0, len(timing.t), SAMPLE_BLOCK):
        block = slice(start, start + SAMPLE_BLOCK)
        accelerations = _sample(models, path, timing, 0,
                                block)[0].solution.lambdaddot
        high = np.maximum(high, accelerations.max(0))
        low = np.minimum(low, accelerations.min(0))
    return float(max(np.max((high - low) / limits.jerk), 1.0 / timing.rate))


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
        self.lam1 = self.alpha[:, 3:]
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
        self.cap = np.where(grid.stop, 0.0, np.minimum(cap, reachability.X_BIG))
        self.cap_extra = np.full_like(self.cap, np.inf)
        self.limits = limits

    def bounds(self, friction, part):
        """
        Return ``(low, high)`` of the gridpoints ``part`` (a slice).

        With ``friction`` (N, (M, 3)) at each gridpoint.
        """
        f = np.hstack((friction[part], np.zeros_like(friction[part])))
        high = self.high[part] - f
        low = self.low[part] - f
        return (np.where(low < 0.0, low * self.scale_low[part], low),
                np.where(high > 0.0, high * self.scale_high[part], high))

    def check(self, motion, samples, max_speed, x, verdict, before):
        """
        Check the samples of ``motion`` (a block); note what to tighten.

        ``samples``: what :func:`_sample` tells of each sample (the
        gridpoints whose rows shaped it, its feed, its statics and
        friction, its jerk's share from the smoothing); ``x``: the
        solution's; ``before``: the sample before the block's ``(t,
        lambdaddot)`` (None for the first). Updates ``verdict``: the
        largest excess over a limit as a share of it (negative: all
        within), the factor by which the smoothing time must grow (1:
        none), the room and the caps of the gridpoints to tighten.
        """
        sol = motion.solution
        signed = np.hstack((sol.force, sol.lambdaddot))
        for value, bound, family in _checks(motion, samples, self.limits,
                                            max_speed, before):
            with np.errstate(divide='ignore', invalid='ignore'):
                share = np.where(np.isfinite(bound), value / bound - 1.0,
                                 -np.inf)
            verdict.worst = max(verdict.worst,
                                float(share.max(initial=-np.inf)))
            cap = verdict.cap
            for sample, j in np.argwhere(share > VERIFY_SHARE):
                points = slice(samples.first[sample],
                               samples.last[sample] + 1)
                ratio = bound[sample, j] / value[sample, j]
                if family == JERK:
                    if samples.smoothed_jerk[sample, j] >= 0.5 * value[
                            sample, j]:
                        verdict.longer = max(verdict.longer,
                                             min(1.5, 1.02 / ratio))
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
                    scale = verdict.scale_high if total > 0.0 \
                        else verdict.scale_low
                    scale[points, column] = np.minimum(
                        scale[points, column], share_left)
                else:   # statics and friction alone: slower, less friction
                    cap[points] = np.minimum(cap[points], x[points] * 0.81)

    def tighten(self, verdict):
        """Tighten the rows where a sample exceeded a limit (``verdict``)."""
        margin = 1.0 - 0.5 * VERIFY_SHARE
        self.scale_high *= np.where(verdict.scale_high < 1.0,
                                    verdict.scale_high * margin, 1.0)
        self.scale_low *= np.where(verdict.scale_low < 1.0,
                                   verdict.scale_low * margin, 1.0)
        self.cap_extra = np.minimum(self.cap_extra, verdict.cap)


class _Verdict:
    """What the checks of a motion found (see :meth:`_Rows.check`)."""

    def __init__(self, rows):
        self.worst = -np.inf
        self.longer = 1.0
        self.scale_high = np.ones_like(rows.scale_high)
        self.scale_low = np.ones_like(rows.scale_low)
        self.cap = np.full_like(rows.cap, np.inf)


JERK = 'jerk'


def _acceleration_bounds(limits, forward):
    """Return the |lambdaddot| bounds (up, down) for each direction."""
    acc = limits.acceleration
    dec = np.where(np.isfinite(limits.deceleration), limits.deceleration,
                   acc)
    return np.where(forward, acc, dec), np.where(forward, dec, acc)


def _checks(motion, samples, limits, max_speed, before):
    """Yield ``(value, bound, family)`` of every limit per sample."""
    sol = motion.solution
    n = len(motion.t)
    yield np.abs(sol.force), np.broadcast_to(limits.effort, (n, 3)), FORCE
    yield (np.abs(sol.lambdadot), np.broadcast_to(limits.velocity, (n, 3)),
           None)
    up, down = _acceleration_bounds(limits, sol.lambdadot >= 0.0)
    yield (np.abs(sol.lambdaddot),
           np.where(sol.lambdaddot >= 0.0, up, down), ACCELERATION)
    speed = np.linalg.norm(motion.velocity, axis=1)[:, None]
    yield speed, np.minimum(samples.feed, max_speed)[:, None], None
    if np.isfinite(limits.jerk).any():
        t, lambdaddot = motion.t, sol.lambdaddot
        if before is not None:
            t = np.r_[before[0], t]
            lambdaddot = np.vstack((before[1], lambdaddot))
        jerk = np.abs(np.diff(lambdaddot, axis=0)) / np.diff(t)[:, None]
        if before is None:
            jerk = np.vstack((np.zeros(3), jerk))
        yield jerk, np.broadcast_to(limits.jerk, (n, 3)), JERK


def _passes(rows, grid, friction, path, first):
    """Run the reachability passes (:func:`reachability.passes`): x, u."""
    try:
        return reachability.passes(rows, grid.delta, friction, first)
    except reachability.Unbounded as error:
        raise PlanningError(
            _stage_line(path, grid, error.stage), 'nothing bounds the '
            'acceleration of G along the path there: give the actuators '
            'effort or acceleration limits (max_effort, max_acceleration)') \
            from None


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

    def __init__(self, path, grid, x, u, rate, smoothing, bounds):
        speed = np.sqrt(x)
        delta = grid.delta
        pace = speed[:-1] + speed[1:]
        moving = delta > 0.0
        if (moving & (pace <= 0.0)).any():
            i = int(np.argmax(moving & (pace <= 0.0)))
            raise PlanningError(_stage_line(path, grid, i), 'G cannot move '
                                'there within the limits')
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


def _sample(models, path, timing, rounds, block):
    """
    Sample the motion at the timing's rate: ``(Motion, _Samples)``.

    The samples ``block`` (a slice) of the motion; the first at rest, the
    last exactly at the end, at rest.
    """
    t = timing.t[block]
    grid = timing.grid
    first_sample = block.start == 0
    last_sample = block.start + len(t) == len(timing.t)
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
    if first_sample:
        sdot[0] = 0.0
        if timing.smoothing > 0.0:
            sddot[0] = 0.0
    piece = np.clip(np.searchsorted(timing.starts, s, side='right') - 1, 0,
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
        rates = np.where(sdot[:, None] > 1e-9, solution.lambdadot
                         / sdot[:, None], np.inf)
        smoothed = np.where(third[:, None] == 0.0, 0.0,
                            np.abs(rates * third[:, None]))
    feeds = timing.feeds[piece]
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
