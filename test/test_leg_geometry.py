"""
Legs as built: the math library against an independent model of them.

A robot whose every leg differs from the drawing (its axis point and
direction, joint offset, bar length and attachment;
doc/model.md#the-machine-as-built) against ``mechanics_reference``, which
shares no code with the package: each leg's sphere, its chain (1)-(8)
turned from the drawing's by scipy's ``Rotation``, the forward kinematics
by scipy's ``least_squares``, Lagrange's equations from complex-step body
Jacobians. Deviations are drawn by hypothesis at a built Orthoglide's size
(0.1-1 mm, 0.05-0.3 deg) and at ten to twenty times more.

Tolerances. Positions and joint readings are a few roundings of lengths
near 1 m: ``GEOMETRY = 1e-12`` m (the drawing's own, test_forward_kinematics),
rates ``RATE = 1e-12`` relative to the Jacobian's size times the speed.
Forces to ``force_tolerance``, the Lagrange model's own error
(test_lagrange.py). The forward dynamics of the reference's forces to what
that error gives: ``|F^-1| force_tolerance`` with ``F = J_lambda^-T M``.
Finite differences (4th order, ``mechanics_reference.derivative``, step
1e-4) carry ``h^4 f^(5) / 30 + 1.5 eps |f| / h``: ``FD = 1e-9``.
"""

from hypothesis import given, settings, strategies as st
from hypothesis_profiles import examples
from mechanics_reference import (
    actuator_displacements, batch_rows, body_jacobians, cube_points,
    derivative, deviations, force_tolerance, lagrange_forces,
    lambda_jacobian, leg_geometry, LEGS, platform_position, rest_forces,
    sphere_residuals, vectors)
import numpy as np
from orthoglide_ros.model import kernel, legs, mechanics
from orthoglide_ros.model.bodies import elements, leg_joints
from orthoglide_ros.model.mechanics import (
    BATCH_CHUNK, forward_dynamics, forward_dynamics_batch,
    forward_kinematics, forward_kinematics_rows, jacobians, payload_force,
    platform_velocity, solve, solve_batch, workspace_status, WorkspaceError)
from orthoglide_ros.model.plant import rk4_step
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.trajectory import paper_sample
from orthoglide_testing.robots_as_built import (
    BUILT as BUILT_VALUES, FAR as FAR_VALUES)
import pytest

GEOMETRY = 1e-12
RATE = 1e-12
FD = 1e-9
GRAVITIES = ((0.0, 0.0, -9.81), (0.0, 0.0, 0.0), (2.0, -5.0, -7.5))
SIZES = ('built', 'large')
BUILT = Robot(**BUILT_VALUES)
FAR = Robot(**FAR_VALUES)


def built_robots():
    """Hypothesis strategy: a Robot as built, deviations of either size."""
    return st.sampled_from(SIZES).flatmap(deviations).map(
        lambda rows: Robot(**rows))


def reference_conditioning(jac):
    """``1 / kappa_F`` of a 3x3 Jacobian, from numpy's inverse."""
    det = np.linalg.det(jac)
    return 3.0 * abs(det) / (np.linalg.norm(jac)
                             * np.linalg.norm(det * np.linalg.inv(jac)))


@settings(deadline=None, max_examples=examples(60))
@given(robot=built_robots(), position=cube_points(), velocity=vectors(3.0))
def test_joint_readings_and_rates_are_each_legs_sphere(robot, position,
                                                       velocity):
    s = solve(robot, position, velocity)
    lam = np.array(s.lambda_)
    assert np.abs(lam - actuator_displacements(robot, position)).max() \
        <= GEOMETRY
    assert np.abs(sphere_residuals(robot, position, lam)).max() <= GEOMETRY
    jac = lambda_jacobian(robot, position)
    assert np.abs(np.array(s.lambdadot) - jac @ velocity).max() <= RATE * (
        np.abs(jac).max() * np.abs(velocity).sum() + 1.0)


@settings(deadline=None, max_examples=examples(30))
@given(robot=built_robots(), position=cube_points(0.25),
       velocity=vectors(2.0), acceleration=vectors(20.0))
