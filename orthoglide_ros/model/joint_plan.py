"""
A joint trajectory sampled in time, as joint_trajectory_controller does.

:class:`JointPlan` holds one ``trajectory_msgs/JointTrajectory`` (three
joints) from its acceptance; :meth:`JointPlan.sample` gives each joint's
desired position (m), velocity (m/s) and effort (N) at a time of the
node's clock: one cubic from the state at acceptance to the first point
ahead, cubic Hermite between points, the effort linear, the last point
held (doc/tracking_controller.md#following-a-joint-trajectory).

>>> plan = JointPlan(10.0, [1.0, 2.0], [[0.0] * 3, [1.0] * 3],
...                  [[0.0] * 3, [0.0] * 3], [[5.0] * 3, [7.0] * 3],
...                  ((0.0,) * 3, (0.0,) * 3, (5.0,) * 3), 10.0)
>>> [round(x, 6) for x in plan.sample(11.5)[0]], plan.sample(11.5)[2]
([0.5, 0.5, 0.5], (6.0, 6.0, 6.0))
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from orthoglide_ros.model.mechanics import ZERO
from orthoglide_ros.model.types import Rows, Triple


class JointPlan:
    """
    One joint trajectory from the instant it starts.

    ``start``: the node-clock time (s) of ``time_from_start`` 0; ``times``
    (N,) s from the start, strictly increasing and >= 0; ``positions``,
    ``velocities``, ``efforts``: (N, 3) arrays (m, m/s, N) in the
    controller's joint order; ``state``: ``(position, velocity, effort)``
    3-tuples of the robot when the plan was accepted (effort: the force
    that held it), at ``accepted`` (s, the same clock as ``start``).
    """

    def __init__(self, start: float, times: Sequence[float], positions: Rows,
                 velocities: Rows, efforts: Rows, state: Any,
                 accepted: float) -> None:
        """Keep the plan; see the class docstring."""
        self.start = float(start)
        self.times = np.asarray(times, dtype=float)
        self.positions = np.asarray(positions, dtype=float)
        self.velocities = np.asarray(velocities, dtype=float)
        self.efforts = np.asarray(efforts, dtype=float)
        self.state = tuple(np.asarray(x, dtype=float) for x in state)
        self.accepted = float(accepted) - self.start     # from the start
        # The first point still ahead at the acceptance.
        self.first = int(np.searchsorted(self.times, self.accepted,
                                         side='right'))
        self.end = self.start + self.times[-1]

    def sample(self, now: float) -> tuple[Triple, Triple, Triple]:
        """
        Return ``(position, velocity, effort)`` 3-tuples at ``now`` (s).

        On the node's clock, the one the plan's ``start`` is on.
        """
        segment = self._segment(now)
        if segment is None:
            return (_floats(self.positions[-1]), ZERO,
                    _floats(self.efforts[-1]))
        s, h, p0, v0, e0, p1, v1, e1 = segment
        s2, s3 = s * s, s * s * s
        position = ((2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * h * v0
                    + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * h * v1)
        velocity = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * h * v0
                    + (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * h * v1) / h
        effort = e0 + s * (e1 - e0)
        return _floats(position), _floats(velocity), _floats(effort)

    def acceleration(self, now: float) -> Triple:
        """Return the cubic's second derivative (m/s^2, a 3-tuple) at ``now``."""
        segment = self._segment(now)
        if segment is None:
            return ZERO
        s, h, p0, v0, _, p1, v1, _ = segment
        return _floats(((12 * s - 6) * (p0 - p1) + (6 * s - 4) * h * v0
                        + (6 * s - 2) * h * v1) / (h * h))

    def _segment(self, now):
        """
        Return the cubic sampled at ``now``: ``(s, h, p0, v0, e0, p1, v1, e1)``.

        ``s`` in [0, 1) along a segment of ``h`` s from ``(p0, v0, e0)`` to
        ``(p1, v1, e1)``; None after the last point.
        """
        t = max(now - self.start, self.accepted)
        times = self.times
        if t >= times[-1]:
            return None
        i = max(int(np.searchsorted(times, t, side='right')), self.first)
        if i == self.first:     # from the accepted state to that point
            (p0, v0, e0), t0 = self.state, self.accepted
        else:
            p0, v0, t0 = (self.positions[i - 1], self.velocities[i - 1],
                          times[i - 1])
            e0 = self.efforts[i - 1]
        h = times[i] - t0
        return ((t - t0) / h, h, p0, v0, e0, self.positions[i],
                self.velocities[i], self.efforts[i])

    def peak_velocity(self) -> tuple[float, int]:
        """
        Return ``(speed, joint)``: the largest |velocity| the plan samples.

        Over the transition from the accepted state and every segment after
        it: each cubic's velocity is a quadratic in its time, largest at an
        end or at its vertex. ``joint``: the column (0, 1, 2) where it is.
        """
        first = self.first
        if first >= len(self.times):
            return 0.0, 0
        p0 = np.vstack((self.state[0], self.positions[first:-1]))
        v0 = np.vstack((self.state[1], self.velocities[first:-1]))
        t0 = np.r_[self.accepted, self.times[first:-1]]
        p1, v1 = self.positions[first:], self.velocities[first:]
        h = (self.times[first:] - t0)[:, None]
        # v(s) = a s^2 + b s + v0 (the derivative of sample's cubic).
        a = (6 * (p0 - p1) + 3 * h * (v0 + v1)) / h
        b = (6 * (p1 - p0) - h * (4 * v0 + 2 * v1)) / h
        with np.errstate(divide='ignore', invalid='ignore'):
            vertex = np.clip(np.where(a != 0.0, -b / (2 * a), 0.0), 0.0, 1.0)
        middle = (a * vertex + b) * vertex + v0
        speeds = np.maximum.reduce((np.abs(v0), np.abs(v1), np.abs(middle)))
        row, joint = np.unravel_index(np.argmax(speeds), speeds.shape)
        return float(speeds[row, joint]), int(joint)

    def finished(self, now: float) -> bool:
        """Whether ``now`` (s, node clock) is past the last point."""
        return bool(now >= self.end)


def _floats(array):
    return tuple(array.tolist())
