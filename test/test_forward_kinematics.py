"""
``forward_kinematics`` inverts eq. (9) over the workspace cube.

Round trip ``r_G -> lambda (eq. 9) -> r_G`` to 1e-12 m, for single points
and batches, with lambda from the package and from eq. (9) written
independently; inputs with no platform position on the home branch raise
``WorkspaceError`` rather than give NaN.
"""

import itertools

from hypothesis import given, settings
from hypothesis_profiles import examples
from mechanics_reference import (
    actuator_displacements, CUBE, cube_points)
import numpy as np
from orthoglide_ros.model.mechanics import (
    forward_kinematics, solve, solve_batch, workspace_status, WorkspaceError)
from orthoglide_ros.model.robot import Robot
import pytest

TOLERANCE = 1e-12  # m
CORNERS = np.array(list(itertools.product((-CUBE, CUBE), repeat=3)))


@settings(deadline=None, max_examples=examples(60))
@given(position=cube_points())
def test_round_trip_single_point(robot, position):
    lam = solve(robot, position).lambda_
    back = forward_kinematics(robot, lam)
    assert back.shape == (3,)
    assert np.abs(back - position).max() <= TOLERANCE
    independent = actuator_displacements(robot, position)
    assert np.abs(forward_kinematics(robot, independent)
                  - position).max() <= TOLERANCE


def test_round_trip_batch_over_the_cube_and_its_corners(robot):
    rng = np.random.default_rng(14)
    grid = np.array(list(itertools.product(np.linspace(-CUBE, CUBE, 7),
                                           repeat=3)))
    positions = np.vstack([rng.uniform(-CUBE, CUBE, (5000, 3)), grid,
                           CORNERS])
    back = forward_kinematics(robot, solve_batch(robot, positions).lambda_)
    assert back.shape == positions.shape
    assert np.abs(back - positions).max() <= TOLERANCE


def test_round_trip_where_a_slider_reads_beyond_l3():
    # Reachable positions past the cube where some lambda_j > l3: the
    # smaller root of the drawing's quadratic is not the home branch there.
    rng = np.random.default_rng(15)
    positions = rng.uniform(-0.7, 0.7, (20000, 3))
    status = workspace_status(Robot(), positions)
    positions = positions[status.ok]
    lam = solve_batch(Robot(), positions).lambda_
    beyond = (lam > Robot().l3).any(1)
    assert beyond.sum() >= 50
    back = forward_kinematics(Robot(), lam[beyond])
    assert np.abs(back - positions[beyond]).max() <= 1e-9
    for position, row in zip(positions[beyond][:20], lam[beyond][:20]):
        assert np.abs(forward_kinematics(Robot(), row)
                      - position).max() <= 1e-9


def test_home():
    assert np.abs(forward_kinematics(Robot(), (0.0, 0.0, 0.0))).max() == 0.0


@pytest.mark.parametrize('lam', [(2.0, 0.0, 0.0), (0.0, -5.0, 0.0),
                                 (0.85, 0.85, 0.85), (1.7, 1.7, 1.7)])
def test_lambda_without_a_platform_position_raises(lam):
    with pytest.raises(WorkspaceError) as error:
        forward_kinematics(Robot(), lam)
    assert error.value.reason == 'unreachable'
    with pytest.raises(WorkspaceError):
        forward_kinematics(Robot(), np.array([(0.0, 0.0, 0.0), lam]))


@pytest.mark.parametrize('bad', [np.nan, np.inf, -np.inf])
def test_non_finite_lambda_raises(bad):
    with pytest.raises(WorkspaceError) as error:
        forward_kinematics(Robot(), (0.0, bad, 0.0))
    assert error.value.reason == 'non_finite'
