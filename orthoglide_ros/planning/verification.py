"""
Verification: every sample of a motion checked, the rows tightened.

TOPP-RA keeps the limits at the gridpoints; between them, and with
friction at the speeds of the last round, a sample may exceed one. Here
every sample is re-solved with :func:`solve_batch` (the full model,
friction and all; :func:`timing.sample`) and checked against every limit
(:func:`checks`); wherever one is exceeded by more than VERIFY_SHARE the
rows of the gridpoints that shaped the sample are tightened by the excess
(:func:`check`, :func:`tighten`) and the plan is made again, so that no
sample exceeds a limit by more than ACCEPT_SHARE (0.1 %).
"""

import math
from typing import Iterator, Optional

import numpy as np

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.types import Array
from orthoglide_ros.planning import smoothing
from orthoglide_ros.planning.bounds import Bounds
from orthoglide_ros.planning.constraints import (acceleration_bounds, Family,
                                                 Models, Rows)
from orthoglide_ros.planning.limits import Limits
from orthoglide_ros.planning.path import Path
from orthoglide_ros.planning.timing import Motion, sample, Samples, Timing

# A sample beyond a limit by this share tightens the limits and plans again;
# the plan is refused (a PlanningError) if one exceeds ACCEPT_SHARE.
VERIFY_SHARE = 2e-4
ACCEPT_SHARE = 1e-3
# A room tightened to keep a sample within keeps it this much inside (half
# VERIFY_SHARE): the next round's sample, shaped by the same rows, lands
# below the threshold, not on it.
TIGHTEN_MARGIN = 1.0 - 0.5 * VERIFY_SHARE
# Where statics and friction alone exceed a force limit (no room left to
# scale), G goes slower there: its speed by this factor a round, x (the
# speed squared) by its square; less speed, less viscous friction.
SLOWER_SPEED = 0.9
SLOWER_X = SLOWER_SPEED ** 2


class Verdict:
    """
    What the checks of a motion found (:func:`check`).

    ``worst``: the largest excess over a limit as a share of it (negative:
    all within); ``longer``: the factor by which the smoothing time must
    grow (1: none); ``scale_high``, ``scale_low`` (M, 6), ``cap`` (M,): the
    room and the caps on ``x`` of the gridpoints to tighten (1, inf:
    none).
    """

    def __init__(self, rows: Rows) -> None:
        """Nothing found yet, on the gridpoints of ``rows``."""
        self.worst = -np.inf
        self.longer = 1.0
        self.scale_high = np.ones_like(rows.scale_high)
        self.scale_low = np.ones_like(rows.scale_low)
        self.cap = np.full_like(rows.cap, np.inf)


def checks(motion: Motion, samples: Samples, limits: Limits,
           max_speed: float, before: Optional[tuple[float, Array]]
           ) -> Iterator[tuple[Array, Array, Family]]:
    """
    Yield ``(value, bound, family)`` of every limit per sample.

    ``value``, ``bound``: (n, 3) or (n, 1) (G's speed); ``before``: the
    sample before the block's ``(t, lambdaddot)`` (None for the first).
    """
    sol = motion.solution
    n = len(motion.t)
    yield np.abs(sol.force), np.broadcast_to(limits.effort, (n, 3)), \
        Family.FORCE
    yield (np.abs(sol.lambdadot), np.broadcast_to(limits.velocity, (n, 3)),
           Family.VELOCITY)
    up, down = acceleration_bounds(limits, sol.lambdadot >= 0.0)
    yield (np.abs(sol.lambdaddot),
           np.where(sol.lambdaddot >= 0.0, up, down), Family.ACCELERATION)
    speed = np.linalg.norm(motion.velocity, axis=1)[:, None]
    yield speed, np.minimum(samples.feed, max_speed)[:, None], \
        Family.VELOCITY
    if np.isfinite(limits.jerk).any():
        yield (smoothing.jerk(motion.t, sol.lambdaddot, before),
               np.broadcast_to(limits.jerk, (n, 3)), Family.JERK)


