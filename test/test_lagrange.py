"""
Invariant 7: the recursive method agrees with Lagrange's equations.

``mechanics_reference.lagrange_forces`` is a second formulation sharing no
code with the package: the geometry of every body from eqs. (1)-(9), body
Jacobians by complex step, ``M(q) = sum m Jv^T Jv + Jw^T I Jw``, Christoffel
terms from ``dM/dq`` and ``f = J_lambda^-T (M qdd + C + dV/dq)``; the
drives' armature as their kinetic energy ``armature_j lambdadot_j^2 / 2``
(``J_lambda^T diag(armature) J_lambda`` in M), a payload as part of the
platform's mass.

Tolerance. Everything in the reference is exact to rounding except
``dM/dq``, a central difference with step h = 1e-5 m: its truncation error
is ``h^2 M''' / 6``, about ``h^2 / L^2 = 4e-10`` relative with L = 0.5 m the
length over which M varies (l3 cos(phi) >= 0.7 m in the cube), and its
rounding ``eps |M| / h``, about 2e-11 relative to ``|M| / L``. So the
Christoffel terms carry a relative error below ``DM_RELATIVE = 1e-8``
(20x margin) of ``|dM/dq| |qd|^2``; the other terms carry rounding,
``ROUNDING = 1e-12`` of their size. ``J_lambda^-T`` amplifies both by at
most its norm, which the bound includes.
"""

from hypothesis import given, settings, strategies as st
from hypothesis_profiles import examples
from mechanics_reference import (
    cube_points, DRIVES_ROBOT_VALUES, force_tolerance, lagrange_forces,
    lambda_jacobian, mass_matrix, OTHER_ROBOT_VALUES, potential_gradient,
    rest_forces, ROUNDING, vectors)
import numpy as np
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.mechanics import solve, solve_batch
from orthoglide_ros.model.robot import Robot

GRAVITIES = {'default': (0.0, 0.0, -9.81), 'zero': (0.0, 0.0, 0.0),
             'oblique': (2.0, -5.0, -7.5)}
ROBOTS = {'paper': {}, 'other': OTHER_ROBOT_VALUES,
          'drives': {**OTHER_ROBOT_VALUES, **DRIVES_ROBOT_VALUES}}


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points(), velocity=vectors(3.0),
       acceleration=vectors(30.0), gravity=st.sampled_from(sorted(GRAVITIES)),
       robot_name=st.sampled_from(sorted(ROBOTS)))
def test_forces_equal_lagrange_forces(position, velocity, acceleration,
                                      gravity, robot_name):
    robot = Robot(**ROBOTS[robot_name], gravity=GRAVITIES[gravity])
    force = np.array(solve(robot, position, velocity, acceleration).force)
    ref = lagrange_forces(robot, position, velocity, acceleration)
    assert np.abs(force - ref.force).max() <= force_tolerance(
        ref, velocity, acceleration)


@settings(deadline=None, max_examples=examples(40))
@given(position=cube_points(), acceleration=vectors(30.0),
       gravity=vectors(10.0), robot_name=st.sampled_from(sorted(ROBOTS)))
def test_forces_at_zero_velocity_equal_the_exact_reference(
        position, acceleration, gravity, robot_name):
    """No Christoffel term: the reference is exact to rounding here."""
    robot = Robot(**ROBOTS[robot_name], gravity=tuple(gravity))
    force = np.array(solve(robot, position, (0.0, 0.0, 0.0),
                           acceleration).force)
    expected, bound = rest_forces(robot, position, acceleration)
    assert np.abs(force - expected).max() <= bound


def test_inertial_forces_dominate_on_fast_motion_without_gravity():
    """The check above is not a check of gravity alone."""
    robot = Robot(gravity=(0.0, 0.0, 0.0))
    rng = np.random.default_rng(7)
    for _ in range(10):
        position = rng.uniform(-0.3, 0.3, 3)
        velocity = rng.uniform(-3.0, 3.0, 3)
        ref = lagrange_forces(robot, position, velocity, np.zeros(3))
        force = np.array(solve(robot, position, velocity).force)
        # Pure velocity terms: tens of newtons, checked to the bound.
        assert np.abs(ref.force).max() > 1.0
        assert np.abs(force - ref.force).max() <= force_tolerance(
            ref, velocity, np.zeros(3))


def random_states(seed, n):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.3, 0.3, (n, 3)), rng.uniform(-3.0, 3.0, (n, 3)),
            rng.uniform(-30.0, 30.0, (n, 3)))


