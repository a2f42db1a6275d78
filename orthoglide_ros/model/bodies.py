"""
Every body and every joint of the Orthoglide at one state (section 2).

:func:`elements`: every body of every leg, eqs. (1)-(12) and (19);
:func:`leg_joints`: every leg's joint variables and rates, eqs. (9) and
(13), for the URDF's and MuJoCo's joints. Both read the kernel's record
after :func:`mechanics.solve` or :func:`mechanics.solve_batch` has checked
the state, so they refuse what those refuse.
"""

from __future__ import annotations

from typing import Any, Callable, TYPE_CHECKING
from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.model.mechanics import (DEFAULT_SINGULARITY_MARGIN,
                                            kernel_solve, solve, solve_batch,
                                            ZERO)
from orthoglide_ros.model.robot import LEGS
from orthoglide_ros.model.types import Array, Vector

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

# The paper's names of the legs, A, B, C: the keys of a solution's records.
LEG_LABELS = tuple(leg.upper() for leg in LEGS)

LegJoints = namedtuple('LegJoints', (
    'lambda_', 'phi21', 'phi32', 'lambdadot', 'omega21', 'omega32'))
LegJoints.__doc__ = """One leg's joint variables and their rates.

``lambda_`` (m) and ``lambdadot`` (m/s) of the slider; ``phi21``,
``phi32`` (rad) of eq. (9) and their rates ``omega21``, ``omega32``
(rad/s) of eq. (13), in the passive convention of ``a^phi`` (a rate about
the child frame's ``u3``). By eq. (5) ``phi54 = phi21`` and ``phi43 =
phi62 = phi32``. Floats for one sample, (N,) arrays for N.
"""


def leg_joints(robot: Robot, position: Vector, velocity: Vector = ZERO,
               margin: float = DEFAULT_SINGULARITY_MARGIN) -> dict[str, 'LegJoints']:
    """
    Every leg's joint variables and rates (eqs. 9 and 13).

    ``position``, ``velocity``: the platform centre G and its velocity in
    frame 0 (m, m/s), 3-sequences for one sample (through :func:`solve`)
    or (N, 3) arrays for N (checked by :func:`solve_batch`; a
    ``velocity`` of shape (3,) is that of every sample, None is zero).
    Returns ``{'A': LegJoints, 'B': ..., 'C': ...}`` (:class:`LegJoints`).
    Refuses what :func:`solve` and :func:`solve_batch` refuse
    (:class:`WorkspaceError`).

    >>> from orthoglide_ros.model.robot import Robot
    >>> leg = leg_joints(Robot(), (0.0, 0.0, -0.425))['A']
    >>> round(math.degrees(leg.phi32), 9), leg.phi21
    (30.0, 0.0)
    """
    record = {}
    p = np.asarray(position, dtype=float)
    if p.ndim == 1:
        solve(robot, position, velocity, ZERO, margin, record)
        atan2: Callable[..., Any] = math.atan2
    else:
        v = np.broadcast_to(np.asarray(
            ZERO if velocity is None else velocity, dtype=float), p.shape)
        solve_batch(robot, p, v, None, margin)
        columns = (*p.T, *v.T, *np.zeros((3, len(p))))
        kernel_solve(robot, *columns, np.sqrt, record)
        atan2 = np.arctan2
    return {leg: _leg_joints(record[leg], atan2) for leg in LEG_LABELS}


def _leg_joints(rec, atan2):
    """One leg's :class:`LegJoints` from the kernel's record."""
    return LegJoints(rec['lam'], atan2(*rec['phi21']), atan2(*rec['phi32']),
                     rec['lamd'], rec['omega21'], rec['omega32'])


def elements(robot: Robot, position: Vector, velocity: Vector = ZERO,
             acceleration: Vector = ZERO,
             margin: float = DEFAULT_SINGULARITY_MARGIN) -> dict[str, dict[str, Any]]:
    """
    Position, velocity and acceleration of every element (section 2).

    Returns ``{'A': leg, 'B': leg, 'C': leg}`` for one sample. Each leg is a
    dict with ``phi21``, ``phi32`` (rad), ``omega21``, ``omega32`` (rad/s),
    ``epsilon21``, ``epsilon32`` (rad/s^2), ``lambda``, ``lambdadot``,
    ``lambdaddot``, the joint centres ``joints`` (``'A1'`` ... ``'A7'`` and
    ``'G'``, the platform centre reached through this leg's chain, eq. 7)
    in frame 0 (m), and ``bodies``: for k in 1..6, a dict with ``rotation``
    (``a_k0``, 3x3, frame 0 -> frame k), ``origin`` (joint A_k, frame 0, m),
    ``omega``, ``epsilon`` (rad/s, rad/s^2) and ``velocity``,
    ``acceleration`` of A_k (m/s, m/s^2), all four in frame 0. Bodies 1 to 6
    follow doc/model.md (5 is the platform as seen from this leg; 6 the second
    bar A6A7). The rates come from the kernel's recursion (10)-(12), (19).
    """
    record = {}
    solve(robot, position, velocity, acceleration, margin, record)
    return {label: _leg_elements(robot, leg, record[label])
            for label, leg in zip(LEG_LABELS, robot.legs)}


