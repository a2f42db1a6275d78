"""
The Orthoglide as a URDF: a cut tree of the closed mechanism, without ROS.

The tree is cut where :mod:`mechanics` cuts it for virtual work (eq. 23):
each parallelogram at A7, legs B and C at their frame 5, leg A carrying
the platform; a joint state of every joint closes every cut. The names
are contracts (doc/mechanism_state_publisher.md#joints-and-links).
"""

from __future__ import annotations

from typing import Any, Callable, Sequence, TYPE_CHECKING
import functools
import math
import xml.etree.ElementTree as ET

import numpy as np

from orthoglide_ros.model import bodies, mechanics, terms
from orthoglide_ros.model.bodies import LEG_LABELS
from orthoglide_ros.model.mechanics import DEFAULT_SINGULARITY_MARGIN, ZERO
from orthoglide_ros.model.robot import JOINT_NAMES
from orthoglide_ros.model.types import Array, Triple

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.legs import Leg
    from orthoglide_ros.model.robot import Robot

BASE_LINK = 'base_link'
PLATFORM = 'platform'
# A leg's bodies in the tree: (body, link suffix, parent body, joint suffix,
# the LegJoints field the joint takes). Parent 0 is base_link; the slider's
# joint is named by joint_names.
CHAIN = (
    (1, 'slider', 0, None, 'lambda_'),
    (2, 'rod_a3a6', 1, 'phi21', 'phi21'),
    (3, 'bar_a3a4', 2, 'phi32', 'phi32'),
    (6, 'bar_a6a7', 2, 'phi62', 'phi32'),
    (4, 'rod_a4a7', 3, 'phi43', 'phi32'),
    (5, 'leg_end', 4, 'phi54', 'phi21'),
)
# The rate (LegJoints field) of each variable.
RATES = {'lambda_': 'lambdadot', 'phi21': 'omega21', 'phi32': 'omega32'}
# The key of each variable in a leg of :func:`bodies.elements`.
ELEMENT_KEYS = {'lambda_': 'lambda', 'phi21': 'phi21', 'phi32': 'phi32'}
# Joint limits are rounded outward to this step (m, rad). Their search: a
# grid of SEARCH_GRID points per axis, then SEARCH_ROUNDS rounds of
# SEARCH_SAMPLES normal samples around the SEARCH_KEEP best points so far,
# the spread (from the grid's step) times SEARCH_SHRINK each round.
LIMIT_STEP = 1e-4
SEARCH_GRID, SEARCH_ROUNDS, SEARCH_SAMPLES, SEARCH_KEEP = 41, 60, 2000, 20
SEARCH_SHRINK, SEARCH_SEED = 0.75, 12
# Effort limit of the sliders (N): the max_effort default of the simulator
# and the tracking controller (the model rates no actuator); velocity
# limits (m/s, rad/s): the model rates none, so a bound for tools only.
SLIDER_EFFORT = 1000.0
VELOCITY_LIMIT = 10.0
# Colours (RGBA): the legs as the axes of their sliders (A red, B green,
# C blue), the rods, sliders and rails grey, the platform light grey.
LEG_COLOURS = {'A': (0.85, 0.2, 0.2, 1.0), 'B': (0.2, 0.7, 0.3, 1.0),
               'C': (0.2, 0.4, 0.9, 1.0)}
GREY = {'rail': (0.55, 0.55, 0.55, 1.0), 'steel': (0.3, 0.3, 0.35, 1.0),
        'platform': (0.8, 0.8, 0.8, 1.0)}


def link_name(leg: str, body: int) -> str:
    """Return the URDF link of ``body`` (1-6) of ``leg`` ('A', 'B', 'C')."""
    for number, suffix, _, _, _ in CHAIN:
        if number == body:
            return f'{leg.lower()}_{suffix}'
    raise ValueError(f'no body {body}')


