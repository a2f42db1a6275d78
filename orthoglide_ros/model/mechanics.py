"""
Inverse and forward mechanics of the Orthoglide: the package's math API.

:func:`solve` (one sample) and :func:`solve_batch` (N, vectorised): eqs.
(9), (13), (18) and (25) plus the terms of :mod:`terms`; the forward
dynamics and kinematics, the workspace and singularities, eqs. (14)-(17).
SI units, frame 0; a refused input raises :class:`WorkspaceError`, no
result holds a NaN (doc/mechanics.md).

>>> from orthoglide_ros.model.robot import Robot
>>> s = solve(Robot(), (0.0, 0.0, 0.0))
>>> [round(f, 3) for f in s.force]
[0.0, 0.0, 256.532]
"""

from __future__ import annotations

from typing import Any, Optional, TYPE_CHECKING
from collections import namedtuple
import math

import numpy as np

from orthoglide_ros.model import kernel, legs, terms
from orthoglide_ros.model.terms import ARRAYS, FLOATS
from orthoglide_ros.model.types import Array, Rows, Triple, Vector

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.model.robot import Robot

# Smallest accepted singularity distance (see workspace_status): below it a
# point is refused as too near a singularity of J1 or J2 (defined with the
# legs, whose home must stand beyond it).
DEFAULT_SINGULARITY_MARGIN = legs.DEFAULT_SINGULARITY_MARGIN

# Why an input was refused: the values of WorkspaceError.reason.
REASONS = ('non_finite', 'unreachable', 'singular', 'overflow')

ZERO = (0.0, 0.0, 0.0)

# The legs' names in messages.
LEG_NAMES = ('A', 'B', 'C')

# The unit accelerations of the forward dynamics' columns.
_UNITS = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))

# Samples per kernel call in solve_batch: arrays of this size stay in the
# processor's cache (measured: 4096 is about 1.3x faster than 10,000).
BATCH_CHUNK = 4096

Solution = namedtuple('Solution', (
    'lambda_', 'lambdadot', 'lambdaddot', 'force', 'power',
    'alpha_ratio', 'conditioning', 'singularity_distance'))
Solution.__doc__ = """Inverse kinematics and dynamics of one sample or a batch.

Per actuator (A, B, C): ``lambda_`` (m), ``lambdadot`` (m/s),
``lambdaddot`` (m/s^2), ``force`` (N, on the slider along +lambda) and
``power = lambdadot * force`` (W); ``alpha_ratio`` = ``alpha_i / L_i``
(eq. 17, ``L_i`` the leg's bar length, ``l3`` as drawn; 1 at home, 0 at a
singularity of J1); ``conditioning`` =
``1 / kappa_F(J_lambda)`` (1 at home, 0 at a singularity of J2);
``singularity_distance`` = the smallest of the four. A single sample holds
3-tuples of floats and floats; a batch holds (N, 3) and (N,) arrays.
"""

WorkspaceStatus = namedtuple('WorkspaceStatus', (
    'reachable', 'alpha_ratio', 'conditioning', 'singularity_distance',
    'ok'))
WorkspaceStatus.__doc__ = """Where a platform position stands.

``reachable``: eq. (9) has a real solution on the home branch for every
leg (``y^2 + z^2 < l3^2`` for leg A, cyclically; ``y'^2 + z'^2 < L_i^2``
in the frame of a leg as built). ``alpha_ratio``,
``conditioning`` and ``singularity_distance`` as in :class:`Solution` (0
where unreachable). ``ok``: reachable and ``singularity_distance >=
margin``.
"""


class WorkspaceError(ValueError):
    """
    An input the mechanics refuse: ``reason`` is one of REASONS.

    ``row`` is the 0-based sample index for batch calls, else None;
    ``detail`` the message without it; ``position`` the position refused
    (m, or None) and ``finding`` what is said of it (``detail`` is
    ``position [x, y, z] m`` and the finding where ``position`` is given).
    """

    def __init__(self, reason: str, message: str,
                 row: Optional[int] = None, position: Any = None) -> None:
        detail = message if position is None else \
            f'position {format_vector(position)} m {message}'
        where = '' if row is None else f'sample {row}: '
        super().__init__(where + detail)
        self.detail = detail
        self.finding = message
        self.position = position
        self.reason = reason
        self.row = row


