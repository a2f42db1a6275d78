"""
Forward dynamics: the platform acceleration from the state and the forces.

``forward_dynamics`` inverts the inverse dynamics at a fixed state: it is
built from ``solve`` (the bias at zero acceleration and ``F = J_lambda^-T
M`` from unit accelerations). Checked here:

- Round trip: ``forward(p, v, solve(p, v, a).force) == a`` on random
  points of the cube |x|, |y|, |z| <= 0.3 m with fast rates (|v| <= 3 m/s
  per axis, |a| <= 30 m/s^2), several gravities and two robots.
- Against the independent Lagrange model of ``mechanics_reference``
  (which shares no code with the package): ``a = M^-1 (J_lambda^T f - C -
  dV/dq)`` for arbitrary forces, not forces made by the inverse dynamics.
- ``forward_dynamics_batch``: the rows on both sides of its chunk
  boundaries and random rows against the Lagrange model too.
- Bad inputs raise ``WorkspaceError`` with the reasons of ``solve``.

Tolerances. Round trip: both directions run the same kernel, whose forces
carry a rounding error of a few eps of the largest term (about a hundred
operations from the inputs to a force, each rounding once). With
``ROUNDING = 1e-14`` (45 eps) of ``|f| + |f(0)| + |F| |a|``, amplified by
``|F^-1|_2`` in the solve, the round-trip bound holds with a wide margin:
the worst measured error is about 1e-15 of max |a|, some 1e-3 of the bound.
Lagrange: the reference's Christoffel terms come from a central difference
of ``M`` (``mechanics_reference.DM_RELATIVE`` of ``|dM/dq| |qd|^2``, derived in
``test_lagrange.py``), and everything else is exact to rounding
(its ``ROUNDING`` of each term); ``M^-1``
amplifies both by ``|M^-1|_2``. At zero velocity there is no difference
quotient and the comparison is to rounding.
"""

import math

from hypothesis import given, settings, strategies as st
from hypothesis_profiles import examples
from mechanics_reference import (
    batch_rows, cube_points, DM_RELATIVE, lagrange_forces, lambda_jacobian,
    mass_matrix, OTHER_ROBOT_VALUES, potential_gradient,
    ROUNDING as REFERENCE_ROUNDING, vectors)
import numpy as np
from orthoglide_ros.model.mechanics import (
    BATCH_CHUNK, forward_dynamics, forward_dynamics_batch, solve,
    WorkspaceError)
from orthoglide_ros.model.robot import Robot
import pytest

ROUNDING = 1e-14
GRAVITIES = {'default': (0.0, 0.0, -9.81), 'zero': (0.0, 0.0, 0.0),
             'oblique': (2.0, -5.0, -7.5)}
ROBOTS = {'paper': {}, 'other': OTHER_ROBOT_VALUES}
L3 = Robot().l3


def make_robot(robot_name, gravity):
    """Return the named robot with the named gravity."""
    return Robot(**ROBOTS[robot_name], gravity=GRAVITIES[gravity])


def actuator_inertia(robot, position):
    """``F = J_lambda^-T M`` (kg) from the reference model."""
    return np.linalg.solve(lambda_jacobian(robot, position).T,
                           mass_matrix(robot, position))


@settings(deadline=None, max_examples=examples(150))
@given(position=cube_points(), velocity=vectors(3.0),
       acceleration=vectors(30.0), gravity=st.sampled_from(sorted(GRAVITIES)),
       robot_name=st.sampled_from(sorted(ROBOTS)))
def test_forward_dynamics_inverts_the_inverse_dynamics(
        position, velocity, acceleration, gravity, robot_name):
    robot = make_robot(robot_name, gravity)
    force = solve(robot, position, velocity, acceleration).force
    got = forward_dynamics(robot, position, velocity, force)
    assert isinstance(got, tuple) and len(got) == 3
    assert all(type(c) is float for c in got)
    bias = solve(robot, position, velocity).force
    inertia = actuator_inertia(robot, position)
    bound = ROUNDING * np.linalg.norm(np.linalg.inv(inertia), 2) * (
        np.abs(force).max() + np.abs(bias).max()
        + np.linalg.norm(inertia, 2) * np.abs(acceleration).max())
    assert np.abs(np.array(got) - acceleration).max() <= bound + 1e-300


