"""The arithmetic kernel of the paper's recursive matrix method.

One implementation of the recursion of sections 2 and 3 of the paper
(Chablat, Wenger, Staicu), corrected as ``MODEL.md`` lists, written as scalar
arithmetic on the components of the paper's vectors with the zeros of the
constant matrices ``a1 ... a6`` exploited. Only ``+ - * /`` and a ``sqrt``
passed in are used, so the same code runs on Python floats (one control tick,
``math.sqrt``) and on numpy arrays of N samples (a whole trajectory,
``numpy.sqrt``) and gives the same numbers.

Conventions. Each leg is evaluated in its own coordinates: leg A sees the
platform centre as ``(x, y, z)``, leg B as ``(y, z, x)`` and leg C as
``(z, x, y)`` (``b10 = a1 P``, ``c10 = a1 P^2`` with ``P`` the cyclic
permutation), so one leg function serves all three. Inside a leg, a vector
with the index ``k`` is expressed in the frame of body ``k``; ``c1, s1`` are
``cos, sin(phi21)`` and ``c2, s2`` are ``cos, sin(phi32)``; ``w1, w2`` and
``e1, e2`` the relative rates ``omega21 = omega54``, ``omega32 = omega43 =
omega62`` and their derivatives. The slider's rate and acceleration are
``lambdadot`` and ``lambdaddot``.

The kernel does not validate: callers (``mechanics``) check that the inputs
are finite and reachable before calling it, and check the conditioning and
the finiteness of what it returns.
"""

from collections import namedtuple
from math import sin

# Constants of the kernel derived once from a Robot (see kernel_constants).
KernelConstants = namedtuple('KernelConstants', (
    'l3', 'minus_inv_l3', 'h3', 'i3', 'm1', 'm2', 'm3', 'm4', 'm5', 'm6',
    'h4', 'p5', 'q5', 'gx', 'gy', 'gz'))


def kernel_constants(robot):
    """Pack the robot's values the kernel uses (lengths m, masses kg).

    ``h3 = l3 / 2`` and ``i3 = l3^2 / 3`` give body 3's centre of mass on
    its -y3 axis and its inertia per unit mass about A3; ``h4 = l2 / 2`` is
    body 4's centre of mass on its x4 axis;
    ``(p5, q5, 0) = (l1 sin(alpha), -l / 2, 0)`` is ``r5G``, the platform's
    centre G seen from A5 in frame 5 (eq. 8).
    """
    gx, gy, gz = robot.gravity
    return KernelConstants(
        robot.l3, -1.0 / robot.l3, robot.l3 / 2.0, robot.l3 ** 2 / 3.0,
        robot.m1, robot.m2, robot.m3, robot.m4, robot.m5,
        robot.m6, robot.l2 / 2.0, robot.l1 * sin(robot.alpha),
        -robot.l / 2.0, gx, gy, gz)


def solve(k, x, y, z, vx, vy, vz, ax, ay, az, sqrt, record=None):
    """Inverse kinematics and dynamics of the whole robot (eqs. 9-25).

    Takes the platform centre G (m), its velocity (m/s) and acceleration
    (m/s^2) in frame 0, as floats or as equal-shaped arrays. Returns
    ``(lam, lamd, lamdd, force, power, alphas, jac_inverse_condition)``:
    three 3-tuples for the actuators' displacement (m), rate (m/s) and
    acceleration (m/s^2), the actuator forces (N) and powers (W), the
    ``alpha_i`` of eq. (17) (m) and ``1 / kappa_F(J_lambda)``.

    The forces follow eq. (25) for the three unit virtual motions at once:
    each leg contributes the virtual work of its sliders' force
    ``u3^T f_1`` times ``v10^v`` and of its accumulated joint moments times
    the relative virtual rates, which are linear in the platform's virtual
    velocity ``delta r``. Summing a leg's joint terms into a generalised
    force ``Q_leg`` on ``delta r`` and using ``delta r = J_lambda^-1 e_j``
    gives ``f = F1 + J_lambda^-T sum(Q_leg)``.

    ``record``, if a dict, receives the per-element quantities of every leg
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


def jacobian_cofactors(x, y, z, al_a, al_b, al_c, sqrt):
    """Cofactors and determinant of ``J_lambda = J1^-1 J2`` (eqs. 15-17).

    ``J_lambda = [[1, y/al_a, z/al_a], [x/al_b, 1, z/al_b], [x/al_c,
    y/al_c, 1]]`` maps the platform velocity to ``lambdadot``; its inverse
    transpose is ``cof / det``. Returns ``(cof, det, inverse_condition)``
    with ``cof`` the 9 cofactors row by row and ``inverse_condition =
    3 |det| / (|J|_F |cof|_F) = 1 / kappa_F``, the normalised inverse
    Frobenius condition number: 1 at home, 0 where J2 is singular.
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
    return cof, det, 3.0 * abs(det) / sqrt(jj * cc)