def test_joint_accelerations_are_the_derivative_of_the_rates(
        robot, position, velocity, acceleration):
    def rates(t):
        p = position + velocity * t + 0.5 * acceleration * t * t
        return lambda_jacobian(robot, p) @ (velocity + acceleration * t)
    expected = derivative(rates, 0.0, 1e-4)
    lamdd = np.array(solve(robot, position, velocity,
                           acceleration).lambdaddot)
    assert np.abs(lamdd - expected).max() <= FD * (
        1.0 + np.abs(expected).max())


@settings(deadline=None, max_examples=examples(40))
@given(robot=built_robots(), position=cube_points(), velocity=vectors(3.0),
       acceleration=vectors(30.0), gravity=st.sampled_from(GRAVITIES))
def test_forces_equal_the_lagrange_model_of_the_legs_as_built(
        robot, position, velocity, acceleration, gravity):
    robot = robot.replace(gravity=gravity)
    force = np.array(solve(robot, position, velocity, acceleration).force)
    ref = lagrange_forces(robot, position, velocity, acceleration)
    assert np.abs(force - ref.force).max() <= force_tolerance(
        ref, velocity, acceleration)


@settings(deadline=None, max_examples=examples(30))
@given(robot=built_robots(), position=cube_points(),
       acceleration=vectors(30.0), gravity=vectors(10.0))
def test_forces_at_rest_equal_the_exact_reference(robot, position,
                                                  acceleration, gravity):
    """No Christoffel term: the reference is exact to rounding here."""
    robot = robot.replace(gravity=tuple(gravity), armature=(3.2, 1.1, 0.45),
                          payload=5.0)
    force = np.array(solve(robot, position, (0.0, 0.0, 0.0),
                           acceleration).force)
    expected, bound = rest_forces(robot, position, acceleration)
    assert np.abs(force - expected).max() <= bound


def test_the_geometry_moves_the_forces_far_beyond_the_check():
    """The checks above tell a robot as built from the drawing's."""
    rng = np.random.default_rng(40)
    drawing = Robot()
    for _ in range(5):
        state = (rng.uniform(-0.3, 0.3, 3), rng.uniform(-3.0, 3.0, 3),
                 rng.uniform(-30.0, 30.0, 3))
        ref = lagrange_forces(BUILT, *state)
        apart = np.abs(np.array(solve(drawing, *state).force)
                       - ref.force).max()
        assert apart >= 1e3 * force_tolerance(ref, *state[1:])
    # Offsets along the axes move the readings only: the forces are the
    # same function of G (the bars' directions do not change).
    along = Robot(joint_offset=(1e-3, -2e-3, 5e-4),
                  axis_point_b=(0.0, 1e-3, 0.0))
    here = solve(along, *state)
    there = solve(drawing, *state)
    assert np.abs(np.array(here.force) - there.force).max() <= 1e-12 * 300
    assert np.abs(np.array(there.lambda_) - here.lambda_
                  - (1e-3, -1e-3, 5e-4)).max() <= GEOMETRY


@settings(deadline=None, max_examples=examples(60))
@given(robot=built_robots(), position=cube_points())
def test_forward_kinematics_inverts_each_legs_sphere(robot, position):
    lam = solve(robot, position).lambda_
    assert np.abs(forward_kinematics(robot, lam) - position).max() \
        <= GEOMETRY
    independent = actuator_displacements(robot, position)
    assert np.abs(forward_kinematics(robot, independent)
                  - position).max() <= GEOMETRY
    assert np.abs(forward_kinematics(robot, lam) - platform_position(
        robot, lam)).max() <= GEOMETRY


@pytest.mark.parametrize('robot', [BUILT, FAR], ids=['built', 'far'])
def test_forward_kinematics_of_a_batch_over_the_cube(robot):
    rng = np.random.default_rng(41)
    positions = rng.uniform(-0.3, 0.3, (5000, 3))
    lam = solve_batch(robot, positions).lambda_
    assert np.abs(forward_kinematics(robot, lam) - positions).max() \
        <= GEOMETRY
    back, found = forward_kinematics_rows(robot, np.vstack([
        lam[:3], (2.0, 0.0, 0.0), (0.85, 0.85, 0.85)]))
    assert found.tolist() == [True, True, True, False, False]
    with pytest.raises(WorkspaceError) as error:
        forward_kinematics(robot, np.vstack([lam[:2], (0.0, -5.0, 0.0)]))
    assert (error.value.reason, error.value.row) == ('unreachable', 2)