def lagrange_acceleration(robot, position, velocity, force):
    """
    Return ``a = M^-1 (J_lambda^T f - C - dV/dq)`` of the reference, and a bound.

    The bound: the reference's error (module docstring) through ``M^-1``.
    """
    ref = lagrange_forces(robot, position, velocity, np.zeros(3))
    generalised = ref.jacobian.T @ force
    # ref.generalised_force at zero acceleration is C + dV/dq.
    expected = np.linalg.solve(ref.mass_matrix,
                               generalised - ref.generalised_force)
    inverse_m = np.linalg.norm(np.linalg.inv(ref.mass_matrix), 2)
    bound = inverse_m * (
        DM_RELATIVE * np.abs(ref.dmass).max() * 9.0 * (velocity @ velocity)
        + REFERENCE_ROUNDING * (np.abs(generalised).max()
                                + np.abs(ref.coriolis).max()
                                + np.abs(ref.gravity).max()))
    return expected, bound + 1e-300


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points(), velocity=vectors(3.0), force=vectors(300.0),
       gravity=st.sampled_from(sorted(GRAVITIES)),
       robot_name=st.sampled_from(sorted(ROBOTS)))
def test_acceleration_equals_lagrange_model(position, velocity, force,
                                            gravity, robot_name):
    """``M a = J_lambda^T f - C - dV/dq`` of the reference, any forces."""
    robot = make_robot(robot_name, gravity)
    got = np.array(forward_dynamics(robot, position, velocity, force))
    expected, bound = lagrange_acceleration(robot, position, velocity, force)
    assert np.abs(got - expected).max() <= bound


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points(), force=vectors(300.0), gravity=vectors(10.0),
       robot_name=st.sampled_from(sorted(ROBOTS)))
def test_acceleration_at_rest_equals_the_exact_reference(
        position, force, gravity, robot_name):
    """No Christoffel term: the reference is exact to rounding here."""
    robot = Robot(**ROBOTS[robot_name], gravity=tuple(gravity))
    got = np.array(forward_dynamics(robot, position, (0.0, 0.0, 0.0),
                                    force))
    mm = mass_matrix(robot, position)
    generalised = lambda_jacobian(robot, position).T @ force
    grad = potential_gradient(robot, position)
    expected = np.linalg.solve(mm, generalised - grad)
    bound = REFERENCE_ROUNDING * np.linalg.norm(np.linalg.inv(mm), 2) * (
        np.abs(generalised).max() + np.abs(grad).max())
    assert np.abs(got - expected).max() <= bound + 1e-300


@pytest.mark.parametrize('robot_name', sorted(ROBOTS))
def test_free_fall_from_home_by_a_hand_argument(robot_name):
    """
    Released at rest at home without forces, the platform falls faster than g.

    Generalised coordinate z, at home, to first order: the platform and the
    whole of leg C (along its slider's axis: its angles do not change) move
    with ``zdot``. In legs A and B the sliders and the rods 2 stay (their
    displacement is of second order) while the bars 3 and 6 turn about
    their slider-side joints at ``zdot / l3``: their centres move at
    ``zdot / 2`` (mass ``m/4`` plus inertia ``m l3^2/12 / l3^2 = m/12``, so
    ``m/3`` seen at z; weight ``m g / 2``) and the rods 4 move with the
    platform. So ``M_zz = m5 + (m1 + m2 + m3 + m4 + m6) + 2 ((m3 + m6)/3 +
    m4)`` against the weight ``g (m5 + m1 + m2 + m3 + m4 + m6 + 2 ((m3 +
    m6)/2 + m4))`` (the hand statics of test_statics.py): the bars fall
    like rods pinned at one end, whose tips accelerate at 1.5 g. With the
    static forces of ``solve`` instead, the acceleration is zero.
    """
    robot = make_robot(robot_name, 'default')
    m1, m2, m3, m4, m5, m6 = (robot.m1, robot.m2, robot.m3, robot.m4,
                              robot.m5, robot.m6)
    leg_c = m1 + m2 + m3 + m4 + m6
    inertia = m5 + leg_c + 2.0 * ((m3 + m6) / 3.0 + m4)
    weight = m5 + leg_c + 2.0 * ((m3 + m6) / 2.0 + m4)
    home = (0.0, 0.0, 0.0)
    fall = forward_dynamics(robot, home, home, home)
    expected = (0.0, 0.0, -9.81 * weight / inertia)
    assert np.abs(np.subtract(fall, expected)).max() <= 1e-13 * 9.81
    assert fall[2] < -9.81
    held = forward_dynamics(robot, home, home, solve(robot, home).force)
    assert np.abs(held).max() <= 1e-13 * 9.81


