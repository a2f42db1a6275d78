"""
An independent second model of the Orthoglide for the tests.

Written from doc/model.md and the paper alone; it shares nothing with the
package but the values of a :class:`Robot` (read as plain attributes).

- :func:`leg_frame`: a leg as built, from the ``robot.*`` rows of its axis
  point and direction, joint offset, bar length and attachment, its
  rotation from the drawing's axis by scipy's ``Rotation``.
- :func:`leg_geometry`: the chain (1)-(8) of one leg with plain 3x3 matrices
  (``a_k0`` products, joint centres, centres of mass, frame 0) from the
  closed-form inverse geometry (9) on the leg's sphere (eq. 14 as built:
  ``|G + r - a - (lambda + e - L) u| = L``). It accepts a complex platform
  position so that derivatives can be taken by complex step.
- :func:`platform_position`: the forward kinematics, the three spheres
  solved by scipy's ``least_squares`` from home.
- :func:`body_jacobians`: the linear (centre of mass) and angular Jacobians
  of every body with respect to the generalised coordinates ``q = r_G``,
  by complex step (exact to machine precision).
- :func:`mass_matrix`, :func:`kinetic_energy`, :func:`potential_energy`
  (gravity, and the drives' screw ripple as a potential of the sliders:
  :func:`ripple_potential`).
- :func:`lagrange_forces`: the actuator forces from Lagrange's equations,
  ``Q = M qdd + C(q, qd) + dV/dq`` and ``f = J_lambda^-T Q``, with the
  Christoffel terms from central finite differences of the exact ``M``;
  :func:`force_tolerance` their error bound.

Units: m, kg, s, N, J; vectors in frame 0.
"""

from collections import namedtuple
import functools

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

# Complex-step size: the derivative is Im f(q + i h) / h, with no
# subtraction, hence exact to rounding for any tiny h.
COMPLEX_STEP = 1e-30
# Central finite-difference step (m) for dM/dq in the Christoffel terms.
MASS_MATRIX_STEP = 1e-5

U1 = np.array([1.0, 0.0, 0.0])
U2 = np.array([0.0, 1.0, 0.0])
U3 = np.array([0.0, 0.0, 1.0])

# The constant matrices of eq. (2) as printed in the paper.
PAPER_A1 = np.array([[0, 0, -1], [0, 1, 0], [1, 0, 0]], dtype=float)
PAPER_A2 = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float)
PAPER_A3 = np.array([[0, 0, -1], [-1, 0, 0], [0, 1, 0]], dtype=float)
PAPER_A4 = np.array([[-1, 0, 0], [0, 1, 0], [0, 0, -1]], dtype=float)
PAPER_A5 = np.array([[-1, 0, 0], [0, 0, 1], [0, 1, 0]], dtype=float)
PAPER_A6 = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], dtype=float)

# Eq. (1): a10 = a1, b10 = a5, c10 = a6.
BASE_ROTATION = {'A': PAPER_A1, 'B': PAPER_A5, 'C': PAPER_A6}
# Eq. (9): the coordinates each leg sees, as indices into (x, y, z).
LEG_AXES = {'A': (0, 1, 2), 'B': (1, 2, 0), 'C': (2, 0, 1)}
LEGS = ('A', 'B', 'C')
# The bodies of one leg that the tree holds (the platform, 5, once).
LEG_BODIES = (1, 2, 3, 4, 6)


def a_phi(sin_phi, cos_phi):
    """Passive rotation about z of eq. (2) (complex entries allowed)."""
    zero = 0.0 * sin_phi
    return np.array([[cos_phi, sin_phi, zero],
                     [-sin_phi, cos_phi, zero],
                     [zero, zero, zero + 1.0]])