@settings(deadline=None, max_examples=examples(40))
@given(robot=built_robots(), position=cube_points(), velocity=vectors(3.0))
def test_jacobians_are_the_derivatives_of_the_joint_readings(
        robot, position, velocity):
    j1, j2 = jacobians(robot, position)
    j_lambda = np.linalg.solve(j1, j2)
    assert np.abs(j_lambda - lambda_jacobian(robot, position)).max() <= RATE
    assert np.abs(np.diag(j1) - [
        robot.legs[i].length * leg_geometry(robot, leg, position).cos21
        * leg_geometry(robot, leg, position).cos32
        for i, leg in enumerate(LEGS)]).max() <= GEOMETRY
    h = 1e-4
    numeric = np.column_stack([derivative(
        lambda t, k=k: solve(robot, position + t * np.eye(3)[k]).lambda_,
        0.0, h) for k in range(3)])
    assert np.abs(j_lambda - numeric).max() <= FD
    rates = j_lambda @ velocity
    assert np.abs(np.array(platform_velocity(robot, position, rates))
                  - velocity).max() <= RATE * (1.0 + np.abs(velocity).max())


@settings(deadline=None, max_examples=examples(40))
@given(robot=built_robots(), position=cube_points(0.45))
def test_workspace_status_is_each_legs_alpha_and_the_conditioning(
        robot, position):
    status = workspace_status(robot, position)
    ratios = []
    for leg in LEGS:
        with np.errstate(invalid='ignore'):
            g = leg_geometry(robot, leg, position)
        ratios.append(g.cos21 * g.cos32)
    if not np.isfinite(ratios).all():
        assert not status.reachable
        assert status.singularity_distance == 0.0
        return
    assert status.reachable
    assert np.abs(status.alpha_ratio - ratios).max() <= GEOMETRY
    conditioning = reference_conditioning(lambda_jacobian(robot, position))
    assert abs(status.conditioning - conditioning) <= 1e-10
    assert status.singularity_distance == min(status.alpha_ratio.min(),
                                              status.conditioning)
    if status.ok:
        s = solve(robot, position)
        assert np.abs(np.subtract(s.alpha_ratio, status.alpha_ratio)).max() \
            <= 1e-15
        assert abs(s.conditioning - status.conditioning) <= 1e-14


@settings(deadline=None, max_examples=examples(30))
@given(robot=built_robots(), position=cube_points(), velocity=vectors(3.0),
       acceleration=vectors(30.0))
def test_forward_dynamics_gives_back_the_lagrange_models_motion(
        robot, position, velocity, acceleration):
    ref = lagrange_forces(robot, position, velocity, acceleration)
    found = np.array(forward_dynamics(robot, position, velocity, ref.force))
    # F = J_lambda^-T M maps an acceleration error to a force error.
    f_matrix = np.linalg.solve(ref.jacobian.T, ref.mass_matrix)
    bound = np.linalg.norm(np.linalg.inv(f_matrix), 2) * force_tolerance(
        ref, velocity, acceleration) * np.sqrt(3.0)
    assert np.abs(found - acceleration).max() <= bound


@pytest.mark.parametrize('robot', [BUILT, FAR], ids=['built', 'far'])
def test_batches_equal_one_sample_at_a_time_across_chunks(robot):
    rng = np.random.default_rng(42)
    n = BATCH_CHUNK + 50
    p = rng.uniform(-0.3, 0.3, (n, 3))
    v = rng.uniform(-3.0, 3.0, (n, 3))
    a = rng.uniform(-30.0, 30.0, (n, 3))
    batch = solve_batch(robot, p, v, a)
    forces = batch.force + rng.uniform(-50.0, 50.0, (n, 3))
    accelerations = forward_dynamics_batch(robot, p, v, forces)
    joints = leg_joints(robot, p, v)
    for row in batch_rows(n, BATCH_CHUNK, 43):
        one = solve(robot, p[row], v[row], a[row])
        for name, value in one._asdict().items():
            got = getattr(batch, name)[row]
            assert np.abs(got - value).max() <= 1e-12 * (
                1.0 + np.abs(value).max()), (row, name)
        assert np.abs(accelerations[row] - forward_dynamics(
            robot, p[row], v[row], forces[row])).max() <= 1e-10
        single = leg_joints(robot, p[row], v[row])
        for leg in 'ABC':
            assert np.abs(np.array([x[row] for x in joints[leg]])
                          - single[leg]).max() <= 1e-12