def kernel_solve(robot: Robot, x: Any, y: Any, z: Any, vx: Any, vy: Any,
                 vz: Any, ax: Any, ay: Any, az: Any, sqrt: Any,
                 record: Optional[dict[str, Any]] = None) -> Any:
    """
    Run the kernel on ``robot``'s legs, unchecked: floats or arrays.

    :func:`kernel.solve` for a robot as drawn (``robot.as_drawn``),
    :func:`kernel.solve_legs` for legs as built; the arguments and the
    result are theirs. Callers check the state (:func:`solve`,
    :func:`solve_batch`) first or after.
    """
    if robot.as_drawn:
        return kernel.solve(robot.constants, x, y, z, vx, vy, vz, ax, ay, az,
                            sqrt, record)
    return kernel.solve_legs(robot.leg_constants, x, y, z, vx, vy, vz, ax,
                             ay, az, sqrt, record)


def solve(robot: Robot, position: Vector, velocity: Vector = ZERO,
          acceleration: Vector = ZERO,
          margin: float = DEFAULT_SINGULARITY_MARGIN,
          record: Optional[dict[str, Any]] = None) -> 'Solution':
    """
    Solve one sample: eqs. (9), (13), (18) and (25) on Python floats.

    ``position``, ``velocity``, ``acceleration``: the platform centre G and
    its derivatives in frame 0 (m, m/s, m/s^2), each a 3-sequence. Returns
    a :class:`Solution` of 3-tuples. The force is the rigid bodies' (the
    kernel's) plus the terms of :mod:`terms` at the sliders' state
    (friction, drives, screw ripple), and the power ``lambdadot * force``
    is the total force's. ``record``, if a dict, receives the kernel's
    per-element quantities (see :func:`elements`).
    """
    x, y, z = position
    vx, vy, vz = velocity
    ax, ay, az = acceleration
    if not math.isfinite(x + y + z + vx + vy + vz + ax + ay + az):
        _check_finite_inputs(position, velocity, acceleration)
    if robot.as_drawn:
        l3sq = robot.l3 * robot.l3
        rho = max(y * y + z * z, z * z + x * x, x * x + y * y)
        if rho >= l3sq * (1.0 - margin * margin):
            raise _leg_error(robot, position, margin)
        try:
            out = kernel.solve(robot.constants, float(x), float(y), float(z),
                               float(vx), float(vy), float(vz), float(ax),
                               float(ay), float(az), math.sqrt, record)
        except (ZeroDivisionError, ValueError):
            # Only exactly on a singularity: det J_lambda = 0 (J2 singular,
            # as at x = y = z = l3/sqrt(3)), or a cosine's square rounded
            # below 0.
            raise _on_singularity(position) from None
        alphas = out[5]
        l3 = robot.l3
        ratio = (alphas[0] / l3, alphas[1] / l3, alphas[2] / l3)
    else:
        try:
            out = kernel.solve_legs(
                robot.leg_constants, float(x), float(y), float(z), float(vx),
                float(vy), float(vz), float(ax), float(ay), float(az),
                math.sqrt, record)
        except (ZeroDivisionError, ValueError):
            # A leg out of reach (a negative square), or exactly on a
            # singularity.
            raise _leg_fault(robot, position, margin) or _on_singularity(
                position) from None
        alphas = out[5]
        la, lb, lc = robot.bar_length
        ratio = (alphas[0] / la, alphas[1] / lb, alphas[2] / lc)
        if min(ratio) < margin:     # each leg's reach and J1 first
            raise _leg_error(robot, position, margin)
    lam, lamd, lamdd, force, power, alphas, conditioning = out
    if robot.active_terms:
        fa, fb, fc = terms.forces(robot, robot.active_terms, lam, lamd,
                                  lamdd, FLOATS)
        force = (force[0] + fa, force[1] + fb, force[2] + fc)
        power = (lamd[0] * force[0], lamd[1] * force[1], lamd[2] * force[2])
    if conditioning < margin or conditioning == 0.0:
        raise _beyond_j2(robot, position) or WorkspaceError('singular', (
            'is too near a singularity of '
            f'J2: 1/kappa_F(J_lambda) = {below(conditioning, margin)} < '
            f'margin {margin:g}'), position=position)
    if min(ratio) < margin:     # the leg test above, rounded apart
        raise _leg_error(robot, position, margin)
    if not math.isfinite(sum(lamdd) + sum(force) + sum(power)) and not all(
            math.isfinite(f) for f in (*lamdd, *force, *power)):
        # (A sum of large finite numbers may overflow: check one by one.)
        raise _overflow_error(position, velocity, acceleration)
    return Solution(lam, lamd, lamdd, force, power, ratio, conditioning,
                    min(min(ratio), conditioning))


