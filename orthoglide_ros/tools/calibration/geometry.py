"""
The geometric parameters a calibration may change, and what they move.

Every leg's geometry (doc/model.md#the-machine-as-built) as deviations
from a nominal robot's, ten per leg: its axis point in the leg's frame
(along the axis, across it twice), its direction's two tilts, its joint
offset, its bar length and its platform attachment (frame 0); with an
instrument in its own frame, the six values of the map from the base
frame into it. :func:`measured` is the measurement model, forward
kinematics (:func:`legs.intersect`) then the instrument's map;
:func:`jacobian` its derivative in closed form, by the implicit function
theorem on the legs' spheres (eq. 14 generalised)
(doc/calibration.md#identifiability).
"""

from __future__ import annotations

from collections import namedtuple
import math
from typing import Optional, Sequence, TYPE_CHECKING
import warnings

import numpy as np

from orthoglide_ros.model import legs
from orthoglide_ros.model.types import Array, Vector

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

# The drawing's axis each leg-frame column lies along, per leg: leg A's
# frame is (x, y, z), leg B's (y, z, x), leg C's (z, x, y) (legs.DRAWING_FRAMES).
_AXIS_NAMES = ('xyz', 'yzx', 'zxy')
# The size of a built Orthoglide's errors: 1 mm and 1 mrad. The Jacobian's
# columns are scaled by it (a column: what such an error moves the
# measurements by) and the least squares solves for deviations in it.
LENGTH_SCALE = 1e-3
ANGLE_SCALE = 1e-3

Parameter = namedtuple('Parameter', ('name', 'row', 'kind', 'leg', 'index',
                                     'unit', 'scale', 'priority'))
Parameter.__doc__ = """One geometric value a calibration may change.

``name``: as printed (``axis_point_a[y]``: the axis point's component
along the drawing's y, across leg A's axis); ``row``: the ``robot.*`` row
it changes (``instrument`` for the instrument's map); ``kind``: ``point``,
``direction``, ``offset``, ``length``, ``attachment``, ``translation`` or
``rotation``; ``leg``: 0, 1, 2 (A, B, C; None for the instrument);
``index``: its component (leg frame for a point, 1 or 2 for a direction's
tilt towards the leg frame's second or third column, frame 0 for an
attachment, the instrument's axes); ``unit``: ``m`` or ``rad``;
``scale``: a built robot's error of it (m, rad); ``priority``: which of
exactly dependent parameters carries their combination (the larger;
doc/calibration.md#identifiability).
"""

# Which of exactly dependent parameters is identified and which held
# (identifiability.identifiable): the instrument's pose before the legs
# (a laser tracker is set up anywhere, the robot's frame is its own); an
# offset before a point's move along its axis (the readings' zero, which
# moves the same); a point's move across its axis before the attachment
# (only their difference enters); among the legs, leg A's axis (its point
# across it, its direction) and leg B's component along x and tilt
# towards z last, so that a rigid motion of the whole robot against an
# instrument is held there: the robot's frame is then the one where A's
# axis and B's tilt about it are the nominal robot's.
PRIORITY_INSTRUMENT = 4.0
PRIORITY_LEG = 1.0
PRIORITY_FRAME = 0.5
PRIORITY_ALONG = 0.3
PRIORITY_ATTACHMENT = 0.2
# The parameters of the robot's frame (leg, kind, index): see above.
_FRAME = {(0, 'point', 1), (0, 'point', 2), (0, 'direction', 1),
          (0, 'direction', 2), (1, 'point', 2), (1, 'direction', 1)}


def _leg_parameters():
    out = []
    for leg, axes in enumerate(_AXIS_NAMES):
        suffix = 'abc'[leg]
        for index in range(3):
            priority = PRIORITY_ALONG if index == 0 else (
                PRIORITY_FRAME if (leg, 'point', index) in _FRAME
                else PRIORITY_LEG)
            out.append(Parameter(f'axis_point_{suffix}[{axes[index]}]',
                                 f'axis_point_{suffix}', 'point', leg, index,
                                 'm', LENGTH_SCALE, priority))
        for index in (1, 2):
            out.append(Parameter(
                f'axis_direction_{suffix}[{axes[index]}]',
                f'axis_direction_{suffix}', 'direction', leg, index, 'rad',
                ANGLE_SCALE, PRIORITY_FRAME
                if (leg, 'direction', index) in _FRAME else PRIORITY_LEG))
        out.append(Parameter(f'joint_offset[{suffix}]', 'joint_offset',
                             'offset', leg, leg, 'm', LENGTH_SCALE,
                             PRIORITY_LEG))
        out.append(Parameter(f'bar_length[{suffix}]', 'bar_length',
                             'length', leg, leg, 'm', LENGTH_SCALE,
                             PRIORITY_LEG))
        for index in range(3):
            out.append(Parameter(f'attachment_{suffix}[{"xyz"[index]}]',
                                 f'attachment_{suffix}', 'attachment', leg,
                                 index, 'm', LENGTH_SCALE,
                                 PRIORITY_ATTACHMENT))
    return tuple(out)