def test_every_leg_holds_the_platform_where_its_geometry_puts_it():
    rng = np.random.default_rng(44)
    for robot in (BUILT, FAR):
        for _ in range(5):
            position = rng.uniform(-0.3, 0.3, 3)
            velocity = rng.uniform(-2.0, 2.0, 3)
            legs_now = elements(robot, position, velocity)
            jac = body_jacobians(robot, position)
            for i, leg in enumerate(LEGS):
                el = legs_now[leg]
                ref = leg_geometry(robot, leg, position)
                built = robot.legs[i]
                for name, point in ref.joints.items():
                    assert np.abs(el['joints'][name] - point).max() \
                        <= GEOMETRY, (leg, name)
                # The slider on its axis, at its true position.
                assert np.abs(el['joints']['A1'] - built.point - (
                    el['lambda'] + built.offset - robot.l1 * np.cos(
                        robot.alpha) - built.length - robot.l / 2)
                    * np.array(built.direction)).max() <= GEOMETRY
                for a, b in (('A3', 'A4'), ('A6', 'A7')):
                    assert abs(np.linalg.norm(el['joints'][a]
                                              - el['joints'][b])
                               - built.length) <= GEOMETRY
                for k in (1, 2, 3, 4, 6):
                    body = el['bodies'][k]
                    assert np.abs(body['omega'] - jac.angular[(leg, k)]
                                  @ velocity).max() <= RATE * 10.0, (leg, k)
                    origin = {1: 'A1', 2: 'A2', 3: 'A3', 4: 'A4',
                              6: 'A6'}[k]
                    moving = derivative(lambda t: leg_geometry(
                        robot, leg, position + t * velocity).joints[origin],
                        0.0, 1e-4)
                    assert np.abs(body['velocity'] - moving).max() <= FD
                assert abs(el['phi32'] - np.arctan2(ref.sin32, ref.cos32)) \
                    <= GEOMETRY
                assert abs(el['phi21'] - np.arctan2(ref.sin21, ref.cos21)) \
                    <= GEOMETRY


def test_payload_force_is_the_heavier_platforms_difference():
    rng = np.random.default_rng(45)
    heavier = BUILT.replace(payload=4.0)
    for _ in range(5):
        state = (rng.uniform(-0.3, 0.3, 3), rng.uniform(-2.0, 2.0, 3),
                 rng.uniform(-20.0, 20.0, 3))
        s = solve(BUILT, *state)
        added = payload_force(BUILT, 4.0, s.lambda_, s.lambdadot,
                              s.lambdaddot)
        expected = np.subtract(solve(heavier, *state).force, s.force)
        assert np.abs(np.array(added) - expected).max() <= 1e-9


def test_a_leg_refuses_with_its_own_length():
    robot = Robot(bar_length=(0.85, 0.80, 0.85))
    with pytest.raises(WorkspaceError) as error:
        solve(robot, (0.0, 0.0, 0.82))
    assert error.value.reason == 'unreachable'
    assert str(error.value) == (
        "position [0, 0, 0.82] m is out of reach of leg B: its distance "
        "0.82 m from the leg's axis is not below L_B = 0.8 m")
    # alpha_B / L_B = sqrt(1 - (0.6^2 + 0.5^2) / 0.8^2) = 0.217 < 0.3.
    point = (0.5, -0.3, -0.6)
    with pytest.raises(WorkspaceError) as error:
        solve(robot, point, margin=0.3)
    assert str(error.value) == (
        'position [0.5, -0.3, -0.6] m is too near a singularity of J1: leg B '
        'has alpha/L_B = 0.217 < margin 0.3')
    with pytest.raises(WorkspaceError) as error:
        solve_batch(robot, [(0.0, 0.0, 0.0), point], margin=0.3)
    assert error.value.row == 1 and 'leg B has alpha/L_B' in str(error.value)
    assert solve(robot, point).alpha_ratio[1] == pytest.approx(
        (1.0 - 0.61 / 0.64) ** 0.5, rel=1e-14)