# Constant matrices of eq. (1)-(2); a1 = a10 of leg A.
A1 = np.array([[0, 0, -1], [0, 1, 0], [1, 0, 0]], dtype=float)
A2 = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float)
A3 = np.array([[0, 0, -1], [-1, 0, 0], [0, 1, 0]], dtype=float)
A4 = np.array([[-1, 0, 0], [0, 1, 0], [0, 0, -1]], dtype=float)


def rotation_z(sin_phi: float, cos_phi: float) -> Array:
    """Return ``a^phi`` of eq. (2), the passive rotation about z."""
    return np.array([[cos_phi, sin_phi, 0.0], [-sin_phi, cos_phi, 0.0],
                     [0.0, 0.0, 1.0]])


def _leg_elements(robot, leg, rec):
    """
    Frame-0 elements of one leg from the kernel's record (eqs. 1-8).

    The kernel's leg runs in the leg's frame ``R_i`` with its origin at the
    axis point ``a_i`` and its slider at its true position ``lambda_i +
    e_i``: ``a10 = a1 R_i^T``, the chain starts from ``a_i`` and reaches
    the platform point ``G + r_i`` (doc/model.md#the-machine-as-built).
    """
    s1, c1 = rec['phi21']
    s2, c2 = rec['phi32']
    a21 = rotation_z(s1, c1) @ A2
    a32 = rotation_z(s2, c2) @ A3
    a43 = rotation_z(s2, c2) @ A4
    a10 = A1 @ np.array(leg.frame).T
    rot = {1: a10}
    rot[2] = a21 @ rot[1]
    rot[3] = a32 @ rot[2]
    rot[6] = rot[3]
    rot[4] = a43 @ rot[3]
    rot[5] = a21 @ rot[4]           # a54 = a^phi21 a2 = a21
    ca, sa = math.cos(robot.alpha), math.sin(robot.alpha)
    u3 = np.array([0.0, 0.0, 1.0])
    length = leg.length
    joints = {'A1': (rec['lam'] + leg.offset - robot.l1 * ca - length
                     - robot.l / 2) * rot[1].T @ u3 + leg.point}
    joints['A2'] = joints['A1'] + rot[1].T @ [0.0, robot.l1 * sa,
                                              robot.l1 * ca]
    joints['A3'] = joints['A2'] + rot[2].T @ [0.0, 0.0, -robot.l2 / 2]
    joints['A6'] = joints['A2'] + rot[2].T @ [0.0, 0.0, robot.l2 / 2]
    joints['A4'] = joints['A3'] + rot[3].T @ [0.0, -length, 0.0]
    joints['A7'] = joints['A6'] + rot[6].T @ [0.0, -length, 0.0]
    joints['A5'] = joints['A4'] + rot[4].T @ [robot.l2 / 2, 0.0, 0.0]
    joints['G'] = joints['A5'] + rot[5].T @ [robot.l1 * sa, -robot.l / 2,
                                             0.0] - leg.attachment
    origin = {1: 'A1', 2: 'A2', 3: 'A3', 4: 'A4', 5: 'A5', 6: 'A6'}
    bodies = {
        b: {'rotation': rot[b], 'origin': joints[origin[b]],
            'omega': rot[b].T @ rec['omega'][b],
            'epsilon': rot[b].T @ rec['epsilon'][b],
            'velocity': rot[b].T @ rec['v'][b],
            'acceleration': rot[b].T @ rec['gamma'][b]}
        for b in (1, 2, 3, 4, 5, 6)}
    variables = _leg_joints(rec, math.atan2)
    return {
        'phi21': variables.phi21, 'phi32': variables.phi32,
        'omega21': variables.omega21, 'omega32': variables.omega32,
        'epsilon21': rec['epsilon21'], 'epsilon32': rec['epsilon32'],
        'lambda': variables.lambda_, 'lambdadot': variables.lambdadot,
        'lambdaddot': rec['lamdd'], 'joints': joints, 'bodies': bodies}