def solve_batch(robot: Robot, positions: Rows,
                velocities: Optional[Rows] = None,
                accelerations: Optional[Rows] = None,
                margin: float = DEFAULT_SINGULARITY_MARGIN) -> 'Solution':
    """
    Solve N samples at once, vectorised (the same kernel on arrays).

    ``positions``, ``velocities``, ``accelerations``: (N, 3) arrays in frame
    0 (m, m/s, m/s^2); a missing velocity or acceleration means zero.
    Returns a :class:`Solution` of (N, 3) and (N,) arrays, the terms
    included as in :func:`solve`. The first bad sample raises
    :class:`WorkspaceError` with its index in ``row``.
    """
    p = _as_samples('positions', positions)
    n = len(p)
    v = np.zeros((n, 3)) if velocities is None else _as_samples(
        'velocities', velocities, n)
    a = np.zeros((n, 3)) if accelerations is None else _as_samples(
        'accelerations', accelerations, n)
    # Whole-array checks first: a reduction along the short axis is ~15x
    # slower, so it only runs to name the row of a failed check.
    if not (np.isfinite(p).all() and np.isfinite(v).all()
            and np.isfinite(a).all()):
        finite = np.isfinite(np.hstack((p, v, a))).all(1)
        row = int(np.argmin(finite))
        _check_finite_inputs(p[row], v[row], a[row], row)
    x, y, z = p.T.copy()
    lengths = np.array(robot.bar_length)
    if robot.as_drawn:
        with np.errstate(over='ignore'):    # a far point: inf, refused below
            rho = np.maximum(np.maximum(y * y + z * z, z * z + x * x),
                             x * x + y * y)
        reach = rho < robot.l3 * robot.l3 * (1.0 - margin * margin)
        if not reach.all():
            row = int(np.argmin(reach))
            raise _leg_error(robot, p[row], margin, row)
    # Filled per actuator row (contiguous writes), returned as (N, 3) views.
    out = np.empty((6, 3, n))
    conditioning = np.empty(n)
    columns = (x, y, z, *v.T.copy(), *a.T.copy())
    for start in range(0, n, BATCH_CHUNK):
        chunk = slice(start, start + BATCH_CHUNK)
        with np.errstate(all='ignore'):     # checked below, row by row
            *values, conditioning[chunk] = kernel_solve(
                robot, *(c[chunk] for c in columns), np.sqrt)
        for j, triple in enumerate(values):
            for leg in range(3):
                out[j, leg, chunk] = triple[leg]
    if not robot.as_drawn:
        # Each leg's reach and J1 first, as the drawing's test above (NaN:
        # out of reach).
        with np.errstate(invalid='ignore'):
            reach = (out[5] / lengths[:, None]).min(0) >= margin
        if not reach.all():
            row = int(np.argmin(reach))
            raise _leg_error(robot, p[row], margin, row)
    if robot.active_terms:
        with np.errstate(all='ignore'):     # checked below, row by row
            for leg, force in enumerate(terms.forces(
                    robot, robot.active_terms, out[0], out[1], out[2],
                    ARRAYS)):
                out[3, leg] += force
            np.multiply(out[1], out[3], out=out[4])
    out = out.transpose(0, 2, 1)
    conditioning = np.nan_to_num(conditioning, nan=0.0)
    # 0 (NaN before): exactly on a singularity, where solve divides by
    # zero; refused whatever the margin, as solve refuses it.
    accepted = (conditioning >= margin) & (conditioning > 0.0)
    if not accepted.all():
        row = int(np.argmin(accepted))
        if conditioning[row] == 0.0:
            raise _beyond_j2(robot, p[row], row) or _on_singularity(
                p[row], row)
        raise WorkspaceError('singular', (
            'is too near a singularity of J2: '
            f'1/kappa_F(J_lambda) = {below(conditioning[row], margin)} < '
            f'margin {margin:g}'), row, position=p[row])
    ratio = out[5] / lengths
    near = ratio.min(1) < margin    # the leg test above, rounded apart
    if near.any():
        row = int(np.argmax(near))
        raise _leg_error(robot, p[row], margin, row)
    if not np.isfinite(out[2:5]).all():
        row = int(np.argmin(np.isfinite(out[2:5]).all(axis=(0, 2))))
        raise _overflow_error(p[row], v[row], a[row], row)
    return Solution(*out[:5], ratio, conditioning,
                    np.minimum(ratio.min(1), conditioning))


