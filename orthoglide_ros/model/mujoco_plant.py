"""
MuJoCo as the plant: the Orthoglide of :mod:`mjcf`, stepped by MuJoCo.

:class:`MujocoPlant` has :class:`plant.Plant`'s interface; any warning
MuJoCo raises in a step is :class:`plant.Diverged` (its handler taken
over), and the terms its joints cannot hold are applied as forces: the
friction beyond them, and the screw ripple the model records
(doc/mujoco.md#warnings-and-divergence).
"""

from __future__ import annotations

from typing import Any, Optional, Union
import math

import numpy as np

from orthoglide_ros.model import mechanics, mjcf
from orthoglide_ros.model.mechanics import (DEFAULT_SINGULARITY_MARGIN,
                                            WorkspaceError, ZERO)
from orthoglide_ros.model.plant import (clipped, Diverged, force_limits,
                                        PlantStep)
from orthoglide_ros.model.robot import JOINT_NAMES, Robot
from orthoglide_ros.model.types import Triple, Vector


def check_model(text: str) -> None:
    """
    Refuse an MJCF that is not ``orthoglide mjcf``'s (ValueError, the reason).

    It must load in MuJoCo and have the contract's names: the slide joints
    and actuators JOINT_NAMES (in that order), every hinge of
    :func:`mjcf.joint_values` and the body ``platform``; the terms it
    records (:data:`mjcf.RECORDED`) must be a robot's.
    """
    import mujoco
    try:
        model = mujoco.MjModel.from_xml_string(text)
    except ValueError as error:
        raise ValueError(f'MuJoCo cannot load it: '
                         f'{str(error).splitlines()[0]}') from None
    joints = {model.joint(i).name for i in range(model.njnt)}
    wanted = set(mjcf.joint_values(Robot(), ZERO))
    actuators = [model.actuator(i).name for i in range(model.nu)]
    bodies = {model.body(i).name for i in range(model.nbody)}
    if not wanted <= joints or actuators != list(JOINT_NAMES) \
            or 'platform' not in bodies:
        raise ValueError(
            'not a model of orthoglide mjcf (default joint names): joints '
            f'{sorted(wanted - joints)} missing, actuators {actuators}, '
            f'platform body {"present" if "platform" in bodies else "absent"}')
    mjcf.recorded(Robot(), numeric_data(model))


# Largest distance (m) a model's loops may stand open, or its platform off
# G, at the joint values of the robot's own legs: far above the rounding
# of orthoglide mjcf's numbers (1e-15 m), far below a leg's error (1e-5 m).
LEGS_TOLERANCE = 1e-9
# Where the legs are compared: home and the corners of a cube of half side
# this share of the shortest bar around it (a tilted axis shows only away
# from home, where the slider stands where the legs meet).
LEGS_CUBE = 0.15


def check_legs(text: str, robot: Robot) -> None:
    """
    Refuse an MJCF whose legs are not ``robot``'s (ValueError, how far).

    ``text``: a model :func:`check_model` accepts. With every joint at
    ``robot``'s values (:func:`mjcf.joint_values`) at home and at the
    corners of a cube around it, its loops must close and its platform
    stand at G, to LEGS_TOLERANCE: each leg's axis, offset, bar length and
    attachment are then the robot's (its other lengths cancel), as the
    workspace checks of the simulator, made with ``robot``, need.
    """
    import mujoco
    model = mujoco.MjModel.from_xml_string(text)
    data = mujoco.MjData(model)
    platform = model.body('platform').id
    half = LEGS_CUBE * min(leg.length for leg in robot.legs)
    corners = [(0.0, 0.0, 0.0)] + [(x, y, z) for x in (-half, half)
                                   for y in (-half, half)
                                   for z in (-half, half)]
    for position in corners:
        try:
            values = mjcf.joint_values(robot, position)
        except WorkspaceError:      # a corner out of this robot's reach
            continue
        for name, (q, _, _) in values.items():
            data.qpos[model.joint(name).qposadr[0]] = q
        mujoco.mj_forward(model, data)
        loops = data.efc_pos[
            data.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY]
        off = max(float(np.abs(loops).max(initial=0.0)), float(
            np.abs(data.xpos[platform] - position).max()))
        if not off <= LEGS_TOLERANCE:
            raise ValueError(
                f'its legs are not those of robot.*: at the joints of '
                f'robot.* with G at {mechanics.format_vector(position)} m '
                f'its loops or platform stand {off:.3g} m off (write it '
                'with orthoglide mjcf from the same robot.*)')


def numeric_data(model: Any) -> dict[str, np.ndarray]:
    """Return a MuJoCo model's ``custom`` numeric data by name."""
    return {model.numeric(i).name: model.numeric(i).data.copy()
            for i in range(model.nnumeric)}


def unavailable() -> Optional[str]:
    """Return why MuJoCo cannot be used here, '' if it can."""
    try:
        import mujoco  # noqa: F401
    except ImportError as error:
        return f'the mujoco package is not installed ({error})'
    return ''


