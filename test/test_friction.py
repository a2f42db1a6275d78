"""
Friction on the sliders: part of the actuator forces, a resistance in the plant.

The paper neglects friction; the package adds, per actuator, the law of
doc/model.md, written here again: ``f_j = c_j v + (F_j if v > 0 else
F_j^-) tanh(v / v_s) + S_j exp(-(v / v_b)^2) tanh(v / v_s)``, ``v =
lambdadot_j`` (``robot.friction_viscous``, ``friction_coulomb``,
``friction_coulomb_negative``, ``friction_stribeck``,
``friction_velocity``, ``friction_stribeck_velocity``). Checked, for a
plain law (viscous + Coulomb the same both ways) and a general one:

- ``solve``: the forces of a robot with friction are those of the same
  robot without it plus the law, and the power is ``lambdadot`` times the
  total force; ``solve_batch``'s, on both sides of its chunks, are the
  independent Lagrange model's rigid forces plus the law;
- without friction (the default) nothing changes, bit for bit; viscous
  and Coulomb friction the same both ways are ``c v + F tanh(v / v_s)``;
- the friction dissipates (``sum f_j lambdadot_j >= 0``), vanishes at rest;
  the plain law is odd in ``lambdadot``, the general one takes each
  direction's Coulomb level and adds the Stribeck excess at low speed;
- ``forward_dynamics`` still inverts ``solve``, and the plant feels the
  friction as a resistance: under forces ``f`` it moves as the robot
  without friction under ``f - friction(lambdadot)``.
"""

import math

from mechanics_reference import (lagrange_forces, lambda_jacobian,
                                 OTHER_ROBOT_VALUES)
import numpy as np
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
import pytest

# Unequal per actuator, so that a mix-up of actuators shows.
FRICTION = {'friction_viscous': (40.0, 25.0, 60.0),
            'friction_coulomb': (6.0, 9.0, 3.5), 'friction_velocity': 0.02}
GENERAL = FRICTION | {'friction_coulomb_negative': (2.0, 9.5, 7.0),
                      'friction_stribeck': (3.0, 0.0, 5.0),
                      'friction_stribeck_velocity': 0.05}
LAWS = {'plain': FRICTION, 'general': GENERAL}
ROUNDING = 1e-14
# The independent Lagrange model's agreement with the rigid forces (N),
# as test_lagrange.py's drives and payload: its finite difference of dM/dq
# at these slow speeds, and rounding.
LAGRANGE = 1e-8
ROBOTS = {'paper': {}, 'other': OTHER_ROBOT_VALUES}


def law(robot, lambdadot):
    """Return the friction law of the module docstring (N) per actuator."""
    forces = []
    for j, v in enumerate(lambdadot):
        coulomb = (robot.friction_coulomb if v > 0
                   else robot.friction_coulomb_negative)[j]
        stribeck = robot.friction_stribeck[j] * math.exp(
            -(v / robot.friction_stribeck_velocity) ** 2)
        forces.append(robot.friction_viscous[j] * v + (coulomb + stribeck)
                      * math.tanh(v / robot.friction_velocity))
    return np.array(forces)


def random_states(seed, n, speed=1.0):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.3, 0.3, (n, 3)),
            rng.uniform(-speed, speed, (n, 3)),
            rng.uniform(-20.0, 20.0, (n, 3)))


@pytest.mark.parametrize('law_name', sorted(LAWS))
@pytest.mark.parametrize('robot_name', sorted(ROBOTS))
def test_forces_are_the_rigid_ones_plus_the_friction_law(robot_name,
                                                         law_name):
    rigid = Robot(**ROBOTS[robot_name])
    robot = rigid.replace(**LAWS[law_name])
    # Slow rates too: the Coulomb term's smooth part (|lambdadot| ~ v_s).
    for speed in (1.0, 0.03):
        for p, v, a in zip(*random_states(1, 200, speed)):
            with_friction = mechanics.solve(robot, p, v, a)
            without = mechanics.solve(rigid, p, v, a)
            assert with_friction.lambdadot == without.lambdadot
            expected = np.add(without.force, law(robot, without.lambdadot))
            scale = np.abs(expected).max()
            assert np.abs(np.subtract(with_friction.force, expected)).max() \
                <= ROUNDING * scale
            assert with_friction.power == tuple(
                d * f for d, f in zip(with_friction.lambdadot,
                                      with_friction.force))