def random_states(seed, n):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.3, 0.3, (n, 3)), rng.uniform(-3.0, 3.0, (n, 3)),
            rng.uniform(-400.0, 400.0, (n, 3)))


@pytest.mark.parametrize('robot_name', sorted(ROBOTS))
def test_batch_rows_equal_the_lagrange_model_across_chunks(robot_name):
    robot = make_robot(robot_name, 'oblique')
    n = BATCH_CHUNK + 37
    positions, velocities, forces = random_states(21, n)
    batch = forward_dynamics_batch(robot, positions, velocities, forces)
    assert batch.shape == (n, 3)
    for row in batch_rows(n, BATCH_CHUNK, 2):
        expected, bound = lagrange_acceleration(
            robot, positions[row], velocities[row], forces[row])
        assert np.abs(batch[row] - expected).max() <= bound, row


def test_batch_of_one_and_shapes():
    robot = Robot()
    p, v, f = random_states(22, 1)
    got = forward_dynamics_batch(robot, p, v, f)
    assert got.shape == (1, 3)
    expected, bound = lagrange_acceleration(robot, p[0], v[0], f[0])
    assert np.abs(got[0] - expected).max() <= bound
    with pytest.raises(ValueError, match='shape'):
        forward_dynamics_batch(robot, p, v, np.zeros((2, 3)))
    with pytest.raises(ValueError, match='shape'):
        forward_dynamics_batch(robot, p[0], v, f)


GOOD = ((0.05, 0.1, -0.2), (0.1, 0.2, 0.3), (10.0, 20.0, 250.0))
# J2 singular on the diagonal at t = -l3/sqrt(6) (det J_lambda = 0) while
# alpha/l3 = 0.82 (see test_workspace.py); a leg's axis distance near l3.
BAD_INPUTS = {
    'nan_position': ((math.nan, 0.0, 0.0), GOOD[1], GOOD[2], 'non_finite',
                     'position'),
    'inf_velocity': (GOOD[0], (0.0, math.inf, 0.0), GOOD[2], 'non_finite',
                     'velocity'),
    'nan_force': (GOOD[0], GOOD[1], (0.0, 0.0, math.nan), 'non_finite',
                  'force'),
    'inf_force': (GOOD[0], GOOD[1], (math.inf, -math.inf, 0.0),
                  'non_finite', 'force'),
    'unreachable': ((0.0, 0.7, 0.7), GOOD[1], GOOD[2], 'unreachable',
                    'leg A'),
    'near_j1_singularity': ((0.0, 0.6, 0.58), GOOD[1], GOOD[2], 'singular',
                            'J1'),
    'j2_singularity': ((-L3 / math.sqrt(6.0),) * 3, GOOD[1], GOOD[2],
                       'singular', 'singularity'),
    'huge_velocity': (GOOD[0], (1e200, 0.0, 0.0), GOOD[2], 'overflow',
                      'force'),
    'huge_force': (GOOD[0], GOOD[1], (1.7e308, -1.7e308, 1.7e308),
                   'overflow', 'force'),
}


@pytest.mark.parametrize('case', sorted(BAD_INPUTS))
def test_bad_inputs_raise_workspace_error(case):
    position, velocity, force, reason, word = BAD_INPUTS[case]
    robot = Robot()
    with pytest.raises(WorkspaceError, match=word) as single:
        forward_dynamics(robot, position, velocity, force)
    assert single.value.reason == reason
    assert single.value.row is None
    p, v, f = (np.array([GOOD[i]] * 3) for i in range(3))
    p[2], v[2], f[2] = position, velocity, force
    with pytest.raises(WorkspaceError, match=word) as batch:
        forward_dynamics_batch(robot, p, v, f)
    assert batch.value.reason == reason
    assert batch.value.row == 2


def test_the_margin_is_the_one_of_solve():
    robot = Robot()
    position = (0.0, 0.6, 0.58)
    with pytest.raises(WorkspaceError):
        solve(robot, position)
    assert math.isfinite(sum(forward_dynamics(
        robot, position, GOOD[1], GOOD[2], margin=0.01)))
