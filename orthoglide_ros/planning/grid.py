"""
The grid: the gridpoints along a path where the time parametrization holds.

TOPP-RA's discretization (Pham and Pham 2018) places gridpoints along
the path and solves between them; here they are counted before they are
made (:func:`counts`, for the memory bound), placed by :func:`make`
(dense where a Bezier piece bends), with both sides of every junction
(two gridpoints at one ``s``: the curvature jumps there), and refined by
:meth:`Grid.reversals` and :meth:`Grid.insert` around every actuator
reversal (where Coulomb friction changes sign).
"""

from dataclasses import dataclass
import math
from typing import Any, Optional

import numpy as np
import numpy.typing as npt

from orthoglide_ros.model.types import Array
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

Indices = npt.NDArray[Any]     # int (pieces, gridpoints) or bool (flags)


@dataclass
class Grid:
    """
    Gridpoints along the path: ``M`` of them, ``M - 1`` stages between.

    ``index`` (M,): the piece; ``w`` (M,): m within it; ``delta`` (M - 1,):
    m to the next gridpoint (0: a junction, the same point on two pieces);
    ``stop`` (M,) bool: G at rest there; ``feed`` (M,): G's speed cap
    (m/s).
    """

    index: Indices
    w: Array
    delta: Array
    stop: Indices
    feed: Array

    @classmethod
    def of(cls, index: Indices, w: Array, stop: Indices,
           feed: Array) -> 'Grid':
        """Return the grid of these gridpoints, ``delta`` found."""
        delta = np.where(index[1:] == index[:-1], np.diff(w), 0.0)
        return cls(index, w, delta, stop, feed)

    def line(self, path: Path, stage: int) -> int:
        """Return the program's line of a stage (from its first gridpoint)."""
        return path.pieces[self.index[stage]].line_at(float(self.w[stage]))

    def reversals(self, lam1: Array) -> Optional[tuple[Array, Indices]]:
        """
        Return where to add gridpoints around the zeros of ``lam1`` (M, 3).

        ``(w, at)``: gridpoints at and REVERSAL_OFFSETS either side of
        every zero of an actuator's ``lambda'`` within a stage (linear
        between its ends), ``at`` the stage each falls in; None where no
        actuator reverses.
        """
        inside = self.delta > 0.0
        change = (np.sign(lam1[1:]) * np.sign(lam1[:-1]) < 0) & \
            inside[:, None]
        if not change.any():
            return None
        stage, joint = np.nonzero(change)
        l0, l1 = lam1[stage, joint], lam1[stage + 1, joint]
        zero = self.w[stage] + self.delta[stage] * l0 / (l0 - l1)
        offsets = np.array((0.0, *REVERSAL_OFFSETS,
                            *(-o for o in REVERSAL_OFFSETS)))
        w = (zero[:, None] + offsets).ravel()
        at = np.repeat(stage, len(offsets))
        keep = (w > self.w[at]) & (w < self.w[at + 1])
        return w[keep], at[keep]

    def insert(self, w: Array, at: Indices) -> tuple['Grid', Indices]:
        """
        Return the grid with gridpoints ``w`` in stages ``at`` added.

        And ``rows`` (M',): where each of the new grid's gridpoints comes
        from, in the old gridpoints followed by the new ones (to take the
        dynamics of both the same way).
        """
        index = self.index[at]
        order = np.lexsort((np.r_[self.w, w], np.r_[self.index, index]))
        all_w = np.r_[self.w, w][order]
        all_index = np.r_[self.index, index][order]
        stop = np.r_[self.stop, np.zeros(len(w), bool)][order]
        feed = np.r_[self.feed, self.feed[at]][order]
        # Junction duplicates differ in their piece; equal (piece, w) once.
        keep = np.r_[True, (all_index[1:] != all_index[:-1])
                     | (np.diff(all_w) > 0.0)]
        return (Grid.of(all_index[keep], all_w[keep], stop[keep],
                        feed[keep]), order[np.nonzero(keep)[0]])


def point_words(path: Path, index: int,
                w: float) -> tuple[Optional[int], str]:
    """Return ``(line, words)`` naming a gridpoint: the path's start apart."""
    if index == 0 and w == 0.0:
        return path.line_at(0, 0.0), 'the start of the path'
    return path.line_at(int(index), float(w)), 'the path'


def counts(path: Path, intervals: int) -> Indices:
    """
    Return the intervals of each piece: (pieces,) int, counted, not made.

    ``intervals`` over the whole path, at least MIN_INTERVALS a piece, one
    per MAX_ARC_STEP of an arc; a Bezier piece its share and one per
    MAX_ARC_STEP of its turning, BEZIER_INTERVALS at least (:func:`make`).
    """
    table = path.table
    with np.errstate(over='ignore'):
        share = table['length'] * (intervals / path.length)
        count = np.maximum(MIN_INTERVALS, np.ceil(share))
        arcs = np.logical_and(table['helix'], table['radius'] > 0.0)
        count = np.where(arcs, np.maximum(count, np.ceil(
            np.abs(table['angle']) / MAX_ARC_STEP)), count)
        curved = np.maximum(BEZIER_INTERVALS, np.ceil(
            share + table['turning'] / MAX_ARC_STEP))
    count = np.where(table['helix'], count, curved)
    return np.minimum(count, 2.0 ** 62).astype(np.int64)


def make(path: Path, counts: Indices, intervals: int) -> Grid:
    """
    Return gridpoints of every piece, both ends included, ends shared twice.

    ``counts``: :func:`counts`. Even along a helix; along a Bezier piece,
    even in its share of ``intervals`` plus its turning over MAX_ARC_STEP:
    dense where it bends.
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
        ends = np.append(table['span_start'][spans], lengths[k])
        cost = ends * per_metre + np.r_[0.0, np.cumsum(
            table['span_turning'][spans])] / MAX_ARC_STEP
        w[first[k]:last[k] + 1] = np.interp(
            np.linspace(0.0, cost[-1], counts[k] + 1), cost, ends)
    w[last] = lengths
    stop = np.zeros(len(w), dtype=bool)
    stop[first] = path.stops[:-1]
    stop[last] |= path.stops[1:]
    feed = np.array([piece.feed for piece in path.pieces])[index]
    return Grid.of(index, w, stop, feed)