class _Heard:
    """MuJoCo's warnings since the process took over its handler."""

    count = 0
    last = ''


def _hear(text: str) -> None:
    """Keep MuJoCo's warning (count, last text): no file, no print."""
    _Heard.count += 1
    _Heard.last = str(text)[:500]


def quiet_warnings() -> None:
    """
    Take MuJoCo's warnings over for this process: no file, no print.

    MuJoCo's default handler prints each warning and appends it to
    ``MUJOCO_LOG.TXT`` in the working directory; a simulation that
    diverges warns at every step (MuJoCo resets its state and warns
    again). A :class:`MujocoPlant` reads its step's warnings from
    ``mjData.warning`` and raises them; the text MuJoCo gives its handler
    is kept only as :attr:`_Heard.last`.
    """
    import mujoco
    if mujoco.get_mju_user_warning() is not _hear:
        mujoco.set_mju_user_warning(_hear)


class MujocoPlant:
    """
    The simulated robot in MuJoCo, with :class:`plant.Plant`'s interface.

    ``position``, ``velocity`` (3-tuples) and ``time`` (s) are read from
    MuJoCo; setting ``velocity`` (the simulator's brake sets it to zero)
    puts every joint at the closed form's rates for it. Building one
    takes MuJoCo's warnings over (:func:`quiet_warnings`).
    """

    # Its sliders are MuJoCo's slide joints (:meth:`joint_state`).
    closed_form = False

    def __init__(self, robot: Robot, position: Vector = ZERO,
                 velocity: Vector = ZERO, time: float = 0.0,
                 force_limit: Union[float, Vector] = math.inf,
                 margin: float = DEFAULT_SINGULARITY_MARGIN,
                 model_text: Optional[str] = None) -> None:
        """
        Build the model of ``robot``; check and set the initial state.

        ``model_text``: an MJCF to simulate instead (:func:`check_model`:
        ``orthoglide mjcf``'s names and ``robot``'s lengths; its masses,
        friction, armature and screw ripple its own). Either way the
        platform carries ``robot.payload`` (:meth:`carry`).
        """
        import mujoco
        quiet_warnings()
        self._mujoco = mujoco
        self.robot = robot
        self.force_limit = force_limits(force_limit, time)
        self.margin = margin
        self.model = mujoco.MjModel.from_xml_string(
            model_text or mjcf.mjcf(robot.replace(payload=0.0)))
        self.data = mujoco.MjData(self.model)
        self._warnings = self.data.warning.number   # a view, per warning
        self._platform = self.model.body('platform').id
        # The platform without a payload: its mass and inertia.
        self._own = (float(self.model.body_mass[self._platform]),
                     self.model.body_inertia[self._platform].copy())
        self.carry(robot.payload)
        self._dofs = {self.model.joint(i).name: (
            self.model.jnt_qposadr[i], self.model.jnt_dofadr[i])
            for i in range(self.model.njnt)}
        # The friction MuJoCo's joints cannot hold, applied as forces (a
        # model given as text has its own friction).
        self._extra_friction = model_text is None \
            and mjcf.held_by_mujoco(robot) != robot
        # The screw ripple the model records (none if it records none).
        self._recorded = mjcf.recorded(robot, numeric_data(self.model))
        self._ripple = any(term in mjcf.RECORDED
                           for term in self._recorded.active_terms)
        self._set(position, velocity)
        self.data.time = float(time)

    def _set(self, position, velocity):
        """Put every joint at the closed form's state (refused: raises)."""
        mechanics.solve(self.robot, position, velocity, ZERO, self.margin)
        values = mjcf.joint_values(self.robot, position, velocity)
        for name, (q, qd, _) in values.items():
            qpos, dof = self._dofs[name]
            self.data.qpos[qpos] = q
            self.data.qvel[dof] = qd
        self._mujoco.mj_forward(self.model, self.data)

    @property
    def position(self) -> Triple:
        """Return the platform centre G (m, frame 0)."""
        return tuple(float(c) for c in self.data.xpos[self._platform])

    @property
    def velocity(self) -> Triple:
        """Return the platform centre's speed vector (m/s, frame 0)."""
        twist = np.zeros(6)
        self._mujoco.mj_objectVelocity(
            self.model, self.data, self._mujoco.mjtObj.mjOBJ_BODY,
            self._platform, twist, 0)
        return tuple(float(c) for c in twist[3:])

    @velocity.setter
    def velocity(self, velocity: Vector) -> None:
        self._set(self.position, velocity)

    @property
    def time(self) -> float:
        """Return the simulated seconds since the start."""
        return float(self.data.time)

    def step(self, force: Vector, dt: float) -> 'PlantStep':
        """
        Apply ``force`` (N) held over ``dt`` (s) and advance the state.

        As :meth:`plant.Plant.step`; the acceleration reported is the
        platform's mean over the step. A step in which MuJoCo warned, or
        whose end state is not finite, raises :class:`plant.Diverged`.
        """
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f'dt must be finite and positive, got {dt!r} s')
        command, applied = clipped(force, self.force_limit)
        mujoco, model, data = self._mujoco, self.model, self.data
        saved = (data.qpos.copy(), data.qvel.copy(), data.time)
        before = self.velocity
        substeps = max(1, math.ceil(dt / mjcf.TIMESTEP - 1e-9))
        model.opt.timestep = dt / substeps
        data.ctrl[:] = applied      # the actuators, in JOINT_NAMES order
        slots = [self._dofs[name][1] for name in JOINT_NAMES]
        positions = [self._dofs[name][0] for name in JOINT_NAMES]
        half = 0.5 * model.opt.timestep
        # MuJoCo counts each warning in data.warning (and clears the
        # counts when it resets a diverged state): zero them, then any
        # count after the step is this step's.
        self._warnings[:] = 0
        heard = _Heard.count
        for _ in range(substeps):
            if self._extra_friction or self._ripple:
                data.qfrc_applied[slots] = np.negative(self._beyond(
                    data.qpos[positions], data.qvel[slots], half))
            mujoco.mj_step(model, data)
        mujoco.mj_forward(model, data)  # positions and velocities at the end
        position, velocity = self.position, self.velocity
        try:
            warned = self._warned(heard) if self._warnings.any() \
                or _Heard.count != heard else ''
            if warned or not all(math.isfinite(c)
                                 for c in position + velocity):
                raise Diverged(
                    f'MuJoCo: the step of {dt:g} s from time {saved[2]:.6g} '
                    f's under force {mechanics.format_vector(applied)} N: '
                    + (warned or 'the end state is not finite'))
            mechanics.solve(self.robot, position, velocity, ZERO,
                            self.margin)
        except (WorkspaceError, Diverged):
            data.qpos[:], data.qvel[:], data.time = saved
            mujoco.mj_forward(model, data)
            raise
        return PlantStep(
            tuple((v - w) / dt for v, w in zip(velocity, before)), applied,
            tuple(a != c for a, c in zip(applied, command)))

    def _beyond(self, lam, lamd, half):
        """
        Return the terms' forces (N) the model's joints leave out.

        The friction beyond the joints' at the sliders' speeds ``lamd``
        (m/s), and the ripple the model records at each slider's position
        in the middle of the step, ``lambda + half lambdadot`` (m; the
        force is held over the step, whose ``half`` is in s).
        """
        force = np.zeros(3)
        if self._extra_friction:
            force += mjcf.friction_beyond(self.robot, tuple(lamd))
        if self._ripple:
            force += mjcf.recorded_forces(self._recorded, lam + half * lamd,
                                          lamd)
        return force

    def _warned(self, heard):
        """Return MuJoCo's warnings of a step, joints named ('' if none)."""
        mujoco, model = self._mujoco, self.model
        texts = []
        for index in np.flatnonzero(self._warnings):
            kind = mujoco.mjtWarning(int(index))
            info = int(self.data.warning[int(index)].lastinfo)
            texts.append(mujoco.mju_warningText(kind, info)
                         + _joint_of(model, kind, info))
        if not texts and _Heard.count != heard:
            texts.append(_Heard.last)
        return ' '.join(texts)

    def carry(self, payload: float) -> None:
        """
        Carry ``payload`` (kg) on the platform from the next step on.

        The platform body's mass becomes its own plus ``payload``, its
        inertia scaled alike (MuJoCo reads both at every step).
        """
        mass, inertia = self._own
        self.model.body_mass[self._platform] = mass + payload
        self.model.body_inertia[self._platform] = inertia * (
            (mass + payload) / mass)
        self.robot = self.robot.replace(payload=payload)

    def joint_state(self) -> tuple[Triple, Triple]:
        """Return ``(lambda, lambdadot)`` (m, m/s) of the slide joints."""
        qpos, qvel = self.data.qpos, self.data.qvel
        slots = [self._dofs[name] for name in JOINT_NAMES]
        return (tuple(float(qpos[q]) for q, _ in slots),
                tuple(float(qvel[d]) for _, d in slots))


def _joint_of(model, kind, info):
    """Name the joint or actuator a MuJoCo warning's ``info`` indexes."""
    import mujoco
    warning = mujoco.mjtWarning
    if kind in (warning.mjWARN_INERTIA, warning.mjWARN_BADQVEL,
                warning.mjWARN_BADQACC) and 0 <= info < model.nv:
        return f' (joint {model.joint(model.dof_jntid[info]).name})'
    if kind == warning.mjWARN_BADQPOS and 0 <= info < model.nq:
        joint = int(np.searchsorted(model.jnt_qposadr, info, 'right')) - 1
        return f' (joint {model.joint(joint).name})'
    if kind == warning.mjWARN_BADCTRL and 0 <= info < model.nu:
        return f' (actuator {model.actuator(info).name})'
    return ''