def friction_force(robot: Robot, lambdadot: Any) -> Any:
    """
    Friction the actuators overcome on their sliders (N), per actuator.

    The sum of the friction terms of :mod:`terms` at the slider speeds
    ``lambdadot`` (m/s): a 3-sequence (returns a 3-tuple) or an (N, 3)
    array (returns one). The law (doc/model.md#terms): ``f_j = c_j v +
    (F_j if v > 0 else F_j^-) tanh(v / v_s) + S_j exp(-(v / v_b)^2)
    tanh(v / v_s)``, ``v = lambdadot_j``. Part of the forces of
    :func:`solve`; zero at rest.

    >>> from orthoglide_ros.model.robot import Robot
    >>> robot = Robot(friction_viscous=(10.0, 0.0, 0.0),
    ...               friction_coulomb=(0.0, 2.0, 0.0))
    >>> [round(f, 6) for f in friction_force(robot, (0.1, -1.0, 0.3))]
    [1.0, -2.0, 0.0]
    """
    friction = tuple(term for term in robot.active_terms if term.friction)
    if isinstance(lambdadot, np.ndarray):
        out = np.zeros(lambdadot.shape)
        for leg, force in enumerate(terms.forces(
                robot, friction, ZERO, lambdadot.T, ZERO, ARRAYS)):
            out[:, leg] += force
        return out
    values = tuple(float(v) for v in lambdadot)
    if not friction:
        return ZERO
    return terms.forces(robot, friction, ZERO, values, ZERO, FLOATS)


def forward_dynamics(robot: Robot, position: Vector, velocity: Vector,
                     force: Vector,
                     margin: float = DEFAULT_SINGULARITY_MARGIN) -> Triple:
    """
    Platform acceleration (m/s^2, frame 0) from its state and the forces.

    ``position`` (m) and ``velocity`` (m/s) of G and ``force`` (N, on the
    sliders A, B, C along +lambda), each a 3-sequence; returns ``rddot_G``.
    ``J_lambda^T f = M a + h`` (eqs. 16 and 25; ``h``, the forces at zero
    acceleration, holds every term but the drives': friction, the screw
    ripple) solved for ``a`` by four kernel calls and Cramer's rule
    (doc/mechanics.md#forward-dynamics-and-simulation). Refuses what
    :func:`solve` refuses, with the same reasons.

    >>> from orthoglide_ros.model.robot import Robot
    >>> robot = Robot()
    >>> f = solve(robot, (0.05, 0.1, -0.2), (0.1, 0.0, 0.3),
    ...           (1.0, -2.0, 0.5)).force
    >>> a = forward_dynamics(robot, (0.05, 0.1, -0.2), (0.1, 0.0, 0.3), f)
    >>> [round(v, 9) for v in a]
    [1.0, -2.0, 0.5]
    """
    fa, fb, fc = force
    if not math.isfinite(fa + fb + fc):
        _check_finite_inputs(position, velocity, force, None, 'force')
    try:
        bias = solve(robot, position, velocity, ZERO, margin).force
    except WorkspaceError as error:
        if error.reason != 'overflow':
            raise
        raise _overflow_error(position, velocity, force, None,
                              'force') from None
    inertia = _inertia(robot)
    x, y, z = float(position[0]), float(position[1]), float(position[2])
    columns = []
    for unit in _UNITS:
        force, lamdd = _unit_column(inertia, x, y, z, unit)
        if inertia.active_terms:    # the drives' terms: their part of M
            extra = terms.forces(inertia, inertia.active_terms, ZERO, ZERO,
                                 lamdd, FLOATS)
            force = (force[0] + extra[0], force[1] + extra[1],
                     force[2] + extra[2])
        columns.append(force)
    rhs = (fa - bias[0], fb - bias[1], fc - bias[2])
    # det F = det M / det J_lambda is not zero where solve accepts the
    # position (M >= m5 I): a zero or an infinity can only be a numeric
    # failure, refused as forward_dynamics_batch refuses it.
    try:
        acceleration = _solve3(columns, rhs)
    except ZeroDivisionError:
        acceleration = (math.nan,) * 3
    if not math.isfinite(sum(acceleration)) and not all(
            math.isfinite(v) for v in acceleration):
        raise _overflow_error(position, velocity, force, None, 'force')
    return acceleration


