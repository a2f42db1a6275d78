"""
The fastest motion along a path under the robot's own dynamics.

Time-optimal path parametrization by reachability analysis (TOPP-RA: Pham
and Pham, IEEE T-RO 34(3), 2018) on the package's inverse dynamics, split
as toppra splits it: the grid (:mod:`grid`); the rows of the dynamics
along the path, ``f = a(s) u + b(s) x + c(s)`` per actuator force and
likewise its rates (:mod:`constraints`); the backward and forward passes
(:mod:`reachability`); the time law and its samples (:mod:`timing`), for
jerk limits smoothed (:mod:`smoothing`). :func:`plan` runs them:

- the grid holds both sides of every junction and points around every
  actuator reversal; a stage with no solution refines it and plans again
  (TOPP-RA's interpolation discretization: each interval's ``u`` meets
  the constraints at both its ends);
- friction (viscous, Coulomb as tanh, per direction, Stribeck), a
  function of ``sdot`` (``lambdadot = lambda' sdot``), which TOPP-RA
  lacks: a fixed point, the friction of each gridpoint at the speed of
  the last solution, until the speeds agree;
- verification (:mod:`verification`): every output sample re-solved
  with :func:`solve_batch` (the full model, friction and all), the rows
  tightened where a sample exceeds a limit and the plan made again, so
  that no sample exceeds a limit by more than ACCEPT_SHARE (0.1 %).

Memory and time are linear in the gridpoints and the samples: both are
counted before they are made and refused (TOO_LARGE) beyond the caller's
bounds (:mod:`bounds`); the dynamics and the samples are computed
SAMPLE_BLOCK at a time.
"""

from __future__ import annotations

import math

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import grid as grids, reachability, smoothing
from orthoglide_ros.planning.bounds import (Bounds, GRIDPOINT_BYTES,
                                            INFEASIBLE, MAX_BYTES, MAX_SAMPLES,
                                            MOVE_BYTES, PlanningError,
                                            SAMPLE_BYTES, TIMEOUT)
from orthoglide_ros.planning.constraints import Dynamics, Models, Rows
from orthoglide_ros.planning.grid import Grid
from orthoglide_ros.planning.limits import Limits
from orthoglide_ros.planning.path import Path
from orthoglide_ros.planning.timing import Motion, sample, Timing
from orthoglide_ros.planning.verification import (ACCEPT_SHARE, tighten,
                                                  verify, VERIFY_SHARE)

__all__ = ['ACCEPT_SHARE', 'GRIDPOINT_BYTES', 'INFEASIBLE', 'MAX_BYTES',
           'MAX_SAMPLES', 'most_pieces', 'Motion', 'MOVE_BYTES', 'plan',
           'PlanningError', 'SAMPLE_BYTES', 'TIMEOUT', 'VERIFY_SHARE']

# Rounds of planning: friction's fixed point (until two solutions' x
# agree within FRICTION_AGREEMENT of the largest, at least AGREEMENT_FLOOR
# m^2/s^2), then verification.
FRICTION_ROUNDS = 8
FRICTION_AGREEMENT = 1e-3
AGREEMENT_FLOOR = 1e-12
VERIFY_ROUNDS = 16
# Grid refinements (GRID_REFINEMENT times the intervals each) where a
# stage has no solution.
REFINEMENTS = 3
GRID_REFINEMENT = 4


def most_pieces(max_bytes: int) -> int:
    """
    Return the most pieces a path planned within ``max_bytes`` may have.

    Each piece has MIN_INTERVALS + 1 gridpoints at least, and half a move
    at least (a move makes a piece and a blend at most).
    """
    return max_bytes // (GRIDPOINT_BYTES * (grids.MIN_INTERVALS + 1)
                         + MOVE_BYTES // 2)


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
    models = Models(robot, margin)
    bounds = Bounds(max_samples, max_bytes - MOVE_BYTES * path.moves,
                    max_seconds)
    intervals = grids.GRID_INTERVALS
    for refinement in range(REFINEMENTS + 1):
        grid, rows = _grid_and_rows(models, path, limits, max_speed,
                                    intervals, refinement, bounds)
        try:
            return _plan_on(models, path, grid, rows, limits, rate,
                            max_speed, bounds)
        except reachability.StageFailure:
            intervals *= GRID_REFINEMENT
    raise PlanningError(None, 'no motion found: the time-optimal '
                        'parametrization failed on every grid')


