"""
Jerk limits: the time law smoothed by its moving average over ``T``.

Biagiotti and Melchiorri's FIR filter, as CNC trajectory generators smooth
a profile: the time law ``s(t)`` of the reachability passes is replaced
by ``s~(t) = (I(t) - I(t - T)) / T`` with ``I`` the integral of ``s``
(:func:`average`), so that ``sdot~`` and ``sddot~`` are continuous and the
jerk of the time law is ``(sddot(t) - sddot(t - T)) / T``; G rests for
``T`` at each stop within the path so that the average comes to rest
there too (:func:`dwells`). The cost: ``T``, plus ``T`` per stop. ``T``
starts at the spread of each actuator's ``lambdaddot`` over its
``max_jerk`` (:func:`first`) and grows (:func:`longer`) where a sample's
jerk (:func:`jerk`) is the smoothing's own and exceeds the limit; a jerk
that is the jump of ``lambda'' x`` at a curvature jump is verification's
(a cap on the speed there).
"""

import math
from typing import Callable, Iterable, Optional

import numpy as np

from orthoglide_ros.model.types import Array

# A sample's jerk is the smoothing's own where the part its time law makes
# (lambda' sdddot) is at least this share of it; else it is the jump of
# lambda'' x where the curvature jumps, which a longer T cannot smooth.
OWN_SHARE = 0.5
# T grows by the jerk's excess and this margin more, so that the next
# round lands below the limit, not on it (rounding, and the excess measured
# on samples, not on the law between them) ...
GROWTH_MARGIN = 1.02
# ... and by at most this factor a round: T's effect on the jerk is not
# exactly inverse (the spread of lambdaddot shrinks as T grows), so a
# larger step would cost cycle time where a smaller one suffices.
MAX_GROWTH = 1.5
# A time (s) on a whole number of periods despite rounding (ceil).
PERIOD_ROUNDING = 1e-9

# ``s, sdot, sddot, I, stage`` at times ``t`` (:meth:`Timing.law`).
Law = Callable[[Array], tuple[Array, Array, Array, Array, Array]]


def first(accelerations: Iterable[Array], max_jerk: Array,
          rate: float) -> float:
    """
    Return the first smoothing time ``T`` (s) for jerk limits.

    The moving average over ``T`` of the time law makes the jerk of
    ``lambdaddot`` about its change over ``T`` divided by ``T``: ``T =
    max_j (range of lambdaddot_j) / max_jerk_j``, one period at least.
    ``accelerations``: the unsmoothed motion's ``lambdaddot`` ((n, 3)
    blocks).
    """
    high, low = np.full(3, -np.inf), np.full(3, np.inf)
    for block in accelerations:
        high = np.maximum(high, block.max(0))
        low = np.minimum(low, block.min(0))
    return float(max(np.max((high - low) / max_jerk), 1.0 / rate))


def dwells(moving_time: float, stops: int, smoothing: float,
           rate: float) -> tuple[int, float]:
    """
    Return the periods of a smoothed motion and ``T`` grown to fill them.

    ``moving_time`` (s): the time law's duration without its dwells;
    ``stops``: the stops within the path, where G rests for ``T``. The
    duration with the average's own ``T`` is made up to a whole number of
    periods at ``rate`` (Hz), the rest going to ``T`` (the dwells grow
    with it).
    """
    duration = moving_time + stops * smoothing
    periods = max(1, math.ceil((duration + smoothing) * rate
                               - PERIOD_ROUNDING))
    return periods, (periods / rate - moving_time) / (1 + stops)


def average(law: Law, t: Array,
            span: float) -> tuple[Array, Array, Array, Array, Array]:
    """
    Return the moving average of ``law`` over ``span`` (s) at ``t``.

    ``s~, sdot~, sddot~`` and ``sdddot~`` (the time law's jerk) at each
    time, and the stage of ``law`` at ``t``.
    """
    s1, v1, a1, i1, stage = law(t)
    s0, v0, a0, i0, _ = law(t - span)
    return ((i1 - i0) / span, (s1 - s0) / span, (v1 - v0) / span,
            (a1 - a0) / span, stage)


def jerk(t: Array, lambdaddot: Array,
         before: Optional[tuple[float, Array]]) -> Array:
    """
    Return each actuator's jerk into each sample (m/s^3, (n, 3)).

    From sample to sample of ``lambdaddot`` (n, 3) at ``t`` (n,);
    ``before``: the sample before the first ``(t, lambdaddot)``, None at
    the motion's start (its first sample's jerk 0).
    """
    if before is not None:
        t = np.r_[before[0], t]
        lambdaddot = np.vstack((before[1], lambdaddot))
    out = np.abs(np.diff(lambdaddot, axis=0)) / np.diff(t)[:, None]
    if before is None:
        out = np.vstack((np.zeros(3), out))
    return out


def owns(smoothed_jerk: float, jerk: float) -> bool:
    """Return whether a sample's ``jerk`` is the smoothing's own."""
    return smoothed_jerk >= OWN_SHARE * jerk


def longer(ratio: float) -> float:
    """Return the factor on ``T`` for a jerk ``1 / ratio`` of its limit."""
    return min(MAX_GROWTH, GROWTH_MARGIN / ratio)
