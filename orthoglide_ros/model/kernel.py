"""
The arithmetic kernel of the paper's recursive matrix method.

The recursion of sections 2 and 3, eqs. (9)-(25), corrected as
doc/model.md#errata-and-traps lists, in scalar arithmetic with only ``+ -
* /`` and a ``sqrt`` passed in: the same code runs on floats and on numpy
arrays. It does not validate (:mod:`mechanics` does;
doc/model.md#the-method).
"""

from __future__ import annotations

from typing import Any, Callable, Optional
from collections import namedtuple

# |cof|_F^2 / |J|_F^4 at or below which J_lambda counts as of rank one
# (1 / kappa_F = 0): there ``det J`` is rounding alone (about 1e-16 |J|^3
# where every slider reads l3, on the sphere |G| = l3), the true 1 /
# kappa_F below 1e-10, and the ratio of roundings would be any number.
RANK_ONE = 1e-20

# Constants of the kernel derived once from a Robot
# (:func:`robot.kernel_constants`).
KernelConstants = namedtuple('KernelConstants', (
    'l3', 'minus_inv_l3', 'h3', 'i3', 'm1', 'm2', 'm3', 'm4', 'm5', 'm6',
    'h4', 'p5', 'q5', 'gx', 'gy', 'gz'))


def solve(k: 'KernelConstants', x: Any, y: Any, z: Any, vx: Any, vy: Any,
          vz: Any, ax: Any, ay: Any, az: Any, sqrt: Callable[[Any], Any],
          record: Optional[dict[str, Any]] = None) -> Optional[tuple]:
    """
    Inverse kinematics and dynamics of the whole robot (eqs. 9-25).

    Takes G's position (m), velocity (m/s) and acceleration (m/s^2) in frame
    0, as floats or equal-shaped arrays. Returns ``(lam, lamd, lamdd, force,
    power, alphas, jac_inverse_condition)``: the actuators' displacement (m),
    rate (m/s), acceleration (m/s^2), forces (N) and powers (W), the
    ``alpha_i`` of eq. (17) (m) and ``1 / kappa_F(J_lambda)``. The forces:
    ``f = F1 + J_lambda^-T sum(Q_leg)`` (eq. 25, doc/model.md#the-method).
    ``record``, if a dict, receives every leg's per-element quantities
    (``record['A']``, ``['B']``, ``['C']``; see ``_leg``).
    """
    gx, gy, gz = k.gx, k.gy, k.gz
    ra = rb = rc = None
    if record is not None:
        ra, rb, rc = record['A'], record['B'], record['C'] = {}, {}, {}
    lam_a, lamd_a, lamdd_a, al_a, f1_a, qy_a, qz_a = _leg(
        k, x, y, z, vx, vy, vz, ax, ay, az, gx, gy, gz, True, sqrt, ra)
    lam_b, lamd_b, lamdd_b, al_b, f1_b, qy_b, qz_b = _leg(
        k, y, z, x, vy, vz, vx, ay, az, ax, gy, gz, gx, False, sqrt, rb)
    lam_c, lamd_c, lamdd_c, al_c, f1_c, qy_c, qz_c = _leg(
        k, z, x, y, vz, vx, vy, az, ax, ay, gz, gx, gy, False, sqrt, rc)

    # Generalised force on the platform in frame 0: leg B's local (y, z)
    # are frame 0's (z, x), leg C's are (x, y).
    qx = qz_b + qy_c
    qy = qy_a + qz_c
    qz = qz_a + qy_b

    # Eq. (25)'s last step, written again in solve_legs: one function for
    # both cost this path 0-5 %
    # (doc/measurements.md#speed-of-the-mechanics).
    (c11, c12, c13, c21, c22, c23, c31, c32, c33), det, inverse_condition = \
        jacobian_cofactors(x, y, z, al_a, al_b, al_c, sqrt)
    rd = 1.0 / det
    f_a = f1_a + (c11 * qx + c12 * qy + c13 * qz) * rd
    f_b = f1_b + (c21 * qx + c22 * qy + c23 * qz) * rd
    f_c = f1_c + (c31 * qx + c32 * qy + c33 * qz) * rd

    return ((lam_a, lam_b, lam_c), (lamd_a, lamd_b, lamd_c),
            (lamdd_a, lamdd_b, lamdd_c), (f_a, f_b, f_c),
            (lamd_a * f_a, lamd_b * f_b, lamd_c * f_c), (al_a, al_b, al_c),
            inverse_condition)