# The 30 values of the legs (ten per leg) and the instrument's 6: its map
# m = exp(omega) Q0 G + t0 + t from the base frame into its own.
LEG_PARAMETERS = _leg_parameters()
INSTRUMENT_PARAMETERS = tuple(
    Parameter(f'instrument.t{axis}', 'instrument', 'translation', None, i,
              'm', LENGTH_SCALE, PRIORITY_INSTRUMENT)
    for i, axis in enumerate('xyz')) + tuple(
    Parameter(f'instrument.r{axis}', 'instrument', 'rotation', None, i,
              'rad', ANGLE_SCALE, PRIORITY_INSTRUMENT)
    for i, axis in enumerate('xyz'))

Frame = namedtuple('Frame', ('rotation', 'translation'))
Frame.__doc__ = """The map ``m = rotation G + translation`` from the base frame.

Into the instrument's (3x3 and (3,)): its pose's start, fitted to the
measurements (:func:`rigid_fit`).
"""
IDENTITY = Frame(np.eye(3), np.zeros(3))


def parameters(instrument: bool) -> tuple[Parameter, ...]:
    """Return the parameters: the legs' 30, the instrument's 6 with it."""
    return LEG_PARAMETERS + (INSTRUMENT_PARAMETERS if instrument else ())


def deviated_legs(nominal: Sequence[legs.Leg],
                  deviation: Vector) -> tuple[legs.Leg, ...]:
    """
    Return the legs ``deviation`` (the 30 legs' values, m and rad) away.

    Leg i (nominal point ``a0``, frame ``R0`` of columns ``u0, y0, z0``):
    ``a = a0 + R0 p``, ``u = (u0 + b y0 + c z0) / |...|``, ``e = e0 + de``,
    ``L = L0 + dL``, ``r = r0 + dr``, its ten values ``(p, b, c, de, dL,
    dr)`` in the order of :data:`LEG_PARAMETERS`.
    """
    d = np.asarray(deviation, dtype=float)
    points, directions, offsets, lengths, attachments = [], [], [], [], []
    for i, leg in enumerate(nominal):
        p, b, c, de, dl, dr = (d[10 * i:10 * i + 3], d[10 * i + 3],
                               d[10 * i + 4], d[10 * i + 5], d[10 * i + 6],
                               d[10 * i + 7:10 * i + 10])
        frame = np.asarray(leg.frame)
        points.append(tuple(np.asarray(leg.point) + frame @ p))
        directions.append(tuple(frame[:, 0] + b * frame[:, 1]
                                + c * frame[:, 2]))
        offsets.append(float(leg.offset + de))
        lengths.append(float(leg.length + dl))
        attachments.append(tuple(np.asarray(leg.attachment) + dr))
    return legs.build(points, directions, tuple(offsets), tuple(lengths),
                      attachments)


def rotation(omega: Vector) -> Array:
    """Return ``exp([omega]x)`` (3x3), omega in rad (scipy's Rotation)."""
    from scipy.spatial.transform import Rotation
    return Rotation.from_rotvec(np.asarray(omega, dtype=float)).as_matrix()


def _left_jacobian(omega):
    """
    SO(3)'s left Jacobian: d exp(omega) x = -[exp(omega) x]x J dw.

    In closed form (scipy's Rotation has no Jacobian of the exponential).
    """
    w = np.asarray(omega, dtype=float)
    angle = math.sqrt(float(w @ w))
    k = _skew(w)
    if angle < 1e-8:
        return np.eye(3) + 0.5 * k
    return (np.eye(3) + (1.0 - math.cos(angle)) / angle ** 2 * k
            + (angle - math.sin(angle)) / angle ** 3 * k @ k)


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]],
                     [-v[1], v[0], 0.0]])


def instrument_map(start: Frame, deviation: Vector) -> Frame:
    """Return the map ``exp(omega) Q0``, ``t0 + t`` of the 6 values ``(t, omega)``."""
    d = np.asarray(deviation, dtype=float)
    return Frame(rotation(d[3:6]) @ start.rotation, start.translation + d[:3])


def measured(nominal: Sequence[legs.Leg], lam: Array, deviation: Array,
             start: Optional[Frame] = None) -> tuple[Array, Array]:
    """
    Return what an instrument reads at the joint readings ``lam`` (N, 3).

    ``(readings (N, 3) m, found (N,))``: the platform centre of the legs
    ``deviation`` away (:func:`deviated_legs`, its first 30 values) by
    :func:`legs.intersect`, mapped into the instrument's frame by its
    last 6 (:func:`instrument_map` from ``start``) when ``start`` is
    given. ``found`` as :func:`legs.intersect`'s.
    """
    built = deviated_legs(nominal, deviation[:30])
    position, found = legs.intersect(built, lam)
    if start is None:
        return position, found
    frame = instrument_map(start, deviation[30:36])
    return position @ frame.rotation.T + frame.translation, found


