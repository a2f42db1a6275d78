"""
The paper's example (section 2): the trajectory of eq. (6) on its robot.

At t = 0 and t = 2 s the actuator displacements must equal eq. (9)
evaluated here independently with ``math``; the forces must be finite
along the whole trajectory; at t = 0 the platform is at rest at home, so
the forces are the hand statics of ``test_statics`` plus the hand inertia
of the home mass matrix: eq. (6) starts from rest but not from zero
acceleration, ``rddot_G(0) = r* (pi/3)^2``.
"""

import math

import numpy as np
from orthoglide_ros.model.mechanics import solve, solve_batch
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.trajectory import (
    paper_batch, paper_sample, paper_times)
import pytest

TARGET = (0.05, 0.10, -0.20)        # r* of the paper (m)


def eq9(robot, position):
    """Eq. (9) for the three legs, with math only."""
    x, y, z = position
    lam = []
    for a, b, c in ((x, y, z), (y, z, x), (z, x, y)):
        phi32 = math.asin(-c / robot.l3)
        phi21 = math.asin(b / (robot.l3 * math.cos(phi32)))
        lam.append(a + robot.l3 * (1.0 - math.cos(phi21) * math.cos(phi32)))
    return lam


def test_trajectory_samples_follow_eq6():
    omega = math.pi / 3
    for t in (0.0, 0.7, 2.0):
        position, velocity, acceleration = paper_sample(t)
        for j in range(3):
            r = TARGET[j]
            assert position[j] == pytest.approx(
                r * (1 - math.cos(omega * t)), abs=1e-15)
            assert velocity[j] == pytest.approx(
                r * omega * math.sin(omega * t), abs=1e-15)
            assert acceleration[j] == pytest.approx(
                r * omega ** 2 * math.cos(omega * t), abs=1e-15)
    # 1 - cos(2 pi / 3) = 3/2.
    assert np.allclose(paper_sample(2.0)[0], (0.075, 0.15, -0.30),
                       atol=1e-15)


@pytest.mark.parametrize('t', [0.0, 2.0])
def test_lambda_at_the_ends_is_eq9(t):
    robot = Robot()
    position = [r * (1.0 - math.cos(math.pi * t / 3.0)) for r in TARGET]
    s = solve(robot, *paper_sample(t))
    assert np.abs(np.array(s.lambda_) - eq9(robot, position)).max() <= 1e-12


def test_lambda_at_the_end_has_the_expected_size():
    """
    Check lambda at t = 2 s against eq. (9) worked by hand.

    lambda_A = 0.075 + 0.85 (1 - sqrt(1 - (0.15^2 + 0.3^2) / 0.85^2)), a
    few centimetres; the B and C legs likewise.
    """
    s = solve(Robot(), *paper_sample(2.0))
    expected = [0.075 + 0.85 * (1 - math.sqrt(1 - 0.1125 / 0.7225)),
                0.15 + 0.85 * (1 - math.sqrt(1 - 0.095625 / 0.7225)),
                -0.30 + 0.85 * (1 - math.sqrt(1 - 0.028125 / 0.7225))]
    assert np.abs(np.array(s.lambda_) - expected).max() <= 1e-12


def test_forces_are_finite_along_the_trajectory():
    robot = Robot()
    times = paper_times(2001)
    s = solve_batch(robot, *paper_batch(times))
    for value in s:
        assert np.isfinite(value).all()
    # Dominated by the weight (about 256 N on C), a few N of inertia.
    assert np.abs(s.force[:, 2] - 256.5).max() < 30.0
    assert np.abs(s.power - s.lambdadot * s.force).max() == 0.0


def test_forces_at_t0_are_hand_statics_plus_hand_inertia():
    robot = Robot()
    position, velocity, acceleration = paper_sample(0.0)
    assert position == (0.0, 0.0, 0.0) and velocity == (0.0, 0.0, 0.0)
    static_mass = 15.0 + 0.35 + 0.2 + 2.0 * (2.5 + 2.5) + 3.0 * 0.2
    dynamic_mass = 15.0 + 0.35 + 0.2 + 5.0 / 3.0 * (2.5 + 2.5) + 3.0 * 0.2
    expected = (dynamic_mass * np.array(TARGET) * (math.pi / 3) ** 2
                - static_mass * np.array([0.0, 0.0, -9.81]))
    force = np.array(solve(robot, position, velocity, acceleration).force)
    assert np.abs(force - expected).max() <= 1e-12 * 256.5
    # Without the initial acceleration: exactly the statics.
    force = np.array(solve(robot, position).force)
    assert np.abs(force - [0.0, 0.0, 9.81 * static_mass]).max() \
        <= 1e-12 * 256.5