@pytest.mark.parametrize('law_name', sorted(LAWS))
def test_batch_forces_are_the_lagrange_ones_plus_the_law(law_name):
    """Across the batch's chunks: the independent model plus the law."""
    rigid = Robot(**OTHER_ROBOT_VALUES)
    robot = rigid.replace(**LAWS[law_name])
    n = mechanics.BATCH_CHUNK + 11
    p, v, a = random_states(2, n, 0.1)
    batch = mechanics.solve_batch(robot, p, v, a)
    chunk = mechanics.BATCH_CHUNK
    rows = sorted({0, 1, chunk - 1, chunk, chunk + 1, n - 1}
                  | set(np.random.default_rng(9).integers(0, n, 10).tolist()))
    for i in rows:
        lambdadot = lambda_jacobian(rigid, p[i]) @ v[i]
        expected = lagrange_forces(rigid, p[i], v[i], a[i]).force \
            + law(robot, lambdadot)
        assert np.abs(batch.lambdadot[i] - lambdadot).max() <= 1e-12, i
        assert np.abs(batch.force[i] - expected).max() <= LAGRANGE, i
    assert np.array_equal(batch.power, batch.lambdadot * batch.force)


def test_no_friction_changes_nothing():
    p, v, a = random_states(3, 50)
    explicit = Robot(friction_viscous=(0.0,) * 3,
                     friction_coulomb=[0.0] * 3, friction_velocity=0.5)
    assert not explicit.has_friction
    for state in zip(p, v, a):
        assert mechanics.solve(explicit, *state) == mechanics.solve(
            Robot(), *state)
    batch = mechanics.solve_batch(explicit, p, v, a)
    reference = mechanics.solve_batch(Robot(), p, v, a)
    for got, want in zip(batch, reference):
        assert np.array_equal(got, want)


def test_viscous_and_symmetric_coulomb_are_c_v_plus_f_tanh():
    """The law without its other terms, written here: c v + F tanh(v / v_s)."""
    robot = Robot(**FRICTION)
    rigid = Robot()
    v_s = robot.friction_velocity
    p, v, a = random_states(8, 100, 0.05)
    for state in zip(p, v, a):
        got = mechanics.solve(robot, *state)
        without = mechanics.solve(rigid, *state)
        expected = [f + c * d + F * math.tanh(d / v_s) for f, c, F, d in zip(
            without.force, robot.friction_viscous, robot.friction_coulomb,
            without.lambdadot)]
        assert np.abs(np.subtract(got.force, expected)).max() \
            <= ROUNDING * np.abs(expected).max()
    batch = mechanics.solve_batch(robot, p, v, a)
    without = mechanics.solve_batch(rigid, p, v, a)
    d = without.lambdadot
    expected = without.force + np.array(robot.friction_viscous) * d \
        + np.array(robot.friction_coulomb) * np.tanh(d / v_s)
    assert np.abs(batch.force - expected).max() \
        <= ROUNDING * np.abs(expected).max()


def test_each_direction_has_its_coulomb_level_and_stribeck_fades():
    robot = Robot(**GENERAL)
    fast = 1.0     # m/s: tanh = 1, the Stribeck excess exp(-400) = 0
    assert mechanics.friction_force(robot, (fast, fast, fast)) == \
        pytest.approx((40.0 + 6.0, 25.0 + 9.0, 60.0 + 3.5), rel=1e-15)
    assert mechanics.friction_force(robot, (-fast, -fast, -fast)) == \
        pytest.approx((-40.0 - 2.0, -25.0 - 9.5, -60.0 - 7.0), rel=1e-15)
    # At the Stribeck velocity the excess is exp(-1) of itself.
    v = robot.friction_stribeck_velocity
    got = mechanics.friction_force(robot.replace(
        friction_viscous=(0.0,) * 3), (v, v, v))
    t = math.tanh(v / robot.friction_velocity)
    assert got == pytest.approx(((6.0 + 3.0 / math.e) * t, 9.0 * t,
                                 (3.5 + 5.0 / math.e) * t), rel=1e-14)