def forward_dynamics_batch(robot: Robot, positions: Rows, velocities: Rows,
                           forces: Rows,
                           margin: float = DEFAULT_SINGULARITY_MARGIN) -> Array:
    """
    Forward dynamics of N samples at once (see :func:`forward_dynamics`).

    ``positions`` (m), ``velocities`` (m/s) and ``forces`` (N): (N, 3)
    arrays. Returns the platform accelerations, an (N, 3) array (m/s^2,
    frame 0). The same construction on arrays: the bias and the three
    columns of ``F = J_lambda^-T M`` from :func:`solve_batch`, then
    Cramer's rule per sample. The first bad sample raises
    :class:`WorkspaceError` with its index in ``row``.
    """
    p = _as_samples('positions', positions)
    n = len(p)
    v = _as_samples('velocities', velocities, n)
    f = _as_samples('forces', forces, n)
    if not (np.isfinite(p).all() and np.isfinite(v).all()
            and np.isfinite(f).all()):
        row = int(np.argmin(np.isfinite(np.hstack((p, v, f))).all(1)))
        _check_finite_inputs(p[row], v[row], f[row], row, 'force')
    try:
        bias = solve_batch(robot, p, v, None, margin).force
    except WorkspaceError as error:
        if error.reason != 'overflow':
            raise
        raise _overflow_error(p[error.row], v[error.row], f[error.row],
                              error.row, 'force') from None
    inertia = _inertia(robot)
    columns = []
    for unit in np.eye(3):
        columns.append(solve_batch(inertia, p, None, np.tile(unit, (n, 1)),
                                   margin).force.T)
    with np.errstate(all='ignore'):     # checked below, row by row
        acceleration = np.column_stack(_solve3(columns, (f - bias).T))
    good = np.isfinite(acceleration).all(1)
    if not good.all():
        row = int(np.argmin(good))
        raise _overflow_error(p[row], v[row], f[row], row, 'force')
    return acceleration


def workspace_status(robot: Robot, position: Vector,
                     margin: float = DEFAULT_SINGULARITY_MARGIN) -> 'WorkspaceStatus':
    """
    Reachability and distance to the singularities of J1 and J2.

    ``position``: one point (3,) or N points (N, 3) in frame 0 (m). The
    singularity distance is the smallest of ``alpha_i / L_i = cos(phi21)
    cos(phi32)`` over the legs (``L_i = l3`` as drawn; J1 = diag(alpha_i)
    is singular at 0) and of
    ``1 / kappa_F(J_lambda) = 3 |det J| / (|J|_F |J^-1 det J|_F)``, the
    normalised inverse Frobenius condition number of the inverse-kinematics
    Jacobian ``J_lambda = J1^-1 J2`` (eq. 16; J2 is singular at 0). Both are
    1 at home. Returns a :class:`WorkspaceStatus` (arrays for N points).
    """
    p = np.asarray(position, dtype=float)
    if not robot.as_drawn:
        reachable, ratio, conditioning, _ = legs.status(
            robot.legs, robot.leg_constants, p)
        distance = np.minimum(ratio.min(-1), conditioning)
        return WorkspaceStatus(reachable, ratio, conditioning, distance,
                               reachable & (distance >= margin))
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    l3sq = robot.l3 * robot.l3
    q = 1.0 - np.stack([y * y + z * z, z * z + x * x, x * x + y * y],
                       -1) / l3sq
    with np.errstate(invalid='ignore'):
        reachable = (q > 0.0).all(-1)
    ratio = np.sqrt(np.where(reachable[..., None], q, 1.0))
    al = robot.l3 * ratio
    with np.errstate(divide='ignore', invalid='ignore'):
        conditioning = kernel.jacobian_cofactors(
            x, y, z, al[..., 0], al[..., 1], al[..., 2], np.sqrt)[2]
    conditioning = np.nan_to_num(conditioning, nan=0.0)
    ratio = np.where(reachable[..., None], ratio, 0.0)
    conditioning = np.where(reachable, conditioning, 0.0)
    distance = np.minimum(ratio.min(-1), conditioning)
    ok = reachable & (distance >= margin)
    return WorkspaceStatus(reachable, ratio, conditioning, distance, ok)


def forward_kinematics(robot: Robot, lam: Rows) -> Array:
    """
    Platform centre G (m) from the actuator displacements (m), eq. (14).

    Intersects the three constraint spheres of eq. (14) on the branch that
    holds the home position (every ``alpha_i > 0``): see
    :func:`forward_kinematics_rows`. ``lam``: (3,) or (N, 3). Raises
    :class:`WorkspaceError` where there is no such point.
    """
    lam = np.asarray(lam, dtype=float)
    if not np.isfinite(lam).all():
        raise WorkspaceError('non_finite', f'lambda {lam} is not finite')
    r, found = forward_kinematics_rows(robot, lam)
    if not np.all(found):
        row = int(np.argmin(np.atleast_1d(found)))
        raise WorkspaceError('unreachable', (
            f'lambda {format_vector(np.atleast_2d(lam)[row])} m has no platform '
            'position on the home branch'), row if lam.ndim == 2 else None)
    return r