def test_forces_do_not_depend_on_l_l1_l2_alpha():
    """doc/model.md: only l3, the masses and gravity enter the forces."""
    positions, velocities, accelerations = random_states(8, 500)
    paper = Robot()
    changed = paper.replace(l=0.31, l1=0.07, l2=0.19, alpha=1.2)
    f0 = solve_batch(paper, positions, velocities, accelerations).force
    f1 = solve_batch(changed, positions, velocities, accelerations).force
    assert np.abs(f1 - f0).max() <= ROUNDING * np.abs(f0).max()
    # The positions of the elements do depend on them (lambda does not).
    for leg in 'ABC':
        a1 = elements(changed, positions[0])[leg]['joints']['A1']
        assert np.abs(a1 - elements(paper, positions[0])[leg]['joints'][
            'A1']).max() > 0.01


def test_reference_forces_do_not_depend_on_l_l1_l2_alpha():
    """The same fact, shown by the independent model at rest."""
    positions, _, accelerations = random_states(9, 5)
    paper = Robot()
    changed = paper.replace(l=0.31, l1=0.07, l2=0.19, alpha=1.2)
    for position, acceleration in zip(positions, accelerations):
        forces = []
        for robot in (paper, changed):
            jac = lambda_jacobian(robot, position)
            generalised = (mass_matrix(robot, position) @ acceleration
                           + potential_gradient(robot, position))
            forces.append(np.linalg.solve(jac.T, generalised))
        assert np.abs(forces[1] - forces[0]).max() <= ROUNDING * np.abs(
            forces[0]).max()


def test_forces_do_depend_on_l3_and_every_mass():
    """The independence test above is not vacuous."""
    positions, velocities, accelerations = random_states(10, 50)
    paper = Robot()
    f0 = solve_batch(paper, positions, velocities, accelerations).force
    for change in ({'l3': 0.9}, {'m1': 0.5}, {'m2': 0.3}, {'m3': 3.0},
                   {'m4': 0.3}, {'m5': 16.0}, {'m6': 3.0}):
        f1 = solve_batch(paper.replace(**change), positions, velocities,
                         accelerations).force
        assert np.abs(f1 - f0).max() > 1e-3 * np.abs(f0).max(), change


DRIVE_STATES = (((0.05, 0.1, -0.2), (0.4, -0.3, 0.5), (3.0, -8.0, 5.0)),
                ((-0.2, 0.15, 0.1), (-1.0, 0.2, 0.7), (-12.0, 4.0, 9.0)),
                ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))


def test_drives_and_payload_match_the_lagrange_model_to_1e_8():
    """The armature and the payload by the independent model, 1e-8 N."""
    robot = Robot(**OTHER_ROBOT_VALUES, **DRIVES_ROBOT_VALUES)
    bare = Robot(**OTHER_ROBOT_VALUES)
    for position, velocity, acceleration in DRIVE_STATES:
        force = np.array(solve(robot, position, velocity, acceleration).force)
        ref = lagrange_forces(robot, position, velocity, acceleration)
        assert np.abs(force - ref.force).max() <= 1e-8
        # And they matter: tens of N at these accelerations, 5 kg of weight.
        assert np.abs(force - np.array(solve(
            bare, position, velocity, acceleration).force)).max() > 20.0


def test_a_payload_is_exactly_a_heavier_platform():
    """robot.payload P gives the forces of m5 + P, bit for bit."""
    carried = Robot(payload=5.0)
    heavier = Robot(m5=Robot().m5 + 5.0)
    p, v, a = (np.array(x) for x in zip(*DRIVE_STATES))
    for position, velocity, acceleration in DRIVE_STATES:
        assert solve(carried, position, velocity, acceleration) == solve(
            heavier, position, velocity, acceleration)
    batch = [solve_batch(r, p, v, a) for r in (carried, heavier)]
    for x, y in zip(*batch):
        assert np.array_equal(x, y)


def test_payload_force_is_what_the_payload_adds_at_a_joint_state():
    """mechanics.payload_force from the joints: the heavier robot's excess."""
    from orthoglide_ros.model.mechanics import payload_force
    robot = Robot(**OTHER_ROBOT_VALUES, armature=(1.0, 2.0, 0.5))
    for position, velocity, acceleration in DRIVE_STATES:
        s = solve(robot, position, velocity, acceleration)
        heavier = solve(robot.replace(payload=7.5), position, velocity,
                        acceleration)
        excess = np.array(heavier.force) - np.array(s.force)
        found = payload_force(robot, 7.5, s.lambda_, s.lambdadot,
                              s.lambdaddot)
        assert np.abs(np.array(found) - excess).max() <= 1e-9 * max(
            1.0, np.abs(excess).max())