def moving_joints(joint_names: Sequence[str] = JOINT_NAMES
                  ) -> tuple[tuple[str, str, str], ...]:
    """
    Every non-fixed joint of the URDF, in the order a joint state lists it.

    The three sliders (``joint_names``, actuators A, B, C), then for legs
    a, b, c their revolute joints ``x_phi21, x_phi32, x_phi62, x_phi43,
    x_phi54``. Returns ``(name, leg, variable)`` triples: ``variable`` is
    the :class:`bodies.LegJoints` field of ``leg`` that the joint takes
    (its rate is ``RATES[variable]``).

    >>> [name for name, _, _ in moving_joints()][:4]
    ['slider_a', 'slider_b', 'slider_c', 'a_phi21']
    """
    joints = [(name, leg, 'lambda_') for name, leg in zip(joint_names, LEG_LABELS)]
    for leg in LEG_LABELS:
        joints += [(f'{leg.lower()}_{suffix}', leg, variable)
                   for _, _, _, suffix, variable in CHAIN if suffix]
    return tuple(joints)


def joint_limits(robot: Robot, margin: float = DEFAULT_SINGULARITY_MARGIN
                 ) -> dict[str, dict[str, tuple[float, float]]]:
    """
    Range of each leg's joint variables over the workspace within ``margin``.

    On the home branch of the forward kinematics
    (doc/mechanism_state_publisher.md#joints-and-links). Returns ``{'A':
    {'lambda_': (low, high), 'phi21': ..., 'phi32': ...}, 'B': ..., 'C':
    ...}`` (m, rad), rounded outward to LIMIT_STEP: each leg's own on a
    robot as built; on the drawing's, whose legs B and C are leg A turned
    about the diagonal (its workspace symmetric under that turn), leg A's
    for all three. Found by a grid over the cube ``|x|, |y|, |z| < max_i(L_i
    + |a_i - r_i|)`` (``l3`` on the drawing), then seeded random samples
    around the best points down to about 1e-9 m (1-3 s per leg searched,
    remembered for the last robots asked).
    """
    return {leg: dict(limits) for leg, limits in _joint_limits(
        robot, float(margin))}


@functools.lru_cache(maxsize=8)
def _joint_limits(robot, margin):
    """Return :func:`joint_limits` as ``(leg, ((variable, limits), ...))``."""
    searched = ('A',) if robot.as_drawn else LEG_LABELS
    found = {}
    for leg in searched:
        limits = []
        for variable in ('lambda_', 'phi21', 'phi32'):
            low = -_extreme(robot, margin, leg, variable, -1.0)
            high = _extreme(robot, margin, leg, variable, 1.0)
            limits.append((variable, (
                round(math.floor(low / LIMIT_STEP) * LIMIT_STEP, 10),
                round(math.ceil(high / LIMIT_STEP) * LIMIT_STEP, 10))))
        found[leg] = tuple(limits)
    return tuple((leg, found.get(leg, found['A'])) for leg in LEG_LABELS)