def skew(v):
    """Return the skew-symmetric matrix ``v~`` with ``v~ w = v x w``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]],
                     [-v[1], v[0], 0.0]])


def unskew(s):
    """Vector of a skew-symmetric matrix (its antisymmetric part)."""
    return 0.5 * np.array([s[2, 1] - s[1, 2], s[0, 2] - s[2, 0],
                           s[1, 0] - s[0, 1]])


# The drawing's axis of each leg's slider, n_A = e_x, n_B = e_y, n_C = e_z.
DRAWING_AXIS = {'A': U1, 'B': U2, 'C': U3}

LegFrame = namedtuple('LegFrame', ('point', 'rotation', 'offset', 'length',
                                   'attachment'))
LegFrame.__doc__ = """One leg as built (doc/model.md#the-machine-as-built).

``point`` a (m), ``rotation`` (3x3) the smallest rotation taking the
drawing's axis onto the leg's direction u, ``offset`` e (m), ``length``
L (m), ``attachment`` r (m); frame 0.
"""


@functools.lru_cache(maxsize=64)
def leg_frame(robot, leg):
    """Return leg ``leg``'s :class:`LegFrame` from the robot's rows."""
    suffix = leg.lower()
    index = LEGS.index(leg)
    direction = np.asarray(getattr(robot, f'axis_direction_{suffix}'))
    direction = direction / np.linalg.norm(direction)
    axis = DRAWING_AXIS[leg]
    cross = np.cross(axis, direction)
    sine = np.linalg.norm(cross)
    turn = np.zeros(3) if sine == 0.0 else cross / sine * np.arctan2(
        sine, axis @ direction)
    return LegFrame(np.asarray(getattr(robot, f'axis_point_{suffix}')),
                    Rotation.from_rotvec(turn).as_matrix(),
                    robot.joint_offset[index], robot.bar_length[index],
                    np.asarray(getattr(robot, f'attachment_{suffix}')))


Geometry = namedtuple('Geometry', (
    'lam', 'sin21', 'cos21', 'sin32', 'cos32', 'rotation', 'joints',
    'centre'))
Geometry.__doc__ = """One leg's configuration (eqs. 1-9).

``lam``: slider displacement (m); ``sin21 ... cos32``: sine and cosine of
phi21, phi32; ``rotation[k]``: ``a_k0`` (frame 0 -> frame k) for k in
1..6; ``joints``: 'A1' ... 'A7' and 'G' in frame 0 (m); ``centre[k]``:
centre of mass of body k in frame 0 (m), k in 1, 2, 3, 4, 6.
"""


def leg_geometry(robot, leg, position):
    """
    Build the chain (1)-(8) of leg ``leg`` for the centre ``position``.

    ``position`` is (x, y, z) in frame 0, real or complex. The leg sees its
    platform point ``G + r`` from its axis point ``a``, turned back by its
    rotation and then as the drawing's leg does (``LEG_AXES``); eq. (9)
    with its bar length gives the joint variables on the home branch
    (cosines positive) and its slider's true position, the reading plus
    its offset.
    """
    frame = leg_frame(robot, leg)
    seen = frame.rotation.T @ (np.asarray(position) + frame.attachment
                               - frame.point)
    i, j, k = LEG_AXES[leg]
    x, y, z = seen[i], seen[j], seen[k]
    l3 = frame.length
    sin32 = -z / l3
    cos32 = np.sqrt(1.0 - sin32 * sin32)
    sin21 = y / (l3 * cos32)
    cos21 = np.sqrt(1.0 - sin21 * sin21)
    slider = x + l3 * (1.0 - cos21 * cos32)
    lam = slider - frame.offset

    a10 = BASE_ROTATION[leg] @ frame.rotation.T
    a21 = a_phi(sin21, cos21) @ PAPER_A2
    a32 = a_phi(sin32, cos32) @ PAPER_A3
    a43 = a_phi(sin32, cos32) @ PAPER_A4     # phi43 = phi32, eq. (5)
    a54 = a_phi(sin21, cos21) @ PAPER_A2     # phi54 = phi21, eq. (5)
    a62 = a32
    rot = {1: a10 + 0.0 * lam}
    rot[2] = a21 @ rot[1]
    rot[3] = a32 @ rot[2]
    rot[4] = a43 @ rot[3]
    rot[5] = a54 @ rot[4]
    rot[6] = a62 @ rot[2]

    side, l1, l2 = robot.l, robot.l1, robot.l2
    ca, sa = np.cos(robot.alpha), np.sin(robot.alpha)
    r21 = np.array([0.0, l1 * sa, l1 * ca])
    r32 = -(l2 / 2.0) * U3
    r62 = (l2 / 2.0) * U3
    r43 = -l3 * U2
    r54 = (l2 / 2.0) * U1
    r5g = np.array([l1 * sa, -side / 2.0, 0.0])

    joints = {'A1': frame.point + (slider - l1 * ca - l3 - side / 2.0)
              * (rot[1].T @ U3)}
    joints['A2'] = joints['A1'] + rot[1].T @ r21
    joints['A3'] = joints['A2'] + rot[2].T @ r32
    joints['A6'] = joints['A2'] + rot[2].T @ r62
    joints['A4'] = joints['A3'] + rot[3].T @ r43
    joints['A7'] = joints['A6'] + rot[6].T @ r43
    joints['A5'] = joints['A4'] + rot[4].T @ r54
    joints['G'] = joints['A5'] + rot[5].T @ r5g - frame.attachment

    # Centres of mass (doc/model.md's table), each from its body's frame.
    centre = {
        1: joints['A1'] + rot[1].T @ (r21 / 2.0),
        2: joints['A2'],
        3: joints['A3'] + rot[3].T @ (-(l3 / 2.0) * U2),
        6: joints['A6'] + rot[6].T @ (-(l3 / 2.0) * U2),
        4: joints['A4'] + rot[4].T @ ((l2 / 2.0) * U1),
    }
    return Geometry(lam, sin21, cos21, sin32, cos32, rot, joints, centre)


def masses(robot):
    """
    Return the mass (kg) of each body of a leg and of the platform (key 5).

    The platform carries the payload: one rigid body of ``m5 + payload``.
    """
    return {1: robot.m1, 2: robot.m2, 3: robot.m3, 4: robot.m4,
            5: robot.m5 + robot.payload, 6: robot.m6}


def central_inertias(robot, leg='A'):
    """
    Inertia (kg m^2) about the centre of mass, body frame (doc/model.md).

    Of leg ``leg``'s bodies (its bars of its own length). Bodies 1 and 5
    only translate; their inertia is given for completeness (body 1 as a
    thin rod, body 5 as the cube).
    """
    l1, l2, side = robot.l1, robot.l2, robot.l
    l3 = leg_frame(robot, leg).length
    return {
        1: robot.m1 * l1 ** 2 / 12.0 * np.diag([1.0, 1.0, 0.0]),
        2: robot.m2 * l2 ** 2 / 12.0 * np.diag([1.0, 1.0, 0.0]),
        3: robot.m3 * l3 ** 2 / 12.0 * np.diag([1.0, 0.0, 1.0]),
        6: robot.m6 * l3 ** 2 / 12.0 * np.diag([1.0, 0.0, 1.0]),
        4: robot.m4 * l2 ** 2 / 12.0 * np.diag([0.0, 1.0, 1.0]),
        5: robot.m5 * side ** 2 / 6.0 * np.eye(3),
    }


def actuator_displacements(robot, position):
    """``(lambda_A, lambda_B, lambda_C)`` (m) by eq. (9)."""
    return np.array([leg_geometry(robot, leg, position).lam
                     for leg in LEGS])


def lambda_jacobian(robot, position):
    """``J_lambda = d lambda / d r_G`` (3x3) by complex step."""
    q = np.asarray(position, dtype=float)
    jac = np.empty((3, 3))
    for i in range(3):
        dq = q.astype(complex)
        dq[i] += 1j * COMPLEX_STEP
        jac[:, i] = actuator_displacements(robot, dq).imag / COMPLEX_STEP
    return jac


def sphere_residuals(robot, position, lam):
    """
    Each leg's eq. (14) as built: ``|G + r - a - (lambda + e - L) u| - L``.

    ``position`` G (m) and ``lam`` (m, A, B, C); zero where G is a
    platform position of these joint readings.
    """
    out = []
    for index, leg in enumerate(LEGS):
        frame = leg_frame(robot, leg)
        u = frame.rotation @ DRAWING_AXIS[leg]
        centre = frame.point - frame.attachment + (
            lam[index] + frame.offset - frame.length) * u
        out.append(np.linalg.norm(np.asarray(position) - centre)
                   - frame.length)
    return np.array(out)


def platform_position(robot, lam, start=(0.0, 0.0, 0.0)):
    """
    Forward kinematics: G (m) from the joint readings ``lam`` (m).

    The three spheres of :func:`sphere_residuals` solved by scipy's
    ``least_squares`` from ``start`` (home), to its tightest tolerances.
    """
    result = least_squares(lambda g: sphere_residuals(robot, g, lam),
                           np.asarray(start, dtype=float), method='lm',
                           xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return result.x


BodyJacobians = namedtuple('BodyJacobians', (
    'centre', 'rotation', 'linear', 'angular'))
BodyJacobians.__doc__ = """Every body's state and Jacobians at one q.

Dicts keyed by ``(leg, k)`` for the leg bodies and ``('platform', 5)``:
``centre`` (3,) m and ``rotation`` (3x3, body frame -> frame 0) at q,
``linear`` = d centre / dq and ``angular`` (3x3, omega = angular @ qdot,
frame 0).
"""


def body_jacobians(robot, position):
    """
    Centres, orientations and Jacobians of all bodies by complex step.

    The angular Jacobian's column i is the vector of
    ``(dR/dq_i) R^T`` with ``R = a_k0^T`` the body's orientation in frame 0.
    """
    q = np.asarray(position, dtype=float)
    base = {leg: leg_geometry(robot, leg, q) for leg in LEGS}
    perturbed = []
    for i in range(3):
        dq = q.astype(complex)
        dq[i] += 1j * COMPLEX_STEP
        perturbed.append({leg: leg_geometry(robot, leg, dq) for leg in LEGS})
    centre, rotation, linear, angular = {}, {}, {}, {}
    for leg in LEGS:
        for k in LEG_BODIES:
            key = (leg, k)
            rot = base[leg].rotation[k].T.real
            centre[key] = base[leg].centre[k].real
            rotation[key] = rot
            jv = np.empty((3, 3))
            jw = np.empty((3, 3))
            for i in range(3):
                geo = perturbed[i][leg]
                jv[:, i] = geo.centre[k].imag / COMPLEX_STEP
                d_rot = geo.rotation[k].T.imag / COMPLEX_STEP
                jw[:, i] = unskew(d_rot @ rot.T)
            linear[key] = jv
            angular[key] = jw
    # The platform: one body, centre G = q, translating (a50 constant).
    key = ('platform', 5)
    centre[key] = q.copy()
    rotation[key] = base['A'].rotation[5].T.real
    linear[key] = np.eye(3)
    angular[key] = np.zeros((3, 3))
    return BodyJacobians(centre, rotation, linear, angular)


def _body_mass_inertia(robot, key, rotation):
    mass = masses(robot)[key[1]]
    inertia = central_inertias(robot, key[0] if key[0] in LEGS else 'A')[
        key[1]]
    return mass, rotation @ inertia @ rotation.T


def mass_matrix(robot, position):
    """
    ``M(q) = sum m Jv^T Jv + Jw^T I Jw`` over every body (kg).

    And the drives: a rotor geared to slider j stores ``armature_j
    lambdadot_j^2 / 2``, ``J_lambda^T diag(armature) J_lambda`` in M.
    """
    jac = body_jacobians(robot, position)
    mm = np.zeros((3, 3))
    for key in jac.centre:
        mass, inertia = _body_mass_inertia(robot, key, jac.rotation[key])
        jv, jw = jac.linear[key], jac.angular[key]
        mm += mass * jv.T @ jv + jw.T @ inertia @ jw
    j_lambda = lambda_jacobian(robot, position)
    return mm + j_lambda.T @ np.diag(robot.armature) @ j_lambda


def kinetic_energy(robot, position, velocity):
    """
    T (J): sum over every body of m |v_C|^2 / 2 + omega^T I omega / 2.

    And each drive's ``armature_j lambdadot_j^2 / 2``.
    """
    jac = body_jacobians(robot, position)
    qd = np.asarray(velocity, dtype=float)
    total = 0.0
    for key in jac.centre:
        mass, inertia = _body_mass_inertia(robot, key, jac.rotation[key])
        v = jac.linear[key] @ qd
        w = jac.angular[key] @ qd
        total += 0.5 * mass * v @ v + 0.5 * w @ inertia @ w
    rates = lambda_jacobian(robot, position) @ qd
    return total + 0.5 * float(np.asarray(robot.armature) @ rates ** 2)


def potential_energy(robot, position):
    """
    V (J) = -sum m g . r_C over every body (platform once), plus the ripple.

    The drives' screw ripple is :func:`ripple_potential`.
    """
    g = np.asarray(robot.gravity, dtype=float)
    total = -masses(robot)[5] * g @ np.asarray(position, dtype=float)
    for leg in LEGS:
        geo = leg_geometry(robot, leg, position)
        for k in LEG_BODIES:
            total -= masses(robot)[k] * g @ geo.centre[k]
    return total + ripple_potential(robot, position)


def ripple_potential(robot, position):
    """
    V_r (J): the screw ripple of the drives as a potential of the sliders.

    A drive of lead ``p_j`` whose force periodic in its screw's angle
    ``phi = 2 pi lambda_j / p_j`` is ``s_j sin(phi) + c_j cos(phi)``
    (doc/model.md#drives-and-payload) stores ``V_j = (p_j / 2 pi) (c_j
    sin(phi) - s_j cos(phi))``, whose derivative along the slider is that
    force; 0 without a lead. ``position`` real or complex (eq. 9 for
    lambda).
    """
    total = 0.0
    lam = None
    for j, lead in enumerate(robot.screw_lead):
        if lead == 0.0:
            continue
        if lam is None:
            lam = [leg_geometry(robot, leg, position).lam for leg in LEGS]
        phi = 2.0 * np.pi * lam[j] / lead
        total = total + lead / (2.0 * np.pi) * (
            robot.ripple_cosine[j] * np.sin(phi)
            - robot.ripple_sine[j] * np.cos(phi))
    return total


def potential_gradient(robot, position):
    """
    dV/dq (N) = -sum m Jv^T g plus the ripple's, exact (complex step).

    The ripple's part is the complex-step derivative of
    :func:`ripple_potential` along each coordinate of q.
    """
    jac = body_jacobians(robot, position)
    g = np.asarray(robot.gravity, dtype=float)
    grad = np.zeros(3)
    for key in jac.centre:
        grad -= masses(robot)[key[1]] * jac.linear[key].T @ g
    if any(robot.screw_lead):
        q = np.asarray(position, dtype=float)
        for i in range(3):
            dq = q.astype(complex)
            dq[i] += 1j * COMPLEX_STEP
            grad[i] += np.imag(ripple_potential(robot, dq)) / COMPLEX_STEP
    return grad


def mass_matrix_derivative(robot, position, step=MASS_MATRIX_STEP):
    """``dM/dq`` as an array ``[k, i, j] = dM_ij / dq_k`` (central FD)."""
    q = np.asarray(position, dtype=float)
    dm = np.empty((3, 3, 3))
    for k in range(3):
        dq = np.zeros(3)
        dq[k] = step
        dm[k] = (mass_matrix(robot, q + dq)
                 - mass_matrix(robot, q - dq)) / (2.0 * step)
    return dm


LagrangeSolution = namedtuple('LagrangeSolution', (
    'force', 'generalised_force', 'mass_matrix', 'coriolis', 'gravity',
    'dmass', 'jacobian'))
LagrangeSolution.__doc__ = """Lagrange's equations on q = r_G.

``force`` (N, actuators A, B, C) = ``J_lambda^-T generalised_force``;
``generalised_force`` = ``mass_matrix @ qdd + coriolis + gravity`` (N);
``dmass[k, i, j] = dM_ij/dq_k``; ``jacobian`` = ``J_lambda``.
"""


def lagrange_forces(robot, position, velocity, acceleration,
                    step=MASS_MATRIX_STEP):
    """
    Actuator forces (N) by Lagrange's equations with q = r_G.

    ``d/dt dT/dqd - dT/dq + dV/dq = Q`` with ``T = qd^T M(q) qd / 2``
    gives ``Q = M qdd + C + dV/dq``, ``C_i = sum_jk (dM_ij/dq_k -
    dM_jk/dq_i / 2) qd_j qd_k``; the actuators' virtual work
    ``f . d lambda = Q . dq`` gives ``f = J_lambda^-T Q``.
    """
    q = np.asarray(position, dtype=float)
    qd = np.asarray(velocity, dtype=float)
    qdd = np.asarray(acceleration, dtype=float)
    mm = mass_matrix(robot, q)
    dm = mass_matrix_derivative(robot, q, step)
    coriolis = (np.einsum('kij,j,k->i', dm, qd, qd)
                - 0.5 * np.einsum('ijk,j,k->i', dm, qd, qd))
    grav = potential_gradient(robot, q)
    gen = mm @ qdd + coriolis + grav
    jac = lambda_jacobian(robot, q)
    force = np.linalg.solve(jac.T, gen)
    return LagrangeSolution(force, gen, mm, coriolis, grav, dm, jac)


# The error of lagrange_forces (derived in test_lagrange.py's docstring):
# the Christoffel terms carry DM_RELATIVE of ``|dM/dq| |qd|^2`` (the central
# difference of M), every other term ROUNDING of its size.
DM_RELATIVE = 1e-8
ROUNDING = 1e-12


def rest_forces(robot, position, acceleration):
    """
    Return the forces (N) at zero velocity, exact to rounding, and a bound.

    No Christoffel term: ``f = J_lambda^-T (M qdd + dV/dq)`` from the
    complex-step Jacobians alone, each term to ROUNDING of its size,
    amplified by at most ``|J_lambda^-T|``.
    """
    mm = mass_matrix(robot, position)
    grad = potential_gradient(robot, position)
    jac = lambda_jacobian(robot, position)
    expected = np.linalg.solve(jac.T, mm @ acceleration + grad)
    bound = ROUNDING * np.linalg.norm(np.linalg.inv(jac.T), 2) * (
        np.abs(mm).max() * 3.0 * np.abs(acceleration).max()
        + np.abs(grad).max())
    return expected, bound + 1e-300


def force_tolerance(ref, velocity, acceleration):
    """Error bound (N) on ``ref.force``, a :class:`LagrangeSolution`."""
    inverse_t = np.linalg.norm(np.linalg.inv(ref.jacobian.T), 2)
    speed2 = np.asarray(velocity) @ np.asarray(velocity)
    fd_part = DM_RELATIVE * np.abs(ref.dmass).max() * 9.0 * speed2
    exact_part = ROUNDING * (
        np.abs(ref.mass_matrix).max() * 3.0 * np.abs(acceleration).max()
        + np.abs(ref.gravity).max() + np.abs(ref.coriolis).max())
    return inverse_t * (fd_part + exact_part) + 1e-300


# --- Shared helpers of the test suite (no part of the second model) ---

# Half side (m) of the tested workspace cube |x|, |y|, |z| <= CUBE (doc/model.md).
CUBE = 0.3

# A robot unlike the paper's in every length, angle and in m4, m6 (which
# then differ from their defaults m2, m3): keyword arguments of Robot.
OTHER_ROBOT_VALUES = {
    'l': 0.13, 'l1': 0.21, 'l2': 0.11, 'l3': 0.93, 'alpha': 0.61,
    'm1': 0.47, 'm2': 0.31, 'm3': 1.9, 'm4': 0.53, 'm5': 11.0, 'm6': 3.1,
}
# A robot with ball-screw drives (a motor's rotor inertia reflected onto
# each slider, unequal: J (2 pi / lead)^2 = 8e-5 kg m^2 on a 10 mm lead is
# 3.2 kg) and a payload on its platform: keyword arguments of Robot.
DRIVES_ROBOT_VALUES = {'armature': (3.2, 1.1, 0.45), 'payload': 5.0}

# Fast trajectories of eq. (6)'s shape, r* (1 - cos(omega t)): targets
# (m) whose whole path 0 .. 2 r* stays in the cube, and omega (rad/s).
FAST_TRAJECTORIES = (
    ((0.15, -0.15, 0.12), 4.0),
    ((-0.12, 0.15, -0.15), 6.0),
    ((0.15, 0.15, 0.15), 8.0),
)


def batch_rows(n, chunk, seed, count=20):
    """
    Rows of an n-row batch to check against the reference, sorted.

    Both sides of every boundary of the package's ``chunk``-row pieces, the
    first and last two, and ``count`` random ones.
    """
    rows = {0, 1, n - 2, n - 1}
    for start in range(chunk, n, chunk):
        rows |= {start - 1, start, start + 1}
    rng = np.random.default_rng(seed)
    return sorted(rows | set(rng.integers(0, n, count).tolist()))


def cube_points(half=CUBE):
    """Hypothesis strategy: a point (3,) of the cube |x|,|y|,|z| <= half."""
    from hypothesis import strategies as st
    coordinate = st.floats(-half, half, allow_nan=False,
                           allow_infinity=False)
    return st.tuples(coordinate, coordinate, coordinate).map(np.array)


# Deviations of a robot as built from the drawing (m, deg): a built
# Orthoglide's (0.1-1 mm, 0.05-0.3 deg) and ten to twenty times more.
DEVIATION_SIZES = {'built': ((1e-4, 1e-3), (0.05, 0.3)),
                   'large': ((1e-3, 2e-2), (0.3, 3.0))}


def _vector_of_length(draw, low, high):
    """Draw a 3-vector of length in [low, high], any direction."""
    from hypothesis import strategies as st
    direction = draw(st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(
        lambda v: 0.1 <= np.linalg.norm(v)))
    length = draw(st.floats(low, high))
    return tuple(length * np.asarray(direction) / np.linalg.norm(direction))


def tilted(axis, degrees, towards):
    """Return the unit ``axis`` turned by ``degrees`` towards ``towards``."""
    across = np.asarray(towards) - (np.asarray(towards) @ axis) * axis
    across /= np.linalg.norm(across)
    angle = np.radians(degrees)
    return tuple(np.cos(angle) * axis + np.sin(angle) * across)


def deviations(size='built', l3=0.85):
    """
    Hypothesis strategy: the per-leg rows of a robot as built (a dict).

    Every row deviates from the drawing by an amount of ``size``
    (:data:`DEVIATION_SIZES`): each axis point and attachment by a vector
    of that length, each direction tilted by that angle towards any side,
    each joint offset and bar length (about ``l3``) by that much either
    way.
    """
    from hypothesis import strategies as st
    (low, high), (tilt_low, tilt_high) = DEVIATION_SIZES[size]

    @st.composite
    def rows(draw):
        out = {}
        signed = st.tuples(st.floats(low, high), st.sampled_from((-1, 1))).map(
            lambda t: t[0] * t[1])
        for leg, axis in zip('abc', (U1, U2, U3)):
            out[f'axis_point_{leg}'] = _vector_of_length(draw, low, high)
            out[f'attachment_{leg}'] = _vector_of_length(draw, low, high)
            towards = draw(st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(
                lambda v: np.linalg.norm(np.cross(v, axis)) >= 0.1))
            out[f'axis_direction_{leg}'] = tilted(
                axis, draw(st.floats(tilt_low, tilt_high)), towards)
        out['joint_offset'] = tuple(draw(signed) for _ in range(3))
        out['bar_length'] = tuple(l3 + draw(signed) for _ in range(3))
        return out
    return rows()


def vectors(bound):
    """Hypothesis strategy: a vector (3,) with components in [-bound, bound]."""
    return cube_points(bound)


def derivative(f, t, h):
    """
    Fourth-order central difference of ``f`` (array-valued) at ``t``.

    ``(f(t-2h) - 8 f(t-h) + 8 f(t+h) - f(t+2h)) / 12h``: truncation error
    ``h^4 f^(5) / 30``, rounding about ``1.5 eps max|f| / h``.
    """
    values = [np.asarray(f(t + k * h), dtype=float) for k in (-2, -1, 1, 2)]
    return (values[0] - 8.0 * values[1] + 8.0 * values[2]
            - values[3]) / (12.0 * h)