# One leg as built, for :func:`solve_legs` (``robot.leg_constants``): ``k``
# its KernelConstants (its bar length L_i as ``l3``, gravity in its frame),
# ``frame`` its R_i row by row (9 floats), ``shift`` ``r_i - a_i`` (m,
# frame 0) and ``offset`` its joint offset ``e_i`` (m).
LegConstants = namedtuple('LegConstants', ('k', 'frame', 'shift', 'offset'))


def leg_point(leg: 'LegConstants', x: Any, y: Any, z: Any) -> tuple:
    """
    Return the platform point as leg ``leg`` sees it, less its offset.

    ``(x', y', z') = R_i^T (G + r_i - a_i) - (e_i, 0, 0)`` for ``G = (x,
    y, z)`` (m, frame 0; floats or arrays): eq. (9) on it with ``l3 =
    L_i`` gives the joint reading, ``lambda_i = x' + L_i - alpha_i``
    (doc/model.md#the-machine-as-built).
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = leg.frame
    sx, sy, sz = leg.shift
    px, py, pz = x + sx, y + sy, z + sz
    return (r00 * px + r10 * py + r20 * pz - leg.offset,
            r01 * px + r11 * py + r21 * pz,
            r02 * px + r12 * py + r22 * pz)


def solve_legs(legs: tuple, x: Any, y: Any, z: Any, vx: Any, vy: Any,
               vz: Any, ax: Any, ay: Any, az: Any, sqrt: Callable[[Any], Any],
               record: Optional[dict[str, Any]] = None) -> tuple:
    """
    :func:`solve` for legs as built: each in its own frame R_i.

    ``legs``: three :data:`LegConstants` (A, B, C). Each leg runs the
    one-leg recursion on :func:`leg_point` and on ``R_i^T`` of the
    velocity, acceleration and gravity; its generalised force ``(0, Qy,
    Qz)`` goes back to frame 0 as ``R_i (0, Qy, Qz)``, and ``J_lambda``'s
    row i is ``R_i (1, y'/alpha_i, z'/alpha_i)``: ``f = F1 + J_lambda^-T
    sum_i R_i Q_i`` (eq. 25). Takes and returns what :func:`solve` does.
    """
    ra = rb = rc = None
    if record is not None:
        ra, rb, rc = record['A'], record['B'], record['C'] = {}, {}, {}
    lam_a, lamd_a, lamdd_a, al_a, f1_a, qa, ja = _leg_in_frame(
        legs[0], x, y, z, vx, vy, vz, ax, ay, az, True, sqrt, ra)
    lam_b, lamd_b, lamdd_b, al_b, f1_b, qb, jb = _leg_in_frame(
        legs[1], x, y, z, vx, vy, vz, ax, ay, az, False, sqrt, rb)
    lam_c, lamd_c, lamdd_c, al_c, f1_c, qc, jc = _leg_in_frame(
        legs[2], x, y, z, vx, vy, vz, ax, ay, az, False, sqrt, rc)
    qx = qa[0] + qb[0] + qc[0]
    qy = qa[1] + qb[1] + qc[1]
    qz = qa[2] + qb[2] + qc[2]
    (c11, c12, c13, c21, c22, c23, c31, c32, c33), det, inverse_condition = \
        cofactors(ja + jb + jc, sqrt)
    rd = 1.0 / det
    f_a = f1_a + (c11 * qx + c12 * qy + c13 * qz) * rd
    f_b = f1_b + (c21 * qx + c22 * qy + c23 * qz) * rd
    f_c = f1_c + (c31 * qx + c32 * qy + c33 * qz) * rd
    return ((lam_a, lam_b, lam_c), (lamd_a, lamd_b, lamd_c),
            (lamdd_a, lamdd_b, lamdd_c), (f_a, f_b, f_c),
            (lamd_a * f_a, lamd_b * f_b, lamd_c * f_c), (al_a, al_b, al_c),
            inverse_condition)


def _leg_in_frame(leg, x, y, z, vx, vy, vz, ax, ay, az, platform, sqrt,
                  record):
    """
    One leg as built: ``_leg`` in its frame, its results in frame 0.

    Returns ``(lambda, lambdadot, lambdaddot, alpha_i, F1, R_i (0, Qy,
    Qz), J_lambda's row i)``, the last two 3-tuples in frame 0.
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = leg.frame
    k = leg.k
    px, py, pz = leg_point(leg, x, y, z)
    lam, lamd, lamdd, al, f1, qy, qz = _leg(
        k, px, py, pz,
        r00 * vx + r10 * vy + r20 * vz, r01 * vx + r11 * vy + r21 * vz,
        r02 * vx + r12 * vy + r22 * vz,
        r00 * ax + r10 * ay + r20 * az, r01 * ax + r11 * ay + r21 * az,
        r02 * ax + r12 * ay + r22 * az,
        k.gx, k.gy, k.gz, platform, sqrt, record)
    ra = 1.0 / al
    ty, tz = py * ra, pz * ra
    return (lam, lamd, lamdd, al, f1,
            (r01 * qy + r02 * qz, r11 * qy + r12 * qz, r21 * qy + r22 * qz),
            (r00 + r01 * ty + r02 * tz, r10 + r11 * ty + r12 * tz,
             r20 + r21 * ty + r22 * tz))


def cofactors(j: Any, sqrt: Callable[[Any], Any]) -> tuple:
    """
    Cofactors, determinant and ``1 / kappa_F`` of any 3x3 ``J_lambda``.

    ``j``: its 9 entries row by row. Returns ``(cof, det,
    inverse_condition)`` as :func:`jacobian_cofactors` does (``cof[3 i +
    m]`` the cofactor of entry (i, m): ``J^-T = cof / det``).
    """
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = j
    c00, c01, c02 = j11 * j22 - j12 * j21, j12 * j20 - j10 * j22, \
        j10 * j21 - j11 * j20
    c10, c11, c12 = j02 * j21 - j01 * j22, j00 * j22 - j02 * j20, \
        j01 * j20 - j00 * j21
    c20, c21, c22 = j01 * j12 - j02 * j11, j02 * j10 - j00 * j12, \
        j00 * j11 - j01 * j10
    det = j00 * c00 + j01 * c01 + j02 * c02
    jj = (j00 * j00 + j01 * j01 + j02 * j02 + j10 * j10 + j11 * j11
          + j12 * j12 + j20 * j20 + j21 * j21 + j22 * j22)
    cc = (c00 * c00 + c01 * c01 + c02 * c02 + c10 * c10 + c11 * c11
          + c12 * c12 + c20 * c20 + c21 * c21 + c22 * c22)
    return ((c00, c01, c02, c10, c11, c12, c20, c21, c22), det,
            3.0 * abs(det) / sqrt(jj * cc) * (cc > RANK_ONE * jj * jj)
            * (det > 0.0))


def jacobian_cofactors(x: Any, y: Any, z: Any, al_a: Any, al_b: Any, al_c: Any,
                       sqrt: Callable[[Any], Any]) -> tuple:
    """
    Cofactors and determinant of ``J_lambda = J1^-1 J2`` (eqs. 15-17).

    ``J_lambda = [[1, y/al_a, z/al_a], [x/al_b, 1, z/al_b], [x/al_c,
    y/al_c, 1]]`` maps the platform velocity to ``lambdadot``; its inverse
    transpose is ``cof / det``. Returns ``(cof, det, inverse_condition)``
    with ``cof`` the 9 cofactors row by row and ``inverse_condition =
    3 |det| / (|J|_F |cof|_F) = 1 / kappa_F``, the normalised inverse
    Frobenius condition number: 1 at home, 0 where J2 is singular (and
    where ``J_lambda`` has rank one to rounding, :data:`RANK_ONE`) and
    beyond it, where ``det J_lambda < 0``: the other assembly mode, where
    a robot assembled as at home is never (its forward kinematics at these
    lambda is the mirror point).
    """
    ra, rb, rc = 1.0 / al_a, 1.0 / al_b, 1.0 / al_c
    ja, jb = y * ra, z * ra
    jc, jd = x * rb, z * rb
    je, jf = x * rc, y * rc
    cof = (1.0 - jd * jf, jd * je - jc, jc * jf - je,
           jb * jf - ja, 1.0 - jb * je, ja * je - jf,
           ja * jd - jb, jb * jc - jd, 1.0 - ja * jc)
    det = cof[0] + ja * cof[1] + jb * cof[2]
    jj = 3.0 + ja * ja + jb * jb + jc * jc + jd * jd + je * je + jf * jf
    cc = 0.0
    for c in cof:
        cc = cc + c * c
    return cof, det, 3.0 * abs(det) / sqrt(jj * cc) * (
        cc > RANK_ONE * jj * jj) * (det > 0.0)


def _leg(k, x, y, z, vx, vy, vz, ax, ay, az, gx, gy, gz, platform, sqrt,
         record):
    """
    One leg in its own coordinates: kinematics and its virtual work.

    Returns ``(lambda, lambdadot, lambdaddot, alpha_i, F1, Qy, Qz)``: the
    slider's force term ``u3^T f_1`` of eq. (25) and the generalised force
    ``(0, Qy, Qz)`` that the leg's joint moments put on the platform's
    virtual velocity (leg coordinates). ``platform`` says whether the
    platform (body 5) belongs to this leg's tree (leg A only).

    Leg A sees the platform centre as ``(x, y, z)``, leg B as ``(y, z,
    x)`` and leg C as ``(z, x, y)`` (``b10 = a1 P``, ``c10 = a1 P^2``, P
    the cyclic permutation), so one function serves all three. A vector
    with the index ``k`` is in the frame of body ``k``; ``c1, s1`` are
    ``cos, sin(phi21)``, ``c2, s2`` ``cos, sin(phi32)``; ``w1, w2`` and
    ``e1, e2`` the relative rates ``omega21 = omega54``, ``omega32 =
    omega43 = omega62`` and their derivatives.
    """
    l3 = k.l3
    # Inverse geometry, eq. (9); alpha_i = l3 cos(phi21) cos(phi32), eq. (17).
    s2 = z * k.minus_inv_l3
    c2 = sqrt(1.0 - s2 * s2)
    r2 = 1.0 / (l3 * c2)
    s1 = y * r2
    c1 = sqrt(1.0 - s1 * s1)
    l3s1 = l3 * s1
    l3c1 = l3 * c1
    al = l3c1 * c2
    ra = 1.0 / al
    lam = x + l3 - al

    # Connectivity conditions (13), derived from (7)-(8) and solved:
    # v10 a10^T u3 - l3 w1 a20^T u3~ a32^T u2 - l3 w2 a30^T u3~ u2 = rdot_G.
    w2 = -vz * r2
    s2w2 = s2 * w2
    w1 = (vy + l3s1 * s2w2) * ra
    lamd = vx + l3s1 * c2 * w1 + l3c1 * s2w2
    # Their time derivative, eq. (18) with the signs of r43 = -l3 u2.
    w1w1 = w1 * w1
    w2w2 = w2 * w2
    w1w2 = w1 * w2
    s2w12 = 2.0 * s2 * w1w2
    e2 = (l3 * s2w2 * w2 - az) * r2
    se_cw = s2 * e2 + c2 * (w1w1 + w2w2)
    e1 = (ay + l3s1 * se_cw + l3c1 * s2w12) * ra
    c2e1 = c2 * e1
    a = ax + l3s1 * (c2e1 - s2w12) + l3c1 * se_cw

    # Recursion (10)-(12), (19), body by body (frames k). Body 1 translates:
    # gamma10 = a u3. Body 2: omega20 = w1 u3, epsilon20 = e1 u3,
    # gamma20 = a21 gamma10 = (c1 a, -s1 a, 0).
    c1a = c1 * a
    s1a = s1 * a
    # Body 3 (and its twin 6: a62 = a32, r62 parallel to omega20):
    # omega30 = a32 omega20 + w2 u3 = (-c2 w1, s2 w1, w2), epsilon30 from
    # (19) = (-c2 e1 + s2 w1 w2, s2 e1 + c2 w1 w2, e2), gamma30 = a32 gamma20
    # = (-s2 c1 a, -c2 c1 a, -s1 a) (r32 is parallel to omega20, epsilon20).
    # (omega30~ omega30~ + epsilon30~) r43 with r43 = -l3 u2 is
    # l3 (bx, by, -bz) with these brackets (also in body 3's moment):
    bx = e2 + s2 * c2 * w1w1            # eps_z - om_x om_y
    by = c2 * c2 * w1w1 + w2w2          # om_x^2 + om_z^2
    bz = s2w12 - c2e1                   # eps_x + om_y om_z
    # Body 4: omega40 = w1 u1 and epsilon40 = e1 u1 (parallel to body 2),
    # gamma40 = a43 (gamma30 + l3 (bx, by, -bz)).
    gx3 = l3 * bx - s2 * c1a
    gy3 = l3 * by - c2 * c1a
    g40x = s2 * gy3 - c2 * gx3
    g40y = s2 * gx3 + c2 * gy3
    g40z = s1a + l3 * bz

    # Gravity in frames 2 (hg, kg, gz), 3, 4 (gz, -hg, -kg) and 1 (z: gx).
    hg = c1 * gx + s1 * gy
    kg = c1 * gy - s1 * gx
    # Wrenches (20)-(24) per unit mass, about each body's joint A_k:
    # f = a_C - g, m = r_C~ (gamma - g) + I_A epsilon + omega~ I_A omega.
    # Body 3: r_C = r43 / 2, I_A = l3^2/3 diag(1, 0, 1) (parallel axis);
    # d3 = gamma30 - g3 with g3 = (-c2 gz - s2 hg, s2 gz - c2 hg, kg).
    hc = hg - c1a
    d3x = s2 * hc + c2 * gz
    d3y = c2 * hc - s2 * gz
    d3z = -(s1a + kg)
    h3 = k.h3
    i3 = k.i3
    f3x = d3x + h3 * bx
    f3y = d3y + h3 * by
    f3z = d3z - h3 * bz
    n3x = i3 * bz - h3 * d3z
    n3z = i3 * bx + h3 * d3x
    # Body 4: r_C = h4 u1 parallel to omega40, epsilon40: no rotary terms;
    # d4 = gamma40 - g4.
    m4 = k.m4
    m4h4 = m4 * k.h4
    d4y = g40y + hg
    d4z = g40z + kg
    f4x = m4 * (g40x - gz)
    f4y = m4 * d4y
    f4z = m4 * d4z
    n4y = -m4h4 * d4z
    n4z = m4h4 * d4y
    t21 = 0.0
    if platform:
        # Body 5, the platform, in leg A's tree: it translates, r_C = r5G;
        # d5 = a54 gamma40 - g5 (r54 parallel to omega40, epsilon40),
        # g5 = (-gy, -gx, -gz).
        m5 = k.m5
        h4 = k.h4
        p5 = m5 * k.p5
        q5 = m5 * k.q5
        d5x = c1 * g40z + s1 * g40y + gy
        d5y = c1 * g40y - s1 * g40z + gx
        d5z = gz - g40x
        n5x = q5 * d5z
        n5y = -p5 * d5z
        t21 = p5 * d5y - q5 * d5x           # m5_z
        # Accumulate into body 4 (23): a54^T f5, a54^T m5, r54~ a54^T f5.
        u1 = m5 * (s1 * d5x + c1 * d5y)
        u2 = m5 * (c1 * d5x - s1 * d5y)
        f4x = f4x - m5 * d5z
        f4y = f4y + u1
        f4z = f4z + u2
        n4x = -t21
        n4y = n4y + s1 * n5x + c1 * n5y - h4 * u2
        n4z = n4z + c1 * n5x - s1 * n5y + h4 * u1
    # Accumulate body 4 into body 3 (23): a43^T f4, a43^T m4, r43~ a43^T f4
    # with a43^T u = (s2 u1 - c2 u0, s2 u0 + c2 u1, -u2); body 6 (a leaf:
    # the parallelogram is cut at A7) adds m6 times body 3's own terms.
    m36 = k.m3 + k.m6
    u0 = s2 * f4y - c2 * f4x
    fx = m36 * f3x + u0
    fy = m36 * f3y + s2 * f4x + c2 * f4y
    fz = m36 * f3z - f4z
    nx = m36 * n3x + s2 * n4y + l3 * f4z
    ny = c2 * n4y
    if platform:
        nx = nx - c2 * n4x
        ny = ny + s2 * n4x
    # Eq. (25) groups joints 3-2, 4-3 and 6-2 (rate w2): m3_z + m4_z + m6_z.
    t32 = m36 * n3z + l3 * u0
    # Into body 2 (23): a32^T u = (-(s2 u0 + c2 u1), u2, -(c2 u0 - s2 u1)).
    t21 = t21 + s2 * ny - c2 * nx
    m2 = k.m2
    f2x = m2 * (c1a - hg) - s2 * fx - c2 * fy
    f2y = m2 * d3z + fz
    # Body 1 (23): u3^T (f10 + a21^T f2), with g1 = a10 g = (-gz, gy, gx).
    f1 = k.m1 * (a - gx) + c1 * f2x - s1 * f2y

    # Virtual rates of the leg for a platform virtual velocity delta r,
    # from (13): w2 = -dz / (l3 c2), w1 = (dy - s1 s2 dz / c2) / alpha_i.
    qy = t21 * ra
    qz = -(t32 * c1 + t21 * s1 * s2 / c2) * ra

    if record is not None:
        o3 = (-c2 * w1, s2 * w1, w2)
        e3 = (s2 * w1w2 - c2e1, s2 * e1 + c2 * w1w2, e2)
        _record_leg(record, l3, s1, c1, s2, c2, lam, lamd, a, w1, w2, e1,
                    e2, o3, e3, (-s2 * c1a, -c2 * c1a, -s1a),
                    (g40x, g40y, g40z))
    return lam, lamd, a, al, f1, qy, qz


def _record_leg(record, l3, s1, c1, s2, c2, lam, lamd, lamdd, w1, w2, e1,
                e2, o3, e3, g30, g40):
    """
    Store one leg's per-element quantities (frames k) in ``record``.

    Velocities are the same recursion (12) as the accelerations above:
    ``v20 = a21 v10``, ``v30 = a32 v20``, ``v40 = a43 (v30 + omega30~
    r43)``, ``v50 = a54 v40``; ``gamma50 = a54 gamma40``.
    """
    v30 = (-s2 * c1 * lamd, -c2 * c1 * lamd, -s1 * lamd)
    bx = v30[0] + l3 * o3[2]
    by = v30[1]
    v40 = (-c2 * bx + s2 * by, s2 * bx + c2 * by, l3 * o3[0] - v30[2])
    zero = 0.0 * lam
    record.update(
        phi21=(s1, c1), phi32=(s2, c2),
        lam=lam, lamd=lamd, lamdd=lamdd,
        omega21=w1, omega32=w2, epsilon21=e1, epsilon32=e2,
        omega={1: (zero, zero, zero), 2: (zero, zero, w1), 3: o3, 6: o3,
               4: (w1, zero, zero), 5: (zero, zero, zero)},
        epsilon={1: (zero, zero, zero), 2: (zero, zero, e1), 3: e3, 6: e3,
                 4: (e1, zero, zero), 5: (zero, zero, zero)},
        v={1: (zero, zero, lamd), 2: (c1 * lamd, -s1 * lamd, zero), 3: v30,
           6: v30, 4: v40, 5: _frame4_to_frame5(s1, c1, v40)},
        gamma={1: (zero, zero, lamdd),
               2: (c1 * lamdd, -s1 * lamdd, zero), 3: g30, 6: g30, 4: g40,
               5: _frame4_to_frame5(s1, c1, g40)})


def _frame4_to_frame5(s1, c1, u):
    """Apply ``a54 = a^phi21 a2`` (eq. 1) to a vector of frame 4."""
    return (c1 * u[2] + s1 * u[1], c1 * u[1] - s1 * u[2], -u[0])
