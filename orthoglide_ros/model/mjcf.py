"""
The Orthoglide as MJCF: MuJoCo's model, with the loops closed, without ROS.

The bodies of :mod:`urdf` as a tree closed by ``connect`` equality
constraints where :mod:`mechanics` cuts the mechanism (A7; A5 of legs B
and C); the :mod:`terms` MuJoCo's joints cannot hold are left to the
plant: friction to :func:`friction_beyond`, the screw ripple (RECORDED,
written in the file's ``custom`` data) to :func:`recorded_forces`
(doc/mujoco.md).
"""

from __future__ import annotations

from typing import Any, Mapping, Optional, Sequence, TYPE_CHECKING
import functools
import xml.etree.ElementTree as ET

import numpy as np

from orthoglide_ros.model import mechanics, terms
from orthoglide_ros.model.bodies import elements, LEG_LABELS
from orthoglide_ros.model.mechanics import ZERO
from orthoglide_ros.model.robot import JOINT_NAMES
from orthoglide_ros.model.urdf import (CHAIN, ELEMENT_KEYS, GREY,
                                       header_comment, inertials,
                                       LEG_COLOURS, link_name, PLATFORM,
                                       slider_axis)
from orthoglide_ros.model.types import Vector

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

MIN_INERTIA = 1e-9          # kg m^2: a principal inertia the model has 0
TIMESTEP = 0.001            # s
INTEGRATOR = 'RK4'
SOLREF = (0.002, 1.0)       # the stiffest MuJoCo allows at TIMESTEP (2 dt)
SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)


# The terms MuJoCo's slide joints hold (their MJCF attribute).
HELD = tuple(term for term in terms.FORCES if term.mujoco)
# The terms no MJCF element holds that are no friction (the screw ripple):
# their rows are written as custom numeric data named ``robot.<row>``, and
# the MuJoCo plant applies them as forces from the model it steps.
RECORDED = tuple(term for term in terms.FORCES
                 if not term.mujoco and not term.friction)
RECORDED_ROWS = tuple(row for term in RECORDED for row in term.rows)


def friction_beyond(robot: Robot, lambdadot: Any) -> Any:
    """
    Return the friction MuJoCo's joints leave out (N, 3-tuple), at speeds.

    The package's law (:func:`mechanics.friction_force`) less the
    friction of the terms MuJoCo holds (HELD, with their coefficients
    there: one Coulomb level, the mean of both directions').
    """
    return tuple(a - b for a, b in zip(
        mechanics.friction_force(robot, lambdadot),
        mechanics.friction_force(held_by_mujoco(robot), lambdadot)))


def recorded(robot: Robot, numeric: Mapping[str, Any]) -> Robot:
    """
    Return ``robot`` with the RECORDED rows of an MJCF's ``custom`` data.

    ``numeric``: the model's numeric data by name (``robot.screw_lead``:
    three values); a row the model does not record takes its default (no
    ripple). Validated: a value no robot has raises
    :class:`robot.ParameterError`.
    """
    return robot.replace(**{row.name: tuple(float(v) for v in numeric.get(
        f'robot.{row.name}', row.default)) for row in RECORDED_ROWS})


def recorded_forces(robot: Robot, lambda_: Vector,
                    lambdadot: Vector) -> tuple[float, float, float]:
    """
    Return the RECORDED terms' forces (N, A, B, C) at the sliders' state.

    ``lambda_`` (m) and ``lambdadot`` (m/s): 3-sequences. The forces the
    actuators overcome (the MuJoCo plant applies their opposite).
    """
    active = tuple(term for term in robot.active_terms if term in RECORDED)
    if not active:
        return ZERO
    fa, fb, fc = terms.forces(robot, active, tuple(map(float, lambda_)),
                              tuple(map(float, lambdadot)), ZERO,
                              terms.FLOATS)
    return fa, fb, fc


@functools.lru_cache(maxsize=16)
def held_by_mujoco(robot: Robot) -> Robot:
    """Return ``robot`` as MuJoCo's joints hold it (made once)."""
    return terms.reduced(robot, HELD)