def jacobian(nominal: Sequence[legs.Leg], lam: Array, deviation: Array,
             start: Optional[Frame] = None) -> Array:
    """
    Return d readings / d parameters (N, 3, 30 or 36) at ``deviation``.

    By the implicit function theorem: leg i's sphere ``F_i = |w_i|^2 -
    L_i^2 = 0``, ``w_i = G + r_i - a_i - (lambda_i + e_i - L_i) u_i``,
    so ``dG = -A^-1 h`` with ``A``'s row i ``w_i`` and ``h_i = dF_i / 2``
    (a point's ``-w_i . dA``, a direction's ``-s_i w_i . du``, an offset's
    ``-w_i . u_i``, a length's ``w_i . u_i - L_i``, an attachment's ``w_i .
    dr``); the instrument's ``m = Q G + t``: ``dm = Q dG``, ``dm/dt = I``,
    ``dm/domega = -[Q G]x J_l(omega)``. Unscaled: m per m, m per rad.
    """
    deviation = np.asarray(deviation, dtype=float)
    built = deviated_legs(nominal, deviation[:30])
    position, _ = legs.intersect(built, lam)
    n = len(position)
    columns = np.zeros((n, 3, 30 + (6 if start is not None else 0)))
    w_rows = []
    for i, leg in enumerate(built):
        s = lam[:, i] + leg.offset - leg.length
        u = np.asarray(leg.direction)
        w_rows.append(position + np.asarray(leg.attachment)
                      - np.asarray(leg.point) - s[:, None] * u)
    inverse = np.linalg.inv(np.stack(w_rows, 1))        # (N, 3, 3)
    for i, (leg, nominal_leg) in enumerate(zip(built, nominal)):
        w = w_rows[i]
        frame = np.asarray(nominal_leg.frame)
        u = np.asarray(leg.direction)
        s = lam[:, i] + leg.offset - leg.length
        b, c = deviation[10 * i + 3], deviation[10 * i + 4]
        norm = math.sqrt(1.0 + b * b + c * c)
        h = np.empty((n, 10))
        h[:, 0:3] = -w @ frame                          # a = a0 + R0 p
        for k, column in ((3, 1), (4, 2)):              # u's tilts
            du = (frame[:, column] - u * (u @ frame[:, column])) / norm
            h[:, k] = -s * (w @ du)
        wu = w @ u
        h[:, 5] = -wu                                   # offset
        h[:, 6] = wu - leg.length                       # length
        h[:, 7:10] = w                                  # attachment
        columns[:, :, 10 * i:10 * i + 10] = -inverse[:, :, i, None] \
            * h[:, None, :]
    if start is None:
        return columns
    turn = instrument_map(start, deviation[30:36]).rotation
    columns[:, :, :30] = np.einsum('ij,njk->nik', turn, columns[:, :, :30])
    columns[:, :, 30:33] = np.eye(3)
    turned = position @ turn.T
    jl = _left_jacobian(deviation[33:36])
    columns[:, :, 33:36] = -np.einsum('nij,jk->nik',
                                      np.stack([_skew(g) for g in turned]),
                                      jl)
    return columns


def rigid_fit(positions: Array, readings: Array) -> Frame:
    """
    Return the rigid map best taking ``positions`` onto ``readings``.

    Kabsch's least squares of the centred points (scipy's
    ``Rotation.align_vectors``, a rotation, never a reflection):
    ``readings ~ rotation positions + translation``; (N, 3) each, N >= 3
    not on a line. Each set is scaled to at most 1 first (the rotation is
    the same), so that a reading near the largest double (1e308) leaves
    the finite numbers nowhere: the start is then poor, and the reading
    refused as far from the nominal robot (scipy's warning that the
    rotation is poorly defined is not shown).
    """
    from scipy.spatial.transform import Rotation
    p0, m0 = positions.mean(0), readings.mean(0)
    centred = [points / max(float(np.abs(points).max()), 1e-300)
               for points in (readings - m0, positions - p0)]
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', UserWarning)
        turn = Rotation.align_vectors(*centred)[0]
    return Frame(turn.as_matrix(), m0 - turn.apply(p0))


def calibrated_robot(nominal: Robot, deviation: Vector) -> Robot:
    """
    Return ``nominal`` with its legs ``deviation`` away (validated).

    Every other row (masses, friction, drives, terms) kept, the legs' as
    floats. Raises :class:`robot.ParameterError` for legs the robot
    refuses.
    """
    built = deviated_legs(nominal.legs, deviation[:30])
    rows = {}
    for leg, suffix in zip(built, 'abc'):
        rows[f'axis_point_{suffix}'] = _floats(leg.point)
        rows[f'axis_direction_{suffix}'] = _floats(leg.direction)
        rows[f'attachment_{suffix}'] = _floats(leg.attachment)
    rows['joint_offset'] = _floats(leg.offset for leg in built)
    rows['bar_length'] = _floats(leg.length for leg in built)
    return nominal.replace(**rows)


def _floats(values):
    return tuple(float(v) for v in values)


def rotation_vector(matrix: Array) -> Array:
    """Return the rotation vector (rad) of a rotation matrix (scipy's)."""
    from scipy.spatial.transform import Rotation
    return Rotation.from_matrix(matrix).as_rotvec()