def test_the_general_legs_at_the_drawing_are_the_drawings_closed_forms():
    """The per-leg code (``solve_legs``, trilateration) reduces to today's."""
    rng = np.random.default_rng(46)
    for robot in (Robot(), Robot(l3=0.93, gravity=(2.0, -5.0, -7.5))):
        assert robot.as_drawn
        n = 2000
        columns = (*rng.uniform(-0.3, 0.3, (3, n)),
                   *rng.uniform(-3.0, 3.0, (3, n)),
                   *rng.uniform(-30.0, 30.0, (3, n)))
        drawn = kernel.solve(robot.constants, *columns, np.sqrt)
        built = kernel.solve_legs(robot.leg_constants, *columns, np.sqrt)
        for a, b in zip(drawn, built):
            assert np.abs(np.asarray(a) - b).max() <= 1e-13 * (
                1.0 + np.abs(np.asarray(a)).max())
        positions = np.array(columns[:3]).T
        lam = np.array(drawn[0]).T
        back, found = legs.intersect(robot.legs, lam)
        assert found.all()
        assert np.abs(back - forward_kinematics(robot, lam)).max() <= 1e-15
        reachable, ratio, conditioning, _ = legs.status(
            robot.legs, robot.leg_constants, positions)
        status = workspace_status(robot, positions)
        assert (reachable == status.reachable).all()
        assert np.abs(ratio - status.alpha_ratio).max() <= 1e-15
        assert np.abs(conditioning - status.conditioning).max() <= 1e-14


def open_loop_error(plant_robot, feedforward_robot, dt=1e-3):
    """Largest error (m) of eq. (6) fed forward open loop over 2 s."""
    position, velocity, _ = paper_sample(0.0)
    error = 0.0
    for k in range(int(round(2.0 / dt))):
        t = k * dt
        force = solve(feedforward_robot, *paper_sample(t + 0.5 * dt)).force
        try:
            position, velocity, _ = rk4_step(plant_robot, position, velocity,
                                             force, dt)
        except WorkspaceError:
            return np.inf
        error = max(error, np.abs(np.subtract(position, paper_sample(
            t + dt)[0])).max())
    return error


def test_a_plant_as_built_moves_as_its_own_model_says():
    """
    The plant integrates the legs as built (test_simulation_energy's bound).

    Its own feedforward keeps it on eq. (6) within 2e-6 m open loop; the
    drawing's, which misses about 0.3 N, lets the inverted pendulum of
    the vertical leg fall away.
    """
    assert open_loop_error(BUILT, BUILT) <= 2e-6
    assert open_loop_error(BUILT, Robot()) >= 1e-3
    assert mechanics.solve(BUILT, (0.0, 0.0, 0.0)).lambda_ != (0.0,) * 3


def test_a_roll_about_an_axis_moves_neither_readings_nor_forces():
    """
    Why the legs' frames take no roll (doc/model.md#the-machine-as-built).

    A leg's frame turned about its own axis moves its joints' axes, yet
    every reading and force is the same: the sphere is round about the
    axis, and the bodies it turns spin about their own axes or translate
    with the platform (as ``l``, ``l1``, ``l2``, ``alpha`` cancel).
    """
    robot = FAR.replace(gravity=(2.0, -5.0, -7.5))
    rng = np.random.default_rng(47)
    for angle in (0.3, -1.1, 2.5):
        c, s = np.cos(angle), np.sin(angle)
        roll = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        rolled = []
        for leg in robot.leg_constants:
            frame = np.array(leg.frame).reshape(3, 3) @ roll
            g = frame.T @ robot.gravity
            rolled.append(leg._replace(
                k=leg.k._replace(gx=g[0], gy=g[1], gz=g[2]),
                frame=tuple(frame.ravel())))
        for _ in range(5):
            state = (*rng.uniform(-0.3, 0.3, 3), *rng.uniform(-3.0, 3.0, 3),
                     *rng.uniform(-30.0, 30.0, 3))
            here = kernel.solve_legs(robot.leg_constants, *state, np.sqrt)
            there = kernel.solve_legs(rolled, *state, np.sqrt)
            assert np.abs(np.subtract(here[0], there[0])).max() <= GEOMETRY
            assert np.abs(np.subtract(here[3], there[3])).max() <= 1e-11
            assert np.abs(np.subtract(here[2], there[2])).max() <= 1e-11
