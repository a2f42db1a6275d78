"""
Time integration of the Orthoglide's platform: a plant to simulate.

:func:`rk4_step` (classic RK4, forces held over the step), :class:`Plant`
(a state with force limits) and :class:`Diverged` (a step not integrated,
as opposed to one the workspace refuses). Units: m, m/s, m/s^2, N, s;
frame 0 (doc/mechanics.md#forward-dynamics-and-simulation).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Union
from collections import namedtuple
import math

from orthoglide_ros.model import mechanics
from orthoglide_ros.model.mechanics import (
    DEFAULT_SINGULARITY_MARGIN, WorkspaceError, ZERO)
from orthoglide_ros.model.types import Triple, Vector

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot


class Diverged(ArithmeticError):
    """
    A step whose integration failed: its result is no state of the robot.

    Raised by a plant's ``step`` (the builtin's state not finite,
    MuJoCo's warnings of the step) with the state left as it was; the
    simulator stops on it (``diverged``). ``reason`` is ``'diverged'``.
    """

    reason = 'diverged'


PlantStep = namedtuple('PlantStep', ('acceleration', 'force', 'clipped'))
PlantStep.__doc__ = """What one :meth:`Plant.step` did.

``acceleration``: the platform's at the start of the step (m/s^2, frame
0); ``force``: the forces applied over the step after clipping (N);
``clipped``: per actuator, whether its command was beyond the limit.
"""


def rk4_step(robot: Robot, position: Vector, velocity: Vector, force: Vector,
             dt: float,
             margin: float = DEFAULT_SINGULARITY_MARGIN) -> tuple[Triple, Triple, Triple]:
    """
    Advance ``(r_G, rdot_G)`` by ``dt`` (s) with the classic RK4 method.

    ``position`` (m), ``velocity`` (m/s) and ``force`` (N, held over the
    step) are 3-sequences. Returns ``(position, velocity, acceleration)``:
    the state at ``t + dt`` and the first stage's acceleration. A
    non-finite input, or a stage or end out of reach or too near a
    singularity, raises :class:`mechanics.WorkspaceError`; one not finite
    from finite inputs :class:`Diverged`; ``dt`` must be finite and
    positive (ValueError).

    >>> from orthoglide_ros.model.robot import Robot
    >>> robot = Robot(gravity=(0.0, 0.0, 0.0))
    >>> rk4_step(robot, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
    ...          1e-3)
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    """
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f'dt must be finite and positive, got {dt!r} s')
    x, y, z = (float(c) for c in position)
    u, v, w = (float(c) for c in velocity)
    force = tuple(float(f) for f in force)
    start = (x, y, z, u, v, w, *force)
    if not all(math.isfinite(c) for c in start):
        raise WorkspaceError('non_finite', (
            f'position {mechanics.format_vector(position)} m, velocity '
            f'{mechanics.format_vector(velocity)} m/s or force '
            f'{mechanics.format_vector(force)} N is not finite'))
    h = 0.5 * dt

    def accel(px, py, pz, vx, vy, vz):
        try:
            return mechanics.forward_dynamics(
                robot, (px, py, pz), (vx, vy, vz), force, margin)
        except WorkspaceError as error:
            # From finite inputs, a stage that is not finite: divergence.
            if error.reason not in ('overflow', 'non_finite'):
                raise
            raise Diverged(_diverged(dt, position, velocity, force,
                                     error)) from None

    a1x, a1y, a1z = accel(x, y, z, u, v, w)
    u2, v2, w2 = u + h * a1x, v + h * a1y, w + h * a1z
    a2x, a2y, a2z = accel(x + h * u, y + h * v, z + h * w, u2, v2, w2)
    u3, v3, w3 = u + h * a2x, v + h * a2y, w + h * a2z
    a3x, a3y, a3z = accel(x + h * u2, y + h * v2, z + h * w2, u3, v3, w3)
    u4, v4, w4 = u + dt * a3x, v + dt * a3y, w + dt * a3z
    a4x, a4y, a4z = accel(x + dt * u3, y + dt * v3, z + dt * w3, u4, v4, w4)
    s = dt / 6.0
    end = ((x + s * (u + 2.0 * (u2 + u3) + u4),
            y + s * (v + 2.0 * (v2 + v3) + v4),
            z + s * (w + 2.0 * (w2 + w3) + w4)),
           (u + s * (a1x + 2.0 * (a2x + a3x) + a4x),
            v + s * (a1y + 2.0 * (a2y + a3y) + a4y),
            w + s * (a1z + 2.0 * (a2z + a3z) + a4z)))
    if not all(math.isfinite(c) for c in (*end[0], *end[1])):
        raise Diverged(_diverged(dt, position, velocity, force,
                                 'the end state is not finite'))
    mechanics.solve(robot, end[0], end[1], ZERO, margin)
    return end[0], end[1], (a1x, a1y, a1z)


def _diverged(dt, position, velocity, force, why):
    """Return the message of a step that diverged."""
    return (f'RK4: the step of {dt:g} s from position '
            f'{mechanics.format_vector(position)} m, velocity '
            f'{mechanics.format_vector(velocity)} m/s under force '
            f'{mechanics.format_vector(force)} N is not finite ({why})')


def force_limits(force_limit: Union[float, Vector],
                 time: float = 0.0) -> Triple:
    """
    Return a plant's force limits as three floats (N); check its time.

    ``force_limit``: one bound or three, positive (``math.inf``: none);
    ``time`` must be finite. ValueError otherwise.
    """
    limits = force_limit if hasattr(force_limit, '__len__') else (
        force_limit,) * 3
    limits = tuple(float(f) for f in limits)
    if len(limits) != 3 or not all(f > 0.0 for f in limits):
        raise ValueError('force_limit must be one or three positive '
                         f'numbers (N, inf for none), got {force_limit}')
    if not math.isfinite(time):
        raise ValueError(f'time must be finite, got {time!r} s')
    return limits


def clipped(force: Vector,
            limits: Vector) -> tuple[Triple, tuple[bool, bool, bool]]:
    """
    Return a force command as floats, and the same clipped to limits (N).

    A non-finite command raises :class:`mechanics.WorkspaceError`
    (``non_finite``) before any clipping.
    """
    command = tuple(float(f) for f in force)
    if not all(math.isfinite(f) for f in command):
        raise WorkspaceError('non_finite', f'force {command} N is not '
                             'finite')
    return command, tuple(min(max(f, -limit), limit)
                          for f, limit in zip(command, limits))


class Plant:
    """
    The simulated robot: platform state, time and actuator force limits.

    ``position`` (m) and ``velocity`` (m/s) of the platform centre G in
    frame 0 and ``time`` (s) are plain attributes (3-tuples of floats and a
    float) that :meth:`step` advances. ``force_limit`` (N): one bound per
    actuator (or one for all, ``math.inf`` for none); a commanded force
    beyond it is clipped to ``[-limit, +limit]`` and the clipping reported.
    ``margin``: the singularity margin of :mod:`mechanics` that every step
    respects. The initial state is checked like any step's end
    (:class:`mechanics.WorkspaceError`).

    >>> from orthoglide_ros.model.robot import Robot
    >>> plant = Plant(Robot(), force_limit=200.0)
    >>> plant.step((0.0, 0.0, 300.0), 1e-3).clipped
    (False, False, True)
    """

    # Its sliders are the closed form of the platform's state (eq. 9, 15).
    closed_form = True

    def __init__(self, robot: Robot, position: Vector = ZERO,
                 velocity: Vector = ZERO, time: float = 0.0,
                 force_limit: Union[float, Vector] = math.inf,
                 margin: float = DEFAULT_SINGULARITY_MARGIN) -> None:
        """Check and set the initial state (see the class docstring)."""
        self.robot = robot
        self.force_limit = force_limits(force_limit, time)
        self.margin = margin
        self.position = tuple(float(c) for c in position)
        self.velocity = tuple(float(c) for c in velocity)
        self.time = float(time)
        mechanics.solve(robot, self.position, self.velocity, ZERO, margin)

    def step(self, force: Vector, dt: float) -> 'PlantStep':
        """
        Apply ``force`` (N) held over ``dt`` (s) and advance the state.

        Returns a :class:`PlantStep`. A non-finite force raises
        :class:`mechanics.WorkspaceError` (``non_finite``) before any
        clipping; a step that :func:`rk4_step` refuses raises its error
        (:class:`mechanics.WorkspaceError` or :class:`Diverged`). On any
        refusal the state and the time stay unchanged.
        """
        command, applied = clipped(force, self.force_limit)
        position, velocity, acceleration = rk4_step(
            self.robot, self.position, self.velocity, applied, dt,
            self.margin)
        self.position, self.velocity = position, velocity
        self.time += dt
        return PlantStep(acceleration, applied,
                         tuple(a != c for a, c in zip(applied, command)))

    def carry(self, payload: float) -> None:
        """Carry ``payload`` (kg) on the platform from the next step on."""
        self.robot = self.robot.replace(payload=payload)

    def joint_state(self) -> tuple[Triple, Triple]:
        """Return ``(lambda, lambdadot)`` (m, m/s, 3-tuples), eq. (9), (15)."""
        s = mechanics.solve(self.robot, self.position, self.velocity,
                            ZERO, self.margin)
        return s.lambda_, s.lambdadot
