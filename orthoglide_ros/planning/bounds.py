"""
What a plan may take (memory, samples, time) and how a plan is refused.

:class:`PlanningError` is every refusal of the time parametrization
(INFEASIBLE, TOO_LARGE, TIMEOUT); :class:`Bounds` counts a plan's
gridpoints and samples before they are made and watches its clock, so
that memory and time stay bounded for every path (doc/planning.md).
"""

import time

from orthoglide_ros.planning.moves import ProgramError, TOO_LARGE

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
# Samples made, solved and checked at once; gridpoints solved at once: the
# work arrays of a block stay small beside SAMPLE_BYTES a sample.
SAMPLE_BLOCK = 16_384


class PlanningError(ProgramError):
    """
    A path the robot cannot follow within its limits (``line N``).

    ``reason``: INFEASIBLE, or TOO_LARGE where the path needs more
    gridpoints, or its motion more samples, than the caller allows, or
    TIMEOUT where planning took longer than the caller allows.
    """

    reason = 'infeasible'


INFEASIBLE = PlanningError.reason
TIMEOUT = 'timeout'


class Bounds:
    """A plan's bounds: its samples, its memory (bytes), its time (s)."""

    def __init__(self, max_samples: int, max_bytes: int,
                 seconds: float) -> None:
        """Start the clock: the plan may take ``seconds`` from now."""
        self.max_samples = max_samples
        self.max_bytes = max_bytes
        self.seconds = seconds
        self.deadline = time.monotonic() + seconds

    def gridpoints(self, count: int, why: str) -> None:
        """Refuse ``count`` gridpoints beyond the memory (TOO_LARGE)."""
        if count * GRIDPOINT_BYTES + 2 * SAMPLE_BYTES > self.max_bytes:
            raise PlanningError(None, f'{why} {count:,} gridpoints: more '
                                f'than the {self.max_bytes / 1e6:.4g} MB left '
                                f'for the plan hold ({GRIDPOINT_BYTES} bytes '
                                'each)', TOO_LARGE)

    def samples(self, count: int, gridpoints: int, rate: float) -> None:
        """Refuse a motion of ``count`` samples beyond the bounds."""
        room = min(self.max_samples, (self.max_bytes - gridpoints
                                      * GRIDPOINT_BYTES) // SAMPLE_BYTES)
        if count > room:
            raise PlanningError(
                None, f'the motion lasts {(count - 1) / rate:.6g} s: '
                f'{count:,} samples at {rate:g} Hz, more than the {room:,} '
                'this planner may hold', TOO_LARGE)

    def clock(self) -> None:
        """Refuse a plan past its time (TIMEOUT)."""
        if time.monotonic() > self.deadline:
            raise PlanningError(None, f'planning took more than '
                                f'{self.seconds:g} s', TIMEOUT)
