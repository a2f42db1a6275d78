"""
``leg_joints`` and ``platform_velocity``: the joint variables and rates.

``leg_joints`` against eq. (9) written independently (the reference model)
and its derivative by complex step, for one sample and for every row of a
batch;
``platform_velocity`` inverts ``lambdadot = J_lambda rdot_G`` (the
reference's complex-step ``J_lambda``); both refuse what ``solve`` refuses.
"""

from hypothesis import given, settings
from hypothesis_profiles import examples
from mechanics_reference import (
    COMPLEX_STEP, cube_points, lambda_jacobian, leg_geometry, LEGS,
    vectors)
import numpy as np
from orthoglide_ros.model.bodies import leg_joints
from orthoglide_ros.model.mechanics import platform_velocity, WorkspaceError
from orthoglide_ros.model.robot import Robot
import pytest


def reference(robot, position, velocity):
    """Per leg: lambda, phi21, phi32 and their rates, by complex step."""
    step = np.asarray(position, complex) + 1j * COMPLEX_STEP * np.asarray(
        velocity, float)
    out = {}
    for leg in LEGS:
        g = leg_geometry(robot, leg, step)
        values = np.array([g.lam, np.arcsin(g.sin21), np.arcsin(g.sin32)])
        out[leg] = (values.real, values.imag / COMPLEX_STEP)
    return out


@settings(deadline=None, max_examples=examples(60))
@given(position=cube_points(), velocity=vectors(1.0))
def test_leg_joints_are_eq9_and_its_derivative(robot, position, velocity):
    legs = leg_joints(robot, position, velocity)
    for leg, (values, rates) in reference(robot, position, velocity).items():
        got = legs[leg]
        assert np.allclose([got.lambda_, got.phi21, got.phi32], values,
                           rtol=0, atol=1e-12)
        assert np.allclose([got.lambdadot, got.omega21, got.omega32], rates,
                           rtol=0, atol=1e-11)


def test_batch_rows_are_eq9_and_its_derivative():
    robot = Robot()
    rng = np.random.default_rng(3)
    positions = rng.uniform(-0.3, 0.3, (50, 3))
    velocities = rng.uniform(-1.0, 1.0, (50, 3))
    batch = leg_joints(robot, positions, velocities)
    for i, (p, v) in enumerate(zip(positions, velocities)):
        for leg, (values, rates) in reference(robot, p, v).items():
            got = batch[leg]
            assert np.allclose([got.lambda_[i], got.phi21[i], got.phi32[i]],
                               values, rtol=0, atol=1e-12)
            assert np.allclose(
                [got.lambdadot[i], got.omega21[i], got.omega32[i]], rates,
                rtol=0, atol=1e-11)


def test_refusals_are_those_of_solve():
    robot = Robot()
    with pytest.raises(WorkspaceError) as error:
        leg_joints(robot, (0.9, 0.0, 0.0))
    assert error.value.reason == 'unreachable'
    with pytest.raises(WorkspaceError) as error:
        leg_joints(robot, np.array([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0]]))
    assert error.value.reason == 'singular' and error.value.row == 1


@settings(deadline=None, max_examples=examples(60))
@given(position=cube_points(), velocity=vectors(1.0))
def test_platform_velocity_inverts_j_lambda(robot, position, velocity):
    rates = lambda_jacobian(robot, position) @ velocity
    back = platform_velocity(robot, position, rates)
    assert np.abs(np.subtract(back, velocity)).max() <= 1e-12


def test_platform_velocity_refuses():
    robot = Robot()
    with pytest.raises(WorkspaceError) as error:
        platform_velocity(robot, (0.0, 0.0, 0.0), (0.0, float('nan'), 0.0))
    assert error.value.reason == 'non_finite'
    with pytest.raises(WorkspaceError) as error:
        platform_velocity(robot, (0.0, 0.0, 0.9), (0.0, 0.0, 0.0))
    assert error.value.reason == 'unreachable'