def check(rows: Rows, motion: Motion, samples: Samples, max_speed: float,
          x: Array, verdict: Verdict,
          before: Optional[tuple[float, Array]]) -> None:
    """
    Check the samples of ``motion`` (a block); note what to tighten.

    ``samples``: what :func:`timing.sample` tells of each sample (the
    gridpoints whose rows shaped it, its feed, its statics and friction,
    its jerk's share from the smoothing); ``x``: the solution's;
    ``before``: the sample before the block's ``(t, lambdaddot)`` (None
    for the first). Updates ``verdict`` (:class:`Verdict`): a force or an
    acceleration beyond its limit scales the room of its row at those
    gridpoints by the share that keeps it within; a velocity, G's speed
    or a jerk at a curvature jump caps ``x`` there; a jerk of the
    smoothing's own makes the smoothing longer.
    """
    sol = motion.solution
    signed = np.hstack((sol.force, sol.lambdaddot))
    for value, bound, family in checks(motion, samples, rows.limits,
                                       max_speed, before):
        with np.errstate(divide='ignore', invalid='ignore'):
            share = np.where(np.isfinite(bound), value / bound - 1.0,
                             -np.inf)
        verdict.worst = max(verdict.worst,
                            float(share.max(initial=-np.inf)))
        cap = verdict.cap
        for i, j in np.argwhere(share > VERIFY_SHARE):
            points = slice(samples.first[i], samples.last[i] + 1)
            ratio = bound[i, j] / value[i, j]
            if family is Family.JERK:
                if smoothing.owns(samples.smoothed_jerk[i, j],
                                  value[i, j]):
                    verdict.longer = max(verdict.longer,
                                         smoothing.longer(ratio))
                else:       # the jump of lambda'' x at a junction
                    cap[points] = np.minimum(cap[points], x[points] * ratio)
                continue
            if family is Family.VELOCITY:
                cap[points] = np.minimum(cap[points],
                                         x[points] * ratio * ratio)
                continue
            column = family.column + j
            total = signed[i, column]
            static = samples.static[i, column]
            room = math.copysign(bound[i, j], total) - static
            if room * total > 0.0 and abs(total - static) > abs(room):
                share_left = room / (total - static)
                scale = verdict.scale_high if total > 0.0 \
                    else verdict.scale_low
                scale[points, column] = np.minimum(scale[points, column],
                                                   share_left)
            else:   # statics and friction alone: slower, less friction
                cap[points] = np.minimum(cap[points], x[points] * SLOWER_X)


def tighten(rows: Rows, verdict: Verdict) -> None:
    """Tighten ``rows`` where a sample exceeded a limit (``verdict``)."""
    rows.scale_high *= np.where(verdict.scale_high < 1.0,
                                verdict.scale_high * TIGHTEN_MARGIN, 1.0)
    rows.scale_low *= np.where(verdict.scale_low < 1.0,
                               verdict.scale_low * TIGHTEN_MARGIN, 1.0)
    rows.cap_extra = np.minimum(rows.cap_extra, verdict.cap)


def verify(models: Models, path: Path, timing: Timing, rounds: int,
           rows: Rows, max_speed: float, x: Array,
           bounds: Bounds) -> tuple[Motion, Verdict]:
    """
    Sample the motion and check every sample: ``(Motion, Verdict)``.

    SAMPLE_BLOCK samples at a time (:func:`timing.sample`), each block
    checked (:func:`check`) and written into the motion's arrays, made
    once.
    """
    n = len(timing.t)
    triples = [np.empty((n, 3)) for _ in range(9)]
    solution = mechanics.Solution(*triples[3:], np.empty(n), np.empty(n))
    verdict = Verdict(rows)
    before = None
    for block in timing.blocks():
        bounds.clock()
        motion, samples = sample(models, path, timing, rounds, block)
        check(rows, motion, samples, max_speed, x, verdict, before)
        for whole, part in zip(triples[:3] + list(solution), (
                motion.position, motion.velocity, motion.acceleration,
                *motion.solution)):
            whole[block] = part
        before = (motion.t[-1], motion.solution.lambdaddot[-1])
    position, velocity, acceleration = triples[:3]
    return Motion(timing.t, position, velocity, acceleration, solution,
                  len(timing.grid.w), rounds), verdict