def _grid_and_rows(models: Models, path: Path, limits: Limits,
                   max_speed: float, intervals: int, refinement: int,
                   bounds: Bounds) -> tuple[Grid, Rows]:
    """
    Return the grid of ``intervals`` and the rows of its dynamics.

    The gridpoints counted before they are made; the path refused where
    it leaves the actuators' position limits or needs more than their
    effort at rest. The dynamics' memory is freed on return: the rows
    hold what the passes use.
    """
    counts = grids.counts(path, intervals)
    bounds.gridpoints(int(counts.sum()) + len(counts), (
        f'the path of {len(path.pieces)} pieces and {path.length:.6g} m '
        'needs' + (f', its grid refined {refinement} times,'
                   if refinement else '')))
    grid = grids.make(path, counts, intervals)
    dyn = models.dynamics(path, grid.index, grid.w, bounds)
    grid, dyn = _add_reversals(models, path, grid, dyn, bounds)
    _check_rest(path, grid, dyn, limits)
    return grid, Rows(dyn, grid, limits, max_speed)


def _add_reversals(models: Models, path: Path, grid: Grid, dyn: Dynamics,
                   bounds: Bounds) -> tuple[Grid, Dynamics]:
    """Add gridpoints, and their dynamics, around every actuator reversal."""
    found = grid.reversals(dyn.lam1)
    if found is None:
        return grid, dyn
    w, at = found
    bounds.gridpoints(len(grid.w) + len(w), f'the path needs, with '
                      f'{len(w):,} around the reversals of its actuators,')
    extra = models.dynamics(path, grid.index[at], w, bounds)
    grid, rows = grid.insert(w, at)
    return grid, dyn.join(extra).take(rows)


def _check_rest(path: Path, grid: Grid, dyn: Dynamics,
                limits: Limits) -> None:
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
            line, what = grids.point_words(path, grid.index[row],
                                           grid.w[row])
            where = 'the start of the path ' if what != 'the path' else ''
            raise PlanningError(
                line, f'{where}at {mechanics.format_vector(dyn.position[row])}'
                f' m {limits.names[j]} {why(row, j)}')


def _plan_on(models: Models, path: Path, grid: Grid, rows: Rows,
             limits: Limits, rate: float, max_speed: float,
             bounds: Bounds) -> Motion:
    """Plan on one grid: friction's fixed point, then verification rounds."""
    x, u, rounds = _friction_point(models, path, grid, rows, bounds)
    smoothed = 0.0
    if np.isfinite(limits.jerk).any():
        smoothed = _first_smoothing(models, path, Timing(
            path, grid, x, u, rate, 0.0, bounds), limits)
    for attempt in range(VERIFY_ROUNDS + 1):
        timing = Timing(path, grid, x, u, rate, smoothed, bounds)
        motion, verdict = verify(models, path, timing, rounds, rows,
                                 max_speed, x, bounds)
        if verdict.worst <= (VERIFY_SHARE if attempt < VERIFY_ROUNDS
                             else ACCEPT_SHARE):
            return motion
        if attempt == VERIFY_ROUNDS:
            break
        del motion          # its memory, before the next is made
        tighten(rows, verdict)
        rounds += 1
        smoothed *= verdict.longer
        bounds.clock()
        x, u = _passes(rows, grid, models.friction(rows.lam1, x), path,
                       False)
    raise PlanningError(None, f'no motion found within the limits: a sample '
                        f'still exceeds one by {verdict.worst:.3%} after '
                        f'{rounds} rounds')


def _friction_point(models: Models, path: Path, grid: Grid, rows: Rows,
                    bounds: Bounds) -> tuple[Array, Array, int]:
    """
    Return ``x``, ``u`` and the rounds of friction's fixed point.

    The passes with the friction of each gridpoint at the speeds of the
    last solution (none at first), until two solutions agree; once where
    the robot has no friction.
    """
    x = np.zeros(len(grid.w))
    rounds = 0
    for _ in range(FRICTION_ROUNDS if models.robot.has_friction else 1):
        rounds += 1
        previous = x
        bounds.clock()
        x, u = _passes(rows, grid, models.friction(rows.lam1, x), path,
                       rounds == 1)
        if np.abs(x - previous).max() <= FRICTION_AGREEMENT * max(
                x.max(), AGREEMENT_FLOOR):
            break
    return x, u, rounds


def _first_smoothing(models: Models, path: Path, timing: Timing,
                     limits: Limits) -> float:
    """Return the first smoothing time (s) of the unsmoothed ``timing``."""
    return smoothing.first(
        (sample(models, path, timing, 0, block)[0].solution.lambdaddot
         for block in timing.blocks()), limits.jerk, timing.rate)


def _passes(rows: Rows, grid: Grid, friction: Array, path: Path,
            first: bool) -> tuple[Array, Array]:
    """Run the reachability passes (:func:`reachability.passes`): x, u."""
    try:
        return reachability.passes(rows, grid.delta, friction, first)
    except reachability.Unbounded as error:
        raise PlanningError(
            grid.line(path, error.stage), 'nothing bounds the acceleration '
            'of G along the path there: give the actuators effort or '
            'acceleration limits (max_effort, max_acceleration)') from None