def mjcf(robot: Robot, joint_names: Sequence[str] = JOINT_NAMES,
         force_limit: Optional[float] = None) -> str:
    """
    Return the MJCF (XML text) of ``robot``; sliders named ``joint_names``.

    ``force_limit`` (N, optional): the actuators' control range +-it.
    ``robot.armature`` (kg, per slider A, B, C) is each slide joint's
    ``armature``, MuJoCo's name for a drive's rotor inertia reflected onto
    it; ``robot.payload`` rides in the platform's mass; the screw ripple
    (RECORDED) is ``custom`` numeric data ``robot.screw_lead``, ...,
    written when the robot has it. Plain text, the same for the same
    arguments.
    """
    home = elements(robot, ZERO)
    masses = {label: inertials(robot, leg)
              for label, leg in zip(LEG_LABELS, robot.legs)}
    radius = robot.l2 / 8.0
    root = ET.Element('mujoco', model='orthoglide')
    root.append(header_comment(
        robot, 'mjcf', _number, '. Loops closed by connect constraints; see '
        'doc/mujoco.md. '))
    ET.SubElement(root, 'compiler', angle='radian', autolimits='true')
    if any(getattr(robot, row.name) != row.default for row in RECORDED_ROWS):
        custom = ET.SubElement(root, 'custom')
        for row in RECORDED_ROWS:
            ET.SubElement(custom, 'numeric', name=f'robot.{row.name}',
                          size='3', data=_vector(getattr(robot, row.name)))
    ET.SubElement(root, 'option', timestep=_number(TIMESTEP),
                  integrator=INTEGRATOR, gravity=_vector(robot.gravity))
    default = ET.SubElement(root, 'default')
    ET.SubElement(default, 'geom', contype='0', conaffinity='0')
    ET.SubElement(default, 'equality', solref=_vector(SOLREF),
                  solimp=_vector(SOLIMP))
    asset = ET.SubElement(root, 'asset')
    for name, rgba in [*((f'leg_{leg.lower()}', c)
                         for leg, c in LEG_COLOURS.items()),
                       *GREY.items()]:
        ET.SubElement(asset, 'material', name=name, rgba=_vector(rgba))
    ET.SubElement(asset, 'texture', name='sky', type='skybox',
                  builtin='gradient', rgb1='0.95 0.97 1', rgb2='0.6 0.65 0.75',
                  width='256', height='256')

    world = ET.SubElement(root, 'worldbody')
    ET.SubElement(world, 'light', pos='1 1 2', dir='-0.5 -0.5 -1',
                  directional='true')
    for leg, built in zip(LEG_LABELS, robot.legs):
        axis, a1 = slider_axis(home[leg])
        ET.SubElement(world, 'geom', type='cylinder', material='rail',
                      size=_number(radius), fromto=_vector(np.concatenate(
                          (a1 - built.length * axis,
                           a1 + built.length * axis))))
    held = held_by_mujoco(robot)
    for j, (leg, name) in enumerate(zip(LEG_LABELS, joint_names)):
        slide = {term.mujoco: _number(getattr(
            held, terms.coefficient_name(term))[j]) for term in HELD}
        _leg(world, robot, leg, name, home, masses[leg], radius, slide)

    equality = ET.SubElement(root, 'equality')
    for leg in LEG_LABELS:
        bodies, joints = home[leg]['bodies'], home[leg]['joints']
        prefix = leg.lower()
        ET.SubElement(equality, 'connect', name=f'{prefix}_a7',
                      body1=link_name(leg, 6), body2=link_name(leg, 4),
                      anchor=_vector(_local(bodies[6], joints['A7'])))
        if leg != 'A':
            z5 = bodies[5]['rotation'].T[:, 2]
            for name, point in (('a5', joints['A5']),
                                ('a5_axis', joints['A5'] + robot.l2 * z5)):
                ET.SubElement(equality, 'connect', name=f'{prefix}_{name}',
                              body1=link_name(leg, 4), body2=PLATFORM,
                              anchor=_vector(_local(bodies[4], point)))

    actuator = ET.SubElement(root, 'actuator')
    for name in joint_names:
        attributes = {'name': name, 'joint': name, 'gear': '1'}
        if force_limit:
            attributes['ctrlrange'] = _vector((-force_limit, force_limit))
        ET.SubElement(actuator, 'motor', attributes)
    ET.indent(root, '  ')
    return ET.tostring(root, encoding='unicode') + '\n'


def _leg(world, robot, leg, slider_joint, home, masses, radius, slide):
    """
    Add one leg's bodies (1, 2, 3, 6, 4; the platform on leg A's 4).

    The bodies where they are at home, the platform at the origin (there
    every loop closes): each joint's ``ref`` is its value there
    (:func:`ref`), 0 on the drawing's robot.
    """
    bodies, joints = home[leg]['bodies'], home[leg]['joints']
    prefix = leg.lower()
    colour = f'leg_{prefix}'
    parents = {0: world}
    for body, _, parent, suffix, variable in CHAIN:
        if body == 5:
            continue
        element = _body(parents[parent], link_name(leg, body), bodies[body],
                        bodies.get(parent), masses[body])
        parents[body] = element
        reference = ref(home[leg], variable)
        if body == 1:
            ET.SubElement(element, 'joint', name=slider_joint, type='slide',
                          axis='0 0 1', **reference, **slide)
        else:
            ET.SubElement(element, 'joint', name=f'{prefix}_{suffix}',
                          type='hinge', axis='0 0 1', **reference)
        _shapes(element, body, bodies[body], joints, colour, radius)
    if leg == 'A':
        platform = ET.SubElement(
            parents[4], 'body', name=PLATFORM,
            pos=_vector(_local(bodies[4], joints['G'])),
            xyaxes=_xyaxes(bodies[4]['rotation'].T))
        z5 = bodies[5]['rotation'].T[:, 2]      # frame 0 = the platform's
        ET.SubElement(platform, 'joint', name='a_phi54', type='hinge',
                      pos=_vector(joints['A5'] - joints['G']),
                      axis=_vector(z5), **ref(home[leg], 'phi21'))
        _inertial(platform, masses[5])
        ET.SubElement(platform, 'geom', type='box', material='platform',
                      size=_vector((robot.l / 2.0,) * 3))
        for other in LEG_LABELS:
            mount = home[other]['joints']['A5'] - home[other]['joints']['G']
            ET.SubElement(platform, 'geom', type='cylinder',
                          material='platform', size=_number(radius),
                          fromto=_vector(np.concatenate((ZERO, mount))))
            ET.SubElement(platform, 'site', name=f'{other.lower()}_mount',
                          pos=_vector(mount), size=_number(radius))