def forward_kinematics_rows(robot: Robot, lam: Rows) -> tuple[Array, Array]:
    """
    Forward kinematics without refusals: ``(positions, found)``.

    ``lam``: (3,) or (N, 3) (m). With ``d_j = l3 - lambda_j`` and ``s =
    |r_G|^2`` each sphere of eq. (14) reads ``s + 2 r_j d_j + d_j^2 =
    l3^2``, so ``r_j = (l3^2 - d_j^2 - s) / (2 d_j)`` and ``s`` solves a
    quadratic whose smaller root is the home branch while every
    ``lambda_j < l3``; elsewhere (a slider beyond l3, as at (0.442, -0.581,
    -0.511) m) :func:`legs.intersect`, the spheres' trilateration, which
    is also what legs as built use. ``found`` (bool, () or (N,)) says where
    the home branch has a point with every ``alpha_i > 0``; ``positions``
    (m) is meaningless elsewhere. Where both roots are valid platform
    positions (two assembly modes), a position on the other one is not
    given back: a robot started at home cannot reach it without crossing a
    singularity of J2.
    """
    if not robot.as_drawn:
        return legs.intersect(robot.legs, lam)
    lam = np.asarray(lam, dtype=float)
    l3 = robot.l3
    d = l3 - lam
    with np.errstate(all='ignore'):     # judged by found, row by row
        kk = l3 * l3 - d * d
        w = 0.25 / (d * d)
        qa = w.sum(-1)
        qb = 1.0 + 2.0 * (w * kk).sum(-1)
        qc = (w * kk * kk).sum(-1)
        disc = qb * qb - 4.0 * qa * qc
        s = 2.0 * qc / (qb + np.sqrt(disc))
        r = (kk - s[..., None]) / (2.0 * d)
        alpha = r + d
        found = (disc >= 0.0) & np.isfinite(r).all(-1) & (alpha > 0.0).all(-1)
    beyond = (lam >= l3).any(-1)
    if np.any(beyond):
        trilaterated, reached = legs.intersect(robot.legs, lam)
        r = np.where(beyond[..., None], trilaterated, r)
        found = np.where(beyond, reached, found)
    return r, found


def platform_velocity(robot: Robot, position: Vector,
                      lambdadot: Vector) -> Triple:
    """
    Platform velocity ``rdot_G`` (m/s, frame 0) from the actuator rates.

    Eq. (15) solved for ``rdot_G``: ``J2 rdot_G = J1 lambdadot``, with
    ``J1``, ``J2`` of eq. (16) at ``position`` (m, as
    :func:`forward_kinematics` returns it) and ``lambdadot`` (m/s, A, B,
    C). Returns a 3-tuple of floats. Raises :class:`WorkspaceError` where
    the position is unreachable, a rate is not finite or J2 is so singular
    that the result is not finite; near a singularity the result is large
    (callers that need a margin check it, as :func:`leg_joints` does).

    >>> from orthoglide_ros.model.robot import Robot
    >>> rates = solve(Robot(), (0.05, 0.1, -0.2), (0.1, -0.2, 0.3)).lambdadot
    >>> [round(v, 12) for v in platform_velocity(
    ...     Robot(), (0.05, 0.1, -0.2), rates)]
    [0.1, -0.2, 0.3]
    """
    rates = np.asarray(lambdadot, dtype=float)
    if not np.isfinite(rates).all():
        raise WorkspaceError(
            'non_finite', f'lambdadot {format_vector(rates)} is not finite')
    j1, j2 = jacobians(robot, position)
    try:
        velocity = np.linalg.solve(j2, j1 @ rates)
    except np.linalg.LinAlgError:
        velocity = np.full(3, math.nan)
    if not np.isfinite(velocity).all():
        raise WorkspaceError('singular', (
            'is on a singularity of J2: the platform velocity is '
            'undefined'), position=position)
    return tuple(velocity.tolist())


def payload_force(robot: Robot, payload: float, lambda_: Any, lambdadot: Any,
                  lambdaddot: Any) -> Any:
    """
    Return the forces (N, A, B, C) that carrying ``payload`` (kg) adds.

    A mass on the platform, which only translates, needs ``payload (rddot_G
    - g)`` at G: by virtual work (eq. 25) the actuators add ``J_lambda^-T
    payload (rddot_G - g)``. The platform's state from the joints' (m, m/s,
    m/s^2, 3-sequences): ``r_G`` by :func:`forward_kinematics`, ``rdot_G =
    J_lambda^-1 lambdadot`` (eq. 15), ``rddot_G = J_lambda^-1 (lambdaddot -
    lambdaddot_0)`` with ``lambdaddot_0`` the joints' acceleration of
    :func:`solve` at ``rddot_G = 0`` (eq. 18). Exactly the forces of
    ``robot.replace(payload=robot.payload + payload)`` less ``robot``'s at
    that state. Raises :class:`WorkspaceError` where the joints have no
    platform position (on the home branch) or J_lambda is singular.

    >>> from orthoglide_ros.model.robot import Robot
    >>> home = solve(Robot(), ZERO).lambda_
    >>> [round(f, 6) for f in payload_force(Robot(), 5.0, home, ZERO, ZERO)]
    [0.0, 0.0, 49.05]
    """
    position = tuple(forward_kinematics(robot, lambda_).tolist())
    j1, j2 = jacobians(robot, position)
    j_lambda = np.linalg.solve(j1, j2)
    velocity = np.linalg.solve(j_lambda, np.asarray(lambdadot, dtype=float))
    rest = solve(robot, position, tuple(velocity.tolist()), ZERO, 0.0)
    acceleration = np.linalg.solve(
        j_lambda, np.asarray(lambdaddot, dtype=float) - rest.lambdaddot)
    gravity: Array = np.asarray(robot.gravity, dtype=np.float64)
    force = payload * np.linalg.solve(j_lambda.T, acceleration - gravity)
    return tuple(force.tolist())


