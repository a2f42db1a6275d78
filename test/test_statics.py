"""
Invariant 6 (statics): at rest at home the forces are the hand statics.

The hand argument (virtual work). At rest, ``f . d(lambda) = dV`` for every
virtual motion, with ``V = -sum m g . r_C``. At home (r_G = 0) eq. (9)
gives all angles zero and ``J_lambda = I`` (eq. 16 with x = y = z = 0 and
alpha_i = l3), so the virtual motion ``d lambda = e_j`` moves the platform
by ``d r_G = e_j``, along actuator j's axis (+x0, +y0, +z0 for A, B, C).
Follow each body's centre of mass for ``d r_G = e_C = +z0``:

- Leg C, whose slider moves by 1: eq. (13) gives its angular rates
  ``omega32 = -(local z rate) / (l3 cos phi32) = 0`` and ``omega21 = 0``,
  so the whole leg translates by 1 along z0: m1 + m2 + m3 + m4 + m6.
- Legs A and B, whose sliders stay (``d lambda = 0``): A1, A2 are fixed;
  body 2 turns only about its own axis z2, which carries A3 and A6, so A3
  and A6 are fixed. Body 4 turns only about its own axis (x4) and the
  platform translates, so A4 and A7 move as G does, by 1 along z0. The
  bars A3A4 and A6A7 therefore pivot about a fixed end and their centres
  (midpoints) move by 1/2 along z0; body 4's centre (A5) moves by 1:
  per leg m3/2 + m6/2 + m4.
- The platform, counted once, moves by 1: m5.

So ``f_C = |g| (m5 + m1 + m2 + 2 (m3 + m6) + 3 m4)`` for g = (0, 0, -|g|),
and for ``d r_G = e_A`` or ``e_B`` (horizontal) no centre of mass moves
vertically to first order, so ``f_A = f_B = 0``. Gravity along x0 or y0
is the same problem turned, and by linearity for any gravity vector
``f = -M_static g`` with ``M_static`` the bracket above.

The same displacements give the home mass matrix. The velocities of the
centres are those displacements; a bar pivoting about its end at
1/l3 rad/s adds ``(m l3^2/12) / l3^2 = m/12`` to the ``m/4`` of its centre,
``m/3`` in all; bodies 2 and 4 spin about their own axis (no inertia); the
two bars of a leg turned by different platform directions pivot about
perpendicular axes, both across the bar, so there are no cross terms:
``M(0) = M_dyn I`` with ``M_dyn = m5 + m1 + m2 + 5/3 (m3 + m6) + 3 m4``
and, at rest at home, ``f = M_dyn rddot_G - M_static g``.
"""

from mechanics_reference import mass_matrix
import numpy as np
from orthoglide_ros.model.mechanics import solve, solve_batch
from orthoglide_ros.model.robot import Robot
import pytest

HOME = (0.0, 0.0, 0.0)
ROUNDING = 1e-12
# Masses unlike each other, so that each coefficient is checked.
DISTINCT_MASSES = {'m1': 0.7, 'm2': 0.45, 'm3': 1.3, 'm4': 0.9, 'm5': 11.0,
                   'm6': 2.2}


def static_mass(robot):
    """Return the bracket of the hand statics argument (kg)."""
    return (robot.m5 + robot.m1 + robot.m2 + 2.0 * (robot.m3 + robot.m6)
            + 3.0 * robot.m4)


def dynamic_mass(robot):
    """Return the home mass matrix M(0) / I of the hand argument (kg)."""
    return (robot.m5 + robot.m1 + robot.m2
            + 5.0 / 3.0 * (robot.m3 + robot.m6) + 3.0 * robot.m4)


def test_paper_robot_holds_its_weight_on_actuator_c():
    robot = Robot()
    s = solve(robot, HOME)
    expected = 9.81 * (15.0 + 0.35 + 0.2 + 2.0 * (2.5 + 2.5) + 3.0 * 0.2)
    assert abs(s.force[0]) <= ROUNDING * expected
    assert abs(s.force[1]) <= ROUNDING * expected
    assert abs(s.force[2] - expected) <= ROUNDING * expected
    assert s.power == (0.0, 0.0, 0.0)


@pytest.mark.parametrize('gravity', [
    (0.0, 0.0, -9.81), (-9.81, 0.0, 0.0), (0.0, -9.81, 0.0),
    (9.81, 0.0, 0.0), (1.5, -2.5, 7.0)])
@pytest.mark.parametrize('masses', ['paper', 'distinct'])
def test_forces_at_rest_at_home_are_the_hand_statics(gravity, masses):
    values = DISTINCT_MASSES if masses == 'distinct' else {}
    robot = Robot(**values, gravity=gravity)
    force = np.array(solve(robot, HOME).force)
    expected = -static_mass(robot) * np.array(gravity)
    scale = static_mass(robot) * np.abs(gravity).max()
    assert np.abs(force - expected).max() <= ROUNDING * scale


def test_each_mass_enters_the_statics_with_its_coefficient():
    """Perturbing one mass at a time changes f_C by |g| times its factor."""
    robot = Robot(**DISTINCT_MASSES)
    base = solve(robot, HOME).force[2]
    factors = {'m1': 1.0, 'm2': 1.0, 'm3': 2.0, 'm4': 3.0, 'm5': 1.0,
               'm6': 2.0}
    for name, factor in factors.items():
        heavier = robot.replace(**{name: getattr(robot, name) + 1.0})
        change = solve(heavier, HOME).force[2] - base
        assert abs(change - 9.81 * factor) <= 1e-10, name


@pytest.mark.parametrize('masses', ['paper', 'distinct'])
def test_forces_at_rest_at_home_accelerating_are_hand_inertia(masses):
    values = DISTINCT_MASSES if masses == 'distinct' else {}
    robot = Robot(**values, gravity=(0.0, 0.0, -9.81))
    acceleration = np.array([0.7, -1.3, 2.1])
    force = np.array(solve(robot, HOME, HOME, acceleration).force)
    expected = (dynamic_mass(robot) * acceleration
                - static_mass(robot) * np.array(robot.gravity))
    assert np.abs(force - expected).max() <= ROUNDING * np.abs(
        expected).max()
    # The independent model's mass matrix agrees with the hand argument.
    assert np.abs(mass_matrix(robot, HOME)
                  - dynamic_mass(robot) * np.eye(3)).max() \
        <= ROUNDING * dynamic_mass(robot)


def test_no_gravity_no_motion_no_force_anywhere():
    robot = Robot(gravity=(0.0, 0.0, 0.0))
    rng = np.random.default_rng(6)
    positions = rng.uniform(-0.3, 0.3, (200, 3))
    s = solve_batch(robot, positions)
    assert np.abs(s.force).max() <= 1e-12