def _leg(k, x, y, z, vx, vy, vz, ax, ay, az, gx, gy, gz, platform, sqrt,
         record):
    """One leg in its own coordinates: kinematics and its virtual work.

    Returns ``(lambda, lambdadot, lambdaddot, alpha_i, F1, Qy, Qz)``: the
    slider's force term ``u3^T f_1`` of eq. (25) and the generalised force
    ``(0, Qy, Qz)`` that the leg's joint moments put on the platform's
    virtual velocity (leg coordinates). ``platform`` says whether the
    platform (body 5) belongs to this leg's tree (leg A only).
    """
    l3 = k.l3
    # Inverse geometry, eq. (9); alpha_i = l3 cos(phi21) cos(phi32), eq. (17).
    s2 = z * k.minus_inv_l3
    c2 = sqrt(1.0 - s2 * s2)
    r2 = 1.0 / (l3 * c2)
    s1 = y * r2
    c1 = sqrt(1.0 - s1 * s1)
    al = l3 * c1 * c2
    ra = 1.0 / al
    lam = x + l3 - al

    # Connectivity conditions (13), derived from (7)-(8) and solved:
    # v10 a10^T u3 - l3 w1 a20^T u3~ a32^T u2 - l3 w2 a30^T u3~ u2 = rdot_G.
    w2 = -vz * r2
    l3s1 = l3 * s1
    l3c1 = l3 * c1
    w1 = (vy + l3s1 * s2 * w2) * ra
    lamd = vx + l3s1 * c2 * w1 + l3c1 * s2 * w2
    # Their time derivative, eq. (18) with the signs of r43 = -l3 u2.
    ww = w1 * w1 + w2 * w2
    w12 = 2.0 * w1 * w2
    e2 = (l3 * s2 * w2 * w2 - az) * r2
    e1 = (ay + l3s1 * (s2 * e2 + c2 * ww) + l3c1 * s2 * w12) * ra
    a = ax + l3s1 * (c2 * e1 - s2 * w12) + l3c1 * (s2 * e2 + c2 * ww)

    # Recursion (10)-(12), (19), body by body (frames k). Body 1 translates:
    # gamma10 = a u3. Body 2: omega20 = w1 u3, epsilon20 = e1 u3,
    # gamma20 = a21 gamma10.
    g20x = c1 * a
    g20y = -s1 * a
    # Body 3 (and its twin 6: a62 = a32, r62 parallel to omega20):
    # omega30 = a32 omega20 + w2 u3, epsilon30 from (19), gamma30 = a32
    # gamma20 (r32 is parallel to omega20 and epsilon20).
    o3x = -c2 * w1
    o3y = s2 * w1
    o3z = w2
    e3x = -c2 * e1 + s2 * w1 * w2
    e3y = s2 * e1 + c2 * w1 * w2
    e3z = e2
    g30x = -s2 * g20x
    g30y = -c2 * g20x
    g30z = g20y
    # (omega30~ omega30~ + epsilon30~) r43 with r43 = -l3 u2.
    t3x = l3 * (e3z - o3x * o3y)
    t3y = l3 * (o3x * o3x + o3z * o3z)
    t3z = -l3 * (e3x + o3y * o3z)
    # Body 4: omega40 = w1 u1 and epsilon40 = e1 u1 (parallel to body 2),
    # gamma40 = a43 (gamma30 + t3).
    bx = g30x + t3x
    by = g30y + t3y
    g40x = -c2 * bx + s2 * by
    g40y = s2 * bx + c2 * by
    g40z = -(g30z + t3z)

    # Gravity in frames 2, 3, 4 (g_k = a_k0 g), 1 (z only) and 5.
    hg = c1 * gx + s1 * gy
    kg = c1 * gy - s1 * gx
    g3x = -c2 * gz - s2 * hg
    g3y = s2 * gz - c2 * hg

    # Wrenches (20)-(24) per unit mass, about each body's joint A_k:
    # f = a_C - g, m = r_C~ (gamma - g) + I_A epsilon + omega~ I_A omega.
    # Body 3: r_C = r43 / 2, I_A = l3^2/3 diag(1, 0, 1) (parallel axis).
    d3x = g30x - g3x
    d3z = g30z - kg
    f3x = d3x + 0.5 * t3x
    f3y = g30y - g3y + 0.5 * t3y
    f3z = d3z + 0.5 * t3z
    h3 = k.h3
    i3 = k.i3
    n3x = -h3 * d3z + i3 * (e3x + o3y * o3z)
    n3z = h3 * d3x + i3 * (e3z - o3x * o3y)
    # Body 4: r_C = h4 u1 parallel to omega40, epsilon40: no rotary terms.
    m4 = k.m4
    h4 = k.h4
    d4x = g40x - gz
    d4y = g40y + hg
    d4z = g40z + kg
    f4x = m4 * d4x
    f4y = m4 * d4y
    f4z = m4 * d4z
    n4x = 0.0
    n4y = -m4 * h4 * d4z
    n4z = m4 * h4 * d4y
    t21 = 0.0
    if platform:
        # Body 5, the platform, in leg A's tree: it translates, r_C = r5G.
        # gamma50 = a54 gamma40 (r54 parallel to omega40, epsilon40).
        m5 = k.m5
        p5 = k.p5
        q5 = k.q5
        d5x = c1 * g40z + s1 * g40y + gy
        d5y = c1 * g40y - s1 * g40z + gx
        d5z = -g40x + gz
        n5x = m5 * q5 * d5z
        n5y = -m5 * p5 * d5z
        n5z = m5 * (p5 * d5y - q5 * d5x)
        # Accumulate into body 4 (23): a54^T f5, a54^T m5, r54~ a54^T f5.
        u0 = -m5 * d5z
        u1 = m5 * (s1 * d5x + c1 * d5y)
        u2 = m5 * (c1 * d5x - s1 * d5y)
        f4x += u0
        f4y += u1
        f4z += u2
        n4x += -n5z
        n4y += s1 * n5x + c1 * n5y - h4 * u2
        n4z += c1 * n5x - s1 * n5y + h4 * u1
        t21 = n5z
    # Accumulate body 4 into body 3 (23): a43^T f4, a43^T m4, r43~ a43^T f4.
    m3 = k.m3
    u0 = s2 * f4y - c2 * f4x
    u2 = -f4z
    f3ax = m3 * f3x + u0
    f3ay = m3 * f3y + s2 * f4x + c2 * f4y
    f3az = m3 * f3z + u2
    n3ax = m3 * n3x + s2 * n4y - c2 * n4x - l3 * u2
    n3ay = s2 * n4x + c2 * n4y
    n3az = m3 * n3z - n4z + l3 * u0
    # Body 6 (a leaf: the parallelogram is cut at A7) has body 3's motion.
    m6 = k.m6
    # Accumulate bodies 3 and 6 into body 2 (23): a32^T (f3 + f6), moments.
    ux = f3ax + m6 * f3x
    uy = f3ay + m6 * f3y
    uz = f3az + m6 * f3z
    nx = n3ax + m6 * n3x
    t21 = t21 + s2 * n3ay - c2 * nx
    t32 = n3az + n4z + m6 * n3z
    m2 = k.m2
    f2x = m2 * (g20x - hg) - s2 * ux - c2 * uy
    f2y = m2 * (g20y - kg) + uz
    # Body 1 (23): u3^T (f10 + a21^T f2), with g1 = a10 g = (-gz, gy, gx).
    f1 = k.m1 * (a - gx) + c1 * f2x - s1 * f2y

    # Virtual rates of the leg for a platform virtual velocity delta r,
    # from (13): w2 = -dz / (l3 c2), w1 = (dy - s1 s2 dz / c2) / alpha_i.
    qy = t21 * ra
    qz = -(t32 * c1 + t21 * s1 * s2 / c2) * ra

    if record is not None:
        _record_leg(record, l3, s1, c1, s2, c2, lam, lamd, a, w1, w2, e1,
                    e2, (o3x, o3y, o3z), (e3x, e3y, e3z),
                    (g30x, g30y, g30z), (g40x, g40y, g40z))
    return lam, lamd, a, al, f1, qy, qz


def _record_leg(record, l3, s1, c1, s2, c2, lam, lamd, lamdd, w1, w2, e1,
                e2, o3, e3, g30, g40):
    """Store one leg's per-element quantities (frames k) in ``record``.

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
           6: v30, 4: v40, 5: _a54(s1, c1, v40)},
        gamma={1: (zero, zero, lamdd),
               2: (c1 * lamdd, -s1 * lamdd, zero), 3: g30, 6: g30, 4: g40,
               5: _a54(s1, c1, g40)})


def _a54(s1, c1, u):
    """Apply ``a54 = a^phi21 a2`` (eq. 1) to a vector of frame 4."""
    return (c1 * u[2] + s1 * u[1], c1 * u[1] - s1 * u[2], -u[0])