def ref(home: dict[str, Any], variable: str) -> dict[str, str]:
    """
    Return a joint's ``ref`` attribute: its value at home, none where 0.

    ``home``: the leg's :func:`bodies.elements` with the platform at the
    origin; ``variable``: the :class:`bodies.LegJoints` field the joint
    takes. MuJoCo's ``ref`` is the joint value of the bodies as written
    (qpos0), so qpos is the model's value everywhere.
    """
    value = home[ELEMENT_KEYS[variable]]
    return {'ref': _number(value)} if value != 0.0 else {}


def _body(parent, name, frame, parent_frame, inertial):
    """Add a body at ``frame`` (of bodies.elements), seen from its parent."""
    if parent_frame is None:
        pos, rotation = frame['origin'], frame['rotation'].T
    else:
        pos = _local(parent_frame, frame['origin'])
        rotation = parent_frame['rotation'] @ frame['rotation'].T
    body = ET.SubElement(parent, 'body', name=name, pos=_vector(pos),
                         xyaxes=_xyaxes(rotation.T))
    _inertial(body, inertial)
    return body


def _inertial(body, inertial):
    mass, centre, inertia = inertial
    inertia = np.array(inertia, dtype=float)
    values, vectors = np.linalg.eigh(inertia)
    inertia = vectors @ np.diag(np.maximum(values, MIN_INERTIA)) @ vectors.T
    ET.SubElement(body, 'inertial', pos=_vector(centre), mass=_number(mass),
                  fullinertia=_vector((
                      inertia[0, 0], inertia[1, 1], inertia[2, 2],
                      inertia[0, 1], inertia[0, 2], inertia[1, 2])))


def _shapes(body, number, frame, joints, colour, radius):
    """Add the visual geoms of one body (its own frame), as the URDF's."""
    def local(joint):
        return _local(frame, joints[joint])

    def rod(material, start, end):
        ET.SubElement(body, 'geom', type='capsule', material=material,
                      size=_number(radius), fromto=_vector(
                          np.concatenate((start, end))))

    if number == 1:
        size = 3.0 * radius
        ET.SubElement(body, 'geom', type='box', material='steel',
                      size=_vector((size, size, 2.0 * size)))
        rod('steel', ZERO, local('A2'))
    elif number == 2:
        rod('steel', local('A3'), local('A6'))
    elif number == 3:
        rod(colour, ZERO, local('A4'))
    elif number == 6:
        rod(colour, ZERO, local('A7'))
    elif number == 4:
        rod('steel', ZERO, local('A5'))


def _local(frame, point):
    """Return a point of frame 0 in ``frame`` (of bodies.elements)."""
    return frame['rotation'] @ (np.asarray(point) - frame['origin'])


def _xyaxes(rotation):
    """Return MJCF ``xyaxes``: a frame's x and y axes in its parent's."""
    rotation = np.asarray(rotation)     # rows: the axes, in the parent
    return _vector(np.concatenate((rotation[0], rotation[1])))


def _number(value):
    """Format a number at full precision (repr), ``-0`` as 0."""
    value = float(value)
    return '0' if value == 0.0 else repr(value)


def _vector(values):
    return ' '.join(_number(v) for v in values)


def joint_values(robot: Robot, position: Vector, velocity: Vector = ZERO,
                 acceleration: Vector = ZERO,
                 joint_names: Sequence[str] = JOINT_NAMES
                 ) -> dict[str, tuple[float, float, float]]:
    """
    Return every MJCF joint's ``{name: (q, qdot, qddot)}`` at a platform state.

    From :func:`bodies.elements` (eqs. 9, 13 and their derivatives):
    the sliders' lambda, the hinges' phi21 (``x_phi21``, ``a_phi54``) and
    phi32 (``x_phi32``, ``x_phi62``, ``x_phi43``), by eq. (5); m, rad and
    their rates.
    """
    legs = elements(robot, position, velocity, acceleration)
    values = {}
    for leg, name in zip(LEG_LABELS, joint_names):
        e, prefix = legs[leg], leg.lower()
        values[name] = (e['lambda'], e['lambdadot'], e['lambdaddot'])
        angle = {n: (e[f'phi{n}'], e[f'omega{n}'], e[f'epsilon{n}'])
                 for n in ('21', '32')}
        for suffix, n in (('phi21', '21'), ('phi32', '32'),
                          ('phi62', '32'), ('phi43', '32')):
            values[f'{prefix}_{suffix}'] = angle[n]
        if leg == 'A':
            values['a_phi54'] = angle['21']
    return values