def jacobians(robot: Robot, position: Vector) -> tuple[Array, Array]:
    """
    Return ``(J1, J2)`` of eq. (16) at a position (m) in frame 0.

    ``J1 lambdadot = J2 rdot_G`` (eq. 15) with ``J1 = diag(alpha_i)`` and
    ``J2 = [[alpha_1, y, z], [x, alpha_2, z], [x, y, alpha_3]]``, ``alpha_i``
    of eq. (17) (m); for legs as built ``J2``'s row i is ``R_i (alpha_i,
    y', z')`` (doc/model.md#the-machine-as-built). ``position``: (3,) or (N, 3); returns (3, 3) or
    (N, 3, 3) arrays. Raises :class:`WorkspaceError` where unreachable.
    """
    p = np.asarray(position, dtype=float)
    if robot.as_drawn:
        reachable, ratio = workspace_status(robot, p, 0.0)[:2]
    else:
        reachable, ratio, _, j_lambda = legs.status(
            robot.legs, robot.leg_constants, p)
    if not np.all(reachable):
        row = int(np.argmin(np.atleast_1d(reachable)))
        raise _leg_error(robot, np.atleast_2d(p)[row], 0.0,
                         row if p.ndim == 2 else None)
    alpha = np.asarray(robot.bar_length) * ratio
    j1 = alpha[..., :, None] * np.eye(3)
    if not robot.as_drawn:
        return j1, alpha[..., :, None] * j_lambda
    j2 = np.broadcast_to(p[..., None, :], j1.shape).copy()
    j2[..., [0, 1, 2], [0, 1, 2]] = alpha
    return j1, j2


def _as_samples(name, values, n=None):
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3 or n not in (None, len(arr)):
        want = '(N, 3)' if n is None else f'({n}, 3)'
        raise ValueError(f'{name} must have shape {want}, got {arr.shape}')
    return arr


def _check_finite_inputs(position, velocity, third, row=None,
                         third_name='acceleration'):
    for name, vec in (('position', position), ('velocity', velocity),
                      (third_name, third)):
        if not all(math.isfinite(v) for v in vec):
            raise WorkspaceError(
                'non_finite', f'{name} {format_vector(vec)} is not finite', row)


def _overflow_error(position, velocity, third, row=None,
                    third_name='acceleration'):
    """Refuse a sample whose result is not finite (a WorkspaceError)."""
    unit = 'N' if third_name == 'force' else 'm/s^2'
    return WorkspaceError('overflow', (
        f'the result for position {format_vector(position)} m, velocity '
        f'{format_vector(velocity)} m/s, {third_name} {format_vector(third)} {unit} is not '
        'finite'), row)


# Copies of the robots as their mass matrix sees them (terms.inertial),
# keyed by what it depends on (the kernel's constants and the inertial
# terms, the drives): the inverse dynamics at zero velocity of such a copy
# is ``M`` applied.
_INERTIA = {}


def _inertia(robot):
    """Return :func:`terms.inertial` of ``robot`` (built once per robot)."""
    drives = [getattr(robot, terms.coefficient_name(term))
              for term in robot.active_terms if term.inertial]
    key = robot.constants if robot.as_drawn else robot.leg_constants
    key = (key, *drives) if drives else key
    inertia = _INERTIA.get(key)
    if inertia is None:
        if len(_INERTIA) >= 16:
            _INERTIA.clear()
        inertia = terms.inertial(robot)
        _INERTIA[key] = inertia
    return inertia


def _unit_column(robot, x, y, z, unit):
    """Return the kernel's forces and ``lambdaddot`` at rest under ``unit``."""
    out = kernel_solve(robot, x, y, z, 0.0, 0.0, 0.0, unit[0], unit[1],
                       unit[2], math.sqrt)
    return out[3], out[2]