@pytest.mark.parametrize('law_name', sorted(LAWS))
def test_friction_dissipates_and_vanishes_at_rest(law_name):
    robot = Robot(**LAWS[law_name])
    rng = np.random.default_rng(4)
    speeds = rng.uniform(-0.5, 0.5, (500, 3))
    friction = mechanics.friction_force(robot, speeds)
    assert friction.shape == (500, 3)
    assert (friction * speeds >= 0.0).all()
    assert mechanics.friction_force(robot, (0.0, 0.0, 0.0)) == (0.0,) * 3
    assert np.abs(friction - np.array([law(robot, s) for s in speeds])) \
        .max() <= ROUNDING * np.abs(friction).max()


def test_the_plain_law_is_odd():
    robot = Robot(**FRICTION)
    rng = np.random.default_rng(4)
    speeds = rng.uniform(-0.5, 0.5, (500, 3))
    friction = mechanics.friction_force(robot, speeds)
    assert np.array_equal(mechanics.friction_force(robot, -speeds),
                          -friction)
    single = mechanics.friction_force(robot, tuple(speeds[0]))
    assert isinstance(single, tuple)
    assert np.abs(np.subtract(single, law(robot, speeds[0]))).max() \
        <= ROUNDING * np.abs(single).max()
    # Far beyond v_s the Coulomb part is the full F_j, of the speed's sign.
    fast = mechanics.friction_force(robot, (1.0, -1.0, 1.0))
    assert fast == pytest.approx((40.0 + 6.0, -25.0 - 9.0, 60.0 + 3.5),
                                 rel=1e-15)


@pytest.mark.parametrize('law_name', sorted(LAWS))
@pytest.mark.parametrize('robot_name', sorted(ROBOTS))
def test_forward_dynamics_inverts_solve_with_friction(robot_name, law_name):
    robot = Robot(**ROBOTS[robot_name], **LAWS[law_name])
    for p, v, a in zip(*random_states(5, 100)):
        force = mechanics.solve(robot, p, v, a).force
        got = mechanics.forward_dynamics(robot, p, v, force)
        assert np.abs(np.subtract(got, a)).max() <= 1e-10 * (
            1.0 + np.abs(a).max())
    p, v, a = random_states(6, 40)
    forces = mechanics.solve_batch(robot, p, v, a).force
    got = mechanics.forward_dynamics_batch(robot, p, v, forces)
    assert np.abs(got - a).max() <= 1e-10 * (1.0 + np.abs(a).max())


@pytest.mark.parametrize('law_name', sorted(LAWS))
def test_the_plant_feels_friction_as_a_resistance(law_name):
    """Under forces f it moves as the frictionless robot under f - friction."""
    rigid = Robot(**OTHER_ROBOT_VALUES)
    robot = rigid.replace(**LAWS[law_name])
    p, v, f = random_states(7, 100)
    f *= 10.0
    for position, velocity, force in zip(p, v, f):
        lambdadot = mechanics.solve(rigid, position, velocity).lambdadot
        got = mechanics.forward_dynamics(robot, position, velocity, force)
        expected = mechanics.forward_dynamics(
            rigid, position, velocity, force - law(robot, lambdadot))
        assert np.abs(np.subtract(got, expected)).max() <= 1e-10 * (
            1.0 + np.abs(expected).max())
    batch = mechanics.forward_dynamics_batch(robot, p, v, f)
    lambdadot = mechanics.solve_batch(rigid, p, v).lambdadot
    expected = mechanics.forward_dynamics_batch(
        rigid, p, v, f - mechanics.friction_force(robot, lambdadot))
    assert np.abs(batch - expected).max() <= 1e-10 * np.abs(expected).max()