def _extreme(robot, margin, leg, variable, sign):
    """Largest ``sign * variable`` of ``leg`` over the workspace."""
    extent = max(other.length + math.dist(other.point, other.attachment)
                 for other in robot.legs)

    def values(points):
        ok = mechanics.workspace_status(robot, points, margin).ok
        points = points[ok]
        if not len(points):
            return points, np.empty(0)
        # Inside the margin by workspace_status: solved without it, so a
        # point on the margin's very edge is not refused by rounding.
        legs = bodies.leg_joints(robot, points, None, 0.0)
        # Only the home branch: the positions the forward kinematics gives
        # back (the others lie beyond a singularity of J2).
        back, found = mechanics.forward_kinematics_rows(
            robot, np.column_stack([legs[name].lambda_
                                    for name in LEG_LABELS]))
        home = found & (np.abs(back - points).max(-1) <= 1e-9 * extent)
        return points[home], sign * getattr(legs[leg], variable)[home]

    axis = np.linspace(-extent, extent, SEARCH_GRID)
    points, found = values(_grid(ZERO, axis))
    # The best points so far, each sampled around with a spread that
    # shrinks every round (a workspace edge may be curved or have corners,
    # where a search along the axes stalls). Seeded: the same limits for
    # the same robot.
    rng = np.random.default_rng(SEARCH_SEED)
    spread = axis[1] - axis[0]
    for _ in range(SEARCH_ROUNDS):
        best = np.argsort(found)[-SEARCH_KEEP:]
        points, found = points[best], found[best]
        near = np.repeat(points, SEARCH_SAMPLES // len(points), 0)
        more, more_found = values(near + rng.normal(0.0, spread, near.shape))
        points = np.concatenate((points, more))
        found = np.concatenate((found, more_found))
        spread *= SEARCH_SHRINK
    return float(found.max())


def _grid(centre, offsets):
    """Return the points ``centre + (a, b, c)`` for a, b, c in offsets."""
    mesh = np.meshgrid(offsets, offsets, offsets, indexing='ij')
    return np.stack(mesh, -1).reshape(-1, 3) + np.asarray(centre)


def inertials(robot: Robot, leg: Leg) -> dict[int, Any]:
    """
    Return doc/model.md's bodies table: ``{body: (mass, centre, inertia)}``.

    ``leg``'s bodies 1, 2, 3, 4, 6 (its bars of its own length ``L_i``)
    and the platform 5 (the robot's, counted once): mass (kg), centre of
    mass (m, from the body's frame origin, in its frame) and inertia about
    the centre of mass (kg m^2, 3x3, in the body's frame). Body 1 only
    translates and the model gives it no inertia: zero. The platform
    carries ``robot.payload``: its mass is :func:`terms.platform_mass` (a
    body that only translates, its inertia scaled alike).
    """
    l2, length = robot.l2, leg.length
    sa, ca = math.sin(robot.alpha), math.cos(robot.alpha)
    platform = terms.platform_mass(robot)
    return {
        1: (robot.m1, (0.0, robot.l1 * sa / 2.0, robot.l1 * ca / 2.0),
            np.zeros((3, 3))),
        2: (robot.m2, ZERO, robot.m2 * l2 ** 2 / 12.0 * np.diag((1, 1, 0))),
        3: (robot.m3, (0.0, -length / 2.0, 0.0),
            robot.m3 * length ** 2 / 12.0 * np.diag((1, 0, 1))),
        6: (robot.m6, (0.0, -length / 2.0, 0.0),
            robot.m6 * length ** 2 / 12.0 * np.diag((1, 0, 1))),
        4: (robot.m4, (l2 / 2.0, 0.0, 0.0),
            robot.m4 * l2 ** 2 / 12.0 * np.diag((0, 1, 1))),
        5: (platform, ZERO, platform * robot.l ** 2 / 6.0 * np.eye(3)),
    }


def urdf(robot: Robot, joint_names: Sequence[str] = JOINT_NAMES,
         margin: float = DEFAULT_SINGULARITY_MARGIN) -> str:
    """
    Return the URDF (XML text) of ``robot``, sliders named ``joint_names``.

    Joint limits over the workspace within ``margin`` (see the module's
    docstring for the tree and its names). Plain text, the same for the
    same arguments.
    """
    home = bodies.elements(robot, ZERO)
    limits = joint_limits(robot, margin)
    masses = {label: inertials(robot, leg)
              for label, leg in zip(LEG_LABELS, robot.legs)}
    radius = robot.l2 / 8.0
    root = ET.Element('robot', name='orthoglide')
    root.append(header_comment(
        robot, 'urdf', _number, f'; joint limits within the singularity '
        f'margin {margin:g}. A cut tree: publish every moving joint '
        '(mechanism_state_publisher). URDF has no place for a drive\'s '
        'reflected inertia: robot.armature above is for the tools that take '
        'it (Pinocchio\'s Model.armature, MuJoCo\'s joint armature); the '
        'platform link\'s mass holds robot.payload. '))
    for name, rgba in [*((f'leg_{leg.lower()}', c)
                         for leg, c in LEG_COLOURS.items()),
                       *GREY.items()]:
        ET.SubElement(ET.SubElement(root, 'material', name=name), 'color',
                      rgba=_vector(rgba))

    base = _link(root, BASE_LINK)
    for leg in LEG_LABELS:
        low, high = limits[leg]['lambda_']
        axis, a1 = slider_axis(home[leg])
        _shape(base, 'cylinder', 'rail', radius,
               a1 + low * axis, a1 + high * axis)
    for leg, name in zip(LEG_LABELS, joint_names):
        _leg(root, leg, name, home[leg], limits[leg], masses[leg], radius)

    platform = _link(root, PLATFORM, masses['A'][5])
    _shape(platform, 'box', 'platform', (robot.l,) * 3)
    a_end = home['A']['bodies'][5]
    _joint(root, 'platform_joint', 'fixed', link_name('A', 5), PLATFORM,
           a_end['rotation'] @ (home['A']['joints']['G'] - a_end['origin']),
           a_end['rotation'])
    centre = home['A']['joints']['G']
    for leg in LEG_LABELS:
        end = home[leg]['bodies'][5]
        mount = f'{leg.lower()}_platform_mount'
        _link(root, mount)
        _joint(root, f'{mount}_joint', 'fixed', PLATFORM, mount,
               end['origin'] - centre, end['rotation'].T)
        _shape(platform, 'cylinder', 'platform', radius, ZERO,
               end['origin'] - centre)
    ET.indent(root, '  ')
    return ('<?xml version="1.0"?>\n'
            + ET.tostring(root, encoding='unicode') + '\n')


def slider_axis(home: dict[str, Any]) -> tuple[Array, Array]:
    """
    Return a leg's actuator axis: ``(u_i, A1 at lambda_i = 0)`` (frame 0).

    ``home``: the leg's :func:`bodies.elements` at any state; ``u_i`` is
    its slider's z axis, along which A1 moves with lambda (m).
    """
    axis = home['bodies'][1]['rotation'].T[:, 2]
    return axis, home['joints']['A1'] - home['lambda'] * axis


def _leg(root, leg, slider_joint, home, limits, masses, radius):
    """
    Add one leg's links and joints (bodies 1-6, the A7 cut).

    Each joint's origin is its child's frame seen from its parent's at
    joint value 0: the frames of ``home`` (the platform at the origin)
    with the slider moved back by its lambda and each revolute joint's
    child turned back by its angle about z, so that a joint state of the
    model's values (:func:`bodies.leg_joints`) puts every body where the
    model does, on the drawing's robot as on one built.
    """
    frames = home['bodies']
    prefix = leg.lower()
    colour = f'leg_{prefix}'
    for body, _, parent, suffix, variable in CHAIN:
        link = _link(root, link_name(leg, body),
                     masses[body] if body != 5 else None)
        frame = frames[body]
        if parent == 0:
            rotation, origin = np.eye(3), np.zeros(3)
        else:
            rotation = frames[parent]['rotation']
            origin = frames[parent]['origin']
        xyz = rotation @ (frame['origin'] - origin)
        turn = rotation @ frame['rotation'].T     # the child's axes
        value = home[ELEMENT_KEYS[variable]]
        if body == 1:
            xyz = xyz - value * turn[:, 2]
        else:
            turn = turn @ bodies.rotation_z(math.sin(value), math.cos(value))
        name = slider_joint if suffix is None else f'{prefix}_{suffix}'
        _joint(root, name, 'prismatic' if body == 1 else 'revolute',
               BASE_LINK if parent == 0 else link_name(leg, parent),
               link_name(leg, body), xyz, turn, limits[variable],
               SLIDER_EFFORT if body == 1 else 0.0)
        _body_shapes(link, body, home, colour, radius)
    # The cut at A7: two frames with body 6's axes at joint value 0, so
    # that the rod's stands turned by -phi32 about z from the bar's (the
    # cut joint's angle): at home the rod's turned back by home's phi32.
    joints = home['joints']
    for body, side, turned in ((6, 'bar', 0.0), (4, 'rod', home['phi32'])):
        frame = frames[body]
        tip = f'{prefix}_a7_{side}'
        _link(root, tip)
        _joint(root, f'{tip}_joint', 'fixed', link_name(leg, body), tip,
               frame['rotation'] @ (joints['A7'] - frame['origin']),
               frame['rotation'] @ frames[6]['rotation'].T
               @ bodies.rotation_z(math.sin(turned), math.cos(turned)))


def _body_shapes(link, body, home, colour, radius):
    """Add the visual and collision shapes of one body (its own frame)."""
    frame = home['bodies'][body]

    def local(joint):
        return frame['rotation'] @ (home['joints'][joint] - frame['origin'])

    if body == 1:
        size = 6.0 * radius
        _shape(link, 'box', 'steel', (size, size, 2.0 * size))
        _shape(link, 'cylinder', 'steel', radius, ZERO, local('A2'))
    elif body == 2:
        _shape(link, 'cylinder', 'steel', radius, local('A3'), local('A6'))
    elif body in (3, 6):
        start = 'A3' if body == 3 else 'A6'
        end = local('A4') if body == 3 else local('A7')
        _shape(link, 'cylinder', colour, radius, local(start), end)
    elif body == 4:
        _shape(link, 'cylinder', 'steel', radius, ZERO,
               2.0 * local('A5'))


def _link(root, name, inertial=None):
    """Add a link; ``inertial`` is ``(mass, centre, inertia)`` or None."""
    link = ET.SubElement(root, 'link', name=name)
    if inertial is not None:
        mass, centre, inertia = inertial
        element = ET.SubElement(link, 'inertial')
        ET.SubElement(element, 'origin', xyz=_vector(centre), rpy='0 0 0')
        ET.SubElement(element, 'mass', value=_number(mass))
        ET.SubElement(element, 'inertia', **{
            key: _number(inertia[i][j]) for key, (i, j) in (
                ('ixx', (0, 0)), ('ixy', (0, 1)), ('ixz', (0, 2)),
                ('iyy', (1, 1)), ('iyz', (1, 2)), ('izz', (2, 2)))})
    return link


def _joint(root, name, kind, parent, child, xyz, rotation, limits=None,
           effort=0.0):
    """Add a joint whose origin is ``(xyz, rotation)`` in the parent."""
    joint = ET.SubElement(root, 'joint', name=name, type=kind)
    ET.SubElement(joint, 'parent', link=parent)
    ET.SubElement(joint, 'child', link=child)
    ET.SubElement(joint, 'origin', xyz=_vector(xyz),
                  rpy=_vector(rpy(rotation)))
    if kind != 'fixed':
        ET.SubElement(joint, 'axis', xyz='0 0 1')
        ET.SubElement(joint, 'limit', lower=_number(limits[0]),
                      upper=_number(limits[1]), effort=_number(effort),
                      velocity=_number(VELOCITY_LIMIT))


def _shape(link, kind, material, size, start=None, end=None):
    """
    Add the same visual and collision shape to a link.

    A box of ``size`` (3 lengths, m) at the link's origin, or a cylinder of
    radius ``size`` from ``start`` to ``end`` (m, the link's frame).
    """
    if kind == 'box':
        xyz, rotation, geometry = ZERO, np.eye(3), {'size': _vector(size)}
    else:
        start, end = np.asarray(start, float), np.asarray(end, float)
        xyz = (start + end) / 2.0
        rotation = _z_towards(end - start)
        geometry = {'radius': _number(size),
                    'length': _number(np.linalg.norm(end - start))}
    for role in ('visual', 'collision'):
        element = ET.SubElement(link, role)
        ET.SubElement(element, 'origin', xyz=_vector(xyz),
                      rpy=_vector(rpy(rotation)))
        ET.SubElement(ET.SubElement(element, 'geometry'), kind, **geometry)
        if role == 'visual':
            ET.SubElement(element, 'material', name=material)


def _z_towards(direction):
    """Return a rotation whose z axis points along ``direction``."""
    z = np.asarray(direction, float) / np.linalg.norm(direction)
    helper = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack((x, np.cross(z, x), z))


def rpy(rotation: Array) -> Triple:
    """
    Return URDF's roll, pitch and yaw (rad) of a rotation matrix.

    URDF composes ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (fixed axes x, y,
    z). At pitch = +-pi/2 only roll - yaw (or roll + yaw) is defined: yaw
    is then 0.

    >>> [abs(round(v, 12)) for v in rpy([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])]
    [0.0, 1.570796326795, 0.0]
    """
    r = np.asarray(rotation, dtype=float)
    cos_pitch = math.hypot(r[0, 0], r[1, 0])
    pitch = math.atan2(-r[2, 0], cos_pitch)
    if cos_pitch < 1e-9:
        return (math.atan2(-r[1, 2], r[1, 1]), pitch, 0.0)
    return (math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0]))


def header_comment(robot: Robot, command: str,
                   number: Callable[[float], str], tail: str) -> ET.Element[Any]:
    """
    Return the comment that opens a model file: its robot, how it was made.

    ``command``: the ``orthoglide`` command that writes the file;
    ``number``: its number format; ``tail``: what the file adds.
    """
    return ET.Comment(
        ' The Orthoglide (Chablat, Wenger, Staicu), written by `orthoglide '
        f'{command}` from the robot.* parameters: '
        + ', '.join(f'{k} = {v if isinstance(v, list) else number(v)}'
                    for k, v in robot.as_parameters().items()) + tail)


def _number(value):
    """Format a number: 12 significant digits, no ``-0``, tiny values 0."""
    value = float(value)
    if abs(value) < 1e-12:
        value = 0.0
    return f'{value:.12g}'


def _vector(values):
    return ' '.join(_number(v) for v in values)