def _solve3(columns, rhs):
    """
    Solve ``[c0 c1 c2] a = b`` by Cramer's rule (floats or arrays).

    ``columns``: three 3-sequences ``c0, c1, c2``; ``rhs``: ``b``. With
    ``r0 = c1 x c2``, ``r1 = c2 x c0``, ``r2 = c0 x c1`` (the rows of
    ``det * inverse``), ``a_i = b . r_i / det`` and ``det = c0 . r0``.
    """
    (p0, p1, p2), (q0, q1, q2), (s0, s1, s2) = columns
    b0, b1, b2 = rhs
    r00, r01, r02 = q1 * s2 - q2 * s1, q2 * s0 - q0 * s2, q0 * s1 - q1 * s0
    r10, r11, r12 = s1 * p2 - s2 * p1, s2 * p0 - s0 * p2, s0 * p1 - s1 * p0
    r20, r21, r22 = p1 * q2 - p2 * q1, p2 * q0 - p0 * q2, p0 * q1 - p1 * q0
    inv = 1.0 / (p0 * r00 + p1 * r01 + p2 * r02)
    return ((b0 * r00 + b1 * r01 + b2 * r02) * inv,
            (b0 * r10 + b1 * r11 + b2 * r12) * inv,
            (b0 * r20 + b1 * r21 + b2 * r22) * inv)


def _beyond_j2(robot, position, row=None):
    """
    Refuse a position beyond a singularity of J2 (a WorkspaceError), or None.

    Where ``det J_lambda < 0`` eq. (9) has its solution but the robot,
    assembled as at home, is at the mirror point of those lambda: it
    cannot get there without crossing the singularity.
    """
    if np.linalg.det(jacobians(robot, position)[1]) >= 0.0:   # J1 > 0
        return None
    return WorkspaceError('singular', (
        'is beyond a singularity of '
        'J2 (det J_lambda < 0): the other assembly mode, which a robot '
        'assembled as at home cannot reach'), row, position=position)


def _on_singularity(position, row=None):
    """Refuse a position exactly on a singularity (a WorkspaceError)."""
    return WorkspaceError('singular', (
        'is on a singularity'), row, position=position)


def _leg_fault(robot, position, margin, row=None):
    """
    Return the first leg's refusal of ``position`` (or None).

    Leg i reaches the position where its point's distance from its axis,
    ``sqrt(y'^2 + z'^2)`` (:func:`kernel.leg_point`), is below its bar
    length ``L_i`` (``l3`` as drawn); ``alpha_i / L_i`` is then J1's
    margin.
    """
    x, y, z = (float(v) for v in position)
    for leg, constants in zip(robot.legs, robot.leg_constants):
        name = leg.name.upper()
        length = leg.length
        what = 'l3' if robot.as_drawn else f'L_{name}'
        _, yq, zq = kernel.leg_point(constants, x, y, z)
        rho = yq * yq + zq * zq
        if rho >= length * length:
            return WorkspaceError('unreachable', (
                f'is out of reach of leg {name}: '
                f'its distance {math.sqrt(rho):.4g} m from the leg\'s axis '
                f'is not below {what} = {length:g} m'), row, position=position)
        ratio = math.sqrt(1.0 - rho / (length * length))
        if ratio < margin:
            return WorkspaceError('singular', (
                'is too near a singularity of '
                f'J1: leg {name} has alpha/{what} = {below(ratio, margin)} '
                f'< margin {margin:g}'), row, position=position)
    return None


def _leg_error(robot, position, margin, row=None):
    """Explain which leg refuses ``position`` (a WorkspaceError)."""
    fault = _leg_fault(robot, position, margin, row)
    if fault is not None:
        return fault
    # On the margin's very edge the callers' test and the ones above can
    # round apart: the leg nearest its singularity refuses it.
    status = workspace_status(robot, np.asarray(position, dtype=float),
                              margin)
    leg = int(np.argmin(status.alpha_ratio))
    what = 'l3' if robot.as_drawn else f'L_{LEG_NAMES[leg]}'
    return WorkspaceError('singular', (
        'is on the edge of the singularity '
        f'margin {margin:g} of J1: leg {LEG_NAMES[leg]} has alpha/{what} = '
        f'{status.alpha_ratio[leg]:.3g}'), row, position=position)


def below(value: float, bound: float) -> str:
    """
    Return ``value`` with the fewest digits (3 at least) that show it below.

    >>> below(0.19996, 0.2)
    '0.19996'
    """
    for digits in range(3, 18):
        text = f'{float(value):.{digits}g}'
        if float(text) < bound:
            return text
    return repr(float(value))


def format_vector(vec: Optional[Vector]) -> str:
    """Return a vector as ``[x, y, z]`` with 6 significant digits."""
    return '[' + ', '.join(f'{float(v):.6g}' for v in vec) + ']'
