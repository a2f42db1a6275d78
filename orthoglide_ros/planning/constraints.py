"""
The rows of the robot's dynamics along a path: toppra's constraints.

Along a path ``p(s)`` the platform's velocity is ``p' sdot`` and its
acceleration ``p' u + p'' x`` with ``x = sdot^2``, ``u = sddot``, so every
actuator force of the rigid model (masses, payload, armature, gravity;
eqs. 16 and 25) is ``f = a(s) u + b(s) x + c(s)``, found by three
:func:`solve_batch` calls over all gridpoints (:meth:`Models.dynamics`):
``a`` on a robot without gravity or friction at rest with acceleration
``p'``, ``b`` on the same robot at velocity ``p'`` and acceleration
``p''``, ``c`` the statics. The same calls give the actuator rates
``lambdadot = lambda' sdot`` and ``lambdaddot = lambda' u + lambda'' x``.
:class:`Rows` turns them and the limits into toppra's form, ``low <=
alpha u + beta x <= high`` per gridpoint, with friction (a function of
``sdot``) given per pass. A limit belongs to a :class:`Family`.
"""

from dataclasses import dataclass
import enum
from typing import Any

import numpy as np

from orthoglide_ros.model import mechanics, terms
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.types import Array
from orthoglide_ros.planning.bounds import Bounds, PlanningError, SAMPLE_BLOCK
from orthoglide_ros.planning.grid import Grid, Indices, point_words
from orthoglide_ros.planning.limits import Limits
from orthoglide_ros.planning.path import Path
from orthoglide_ros.planning.reachability import X_BIG


class Family(enum.Enum):
    """
    What a limit bounds, and so how a sample beyond it tightens the rows.

    FORCE and ACCELERATION: two-sided rows in ``(u, x)``, one column per
    actuator (:attr:`column`: the first); VELOCITY: ``x`` alone (the
    actuators' velocities, G's speed and feed); JERK: from sample to
    sample, kept by the smoothing of the time law (:mod:`smoothing`).
    """

    FORCE = 'force'
    ACCELERATION = 'acceleration'
    VELOCITY = 'velocity'
    JERK = 'jerk'

    @property
    def column(self) -> int:
        """Return the first of this family's 3 columns of :class:`Rows`."""
        return 3 * ROW_FAMILIES.index(self)


# The families of the two-sided rows of a gridpoint, in their order:
# each actuator's force, then its acceleration.
ROW_FAMILIES = (Family.FORCE, Family.ACCELERATION)


@dataclass
class Dynamics:
    """
    The dynamics of every gridpoint: the forces' rows and the rates.

    G's position, the forces' ``a``, ``b``, ``c`` (N), the actuators'
    ``lambda``, ``lambda'``, ``lambda''`` ((M, 3) each) and ``|p'|`` (M,).
    """

    position: Array
    a: Array
    b: Array
    c: Array
    lam: Array
    lam1: Array
    lam2: Array
    speed: Array

    def take(self, order: Indices) -> 'Dynamics':
        """Return the rows ``order`` (an index array) of every field."""
        return Dynamics(*(getattr(self, f)[order] for f in _FIELDS))

    def join(self, other: 'Dynamics') -> 'Dynamics':
        """Return these rows followed by ``other``'s."""
        return Dynamics(*(np.concatenate((getattr(self, f),
                                          getattr(other, f)))
                          for f in _FIELDS))


_FIELDS = ('position', 'a', 'b', 'c', 'lam', 'lam1', 'lam2', 'speed')


class Models:
    """The robot and the two it is split into, built once per plan."""

    def __init__(self, robot: Robot, margin: float) -> None:
        """Split ``robot``: its statics, its inertia (``margin``: eq. 17)."""
        self.robot = robot
        self.statics = robot.frictionless()
        self.inertia = terms.inertial(robot)
        self.margin = margin

    def dynamics(self, path: Path, index: Indices, w: Array,
                 bounds: Bounds) -> Dynamics:
        """
        Return a, b, c and the rates: three batch solves over the points.

        At pieces ``index``, ``w`` m along; SAMPLE_BLOCK points at a time,
        into arrays made once. A point out of the workspace, or nearer a
        singularity than the margin, is refused naming its line.
        """
        out = Dynamics(*(np.empty((len(w), 3)) for _ in _FIELDS[:-1]),
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
                line, what = point_words(path, index[row], w[row])
                raise PlanningError(line, f'{what} at {point} m '
                                    f'{error.finding}') from None
            for name, value in zip(_FIELDS, (
                    p, along.force, curving.force, statics.force,
                    statics.lambda_, curving.lambdadot, curving.lambdaddot,
                    np.linalg.norm(d1, axis=1))):
                getattr(out, name)[rows] = value
        return out

    def friction(self, lam1: Array, x: Array) -> Array:
        """Friction (N, (M, 3)) at each gridpoint at the speeds ``sqrt(x)``."""
        if not self.robot.has_friction:
            return np.zeros_like(lam1)
        return mechanics.friction_force(self.robot,
                                        lam1 * np.sqrt(x)[:, None])


def acceleration_bounds(limits: Limits, forward: Any) -> tuple[Array, Array]:
    """
    Return the |lambdaddot| bounds ``(up, down)`` for each direction.

    ``forward``: where the actuator moves forward (bool, broadcast with
    the limits): there ``up`` speeds it up, ``down`` slows it down
    (``max_deceleration``, else ``max_acceleration``); backward the other
    way round.
    """
    acc = limits.acceleration
    dec = np.where(np.isfinite(limits.deceleration), limits.deceleration,
                   acc)
    return np.where(forward, acc, dec), np.where(forward, dec, acc)


class Rows:
    """
    The constraints of every gridpoint, two-sided and affine in ``(u, x)``.

    ``low <= alpha u + beta x <= high`` (M, 6): per actuator its force
    (``high = max_effort - c - friction``, ``low = -max_effort - c -
    friction``: the room the motion has beside statics and friction), then
    its acceleration (the deceleration's bound where it slows the actuator
    down): the columns of ROW_FAMILIES; ``cap`` (M,): the bounds on ``x``
    alone (the actuators' velocities, G's speed, a stop's 0). Where a
    sample exceeded a limit, verification scales that room down by
    ``scale_high``, ``scale_low`` (the share of the sample's own room that
    keeps it within) and bounds ``x`` by ``cap_extra`` (a share of the
    ``x`` that exceeded; :func:`verification.tighten`).
    """

    def __init__(self, dyn: Dynamics, grid: Grid, limits: Limits,
                 max_speed: float) -> None:
        """Make the rows of ``dyn`` on ``grid``: ``limits``, ``max_speed``."""
        lam1 = dyn.lam1
        self.alpha = np.hstack((dyn.a, lam1))
        self.lam1 = self.alpha[:, 3:]
        self.beta = np.hstack((dyn.b, dyn.lam2))
        up, down = acceleration_bounds(limits, lam1 >= 0.0)
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

    def bounds(self, friction: Array, part: slice) -> tuple[Array, Array]:
        """
        Return ``(low, high)`` of the gridpoints ``part`` (a slice).

        With ``friction`` (N, (M, 3)) at each gridpoint.
        """
        f = np.hstack((friction[part], np.zeros_like(friction[part])))
        high = self.high[part] - f
        low = self.low[part] - f
        return (np.where(low < 0.0, low * self.scale_low[part], low),
                np.where(high > 0.0, high * self.scale_high[part], high))
