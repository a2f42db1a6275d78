"""
Refused inputs raise ``WorkspaceError`` with their reason, never a NaN.

A platform position out of reach of a leg (eq. 9 not real), too near a
singularity of J1 (some ``alpha_i / l3`` below the margin) or of J2
(``1 / kappa_F(J_lambda)`` below the margin), a non-finite input or a
result that overflows must raise ``WorkspaceError`` with ``reason`` one of
``unreachable``, ``singular``, ``non_finite``, ``overflow`` (and the
sample's index in ``row`` for batches); nothing else may escape and no
output may hold a NaN or an infinity. ``workspace_status`` reports the
same distances, which are checked here against eqs. (9), (16) and (17)
written independently: over the cube |x|, |y|, |z| <= 0.3 m every
``alpha_i / l3 >= 0.866`` (doc/model.md).
"""

import itertools
import math

import numpy as np
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.mechanics import (
    DEFAULT_SINGULARITY_MARGIN, format_vector, REASONS, solve, solve_batch,
    workspace_status, WorkspaceError)
from orthoglide_ros.model.robot import Robot
import pytest

L3 = Robot().l3
# Points of the diagonal x = y = z = t where J2 is singular (eq. 16):
# J_lambda = I + r (ones - I) with r = t / alpha, det = (1 - r)^2 (1 + 2 r),
# alpha = sqrt(l3^2 - 2 t^2): r = -1/2 at t = -l3/sqrt(6) and r = 1 (rank
# one, every cofactor zero) at t = l3/sqrt(3). alpha/l3 = 0.82 and 0.58 there:
# J1 is regular.
J2_SINGULAR = {'det_zero': -L3 / math.sqrt(6.0),
               'rank_one': L3 / math.sqrt(3.0)}


def independent_status(robot, position):
    """alpha_i / l3 (eq. 17 via eq. 9) and 1/kappa_F(J1^-1 J2) (eq. 16)."""
    x, y, z = position
    l3 = robot.l3
    alpha = np.array([math.sqrt(l3 ** 2 - y * y - z * z),
                      math.sqrt(l3 ** 2 - z * z - x * x),
                      math.sqrt(l3 ** 2 - x * x - y * y)])
    j2 = np.array([[alpha[0], y, z], [x, alpha[1], z], [x, y, alpha[2]]])
    jac = np.linalg.solve(np.diag(alpha), j2)
    kappa = np.linalg.norm(jac) * np.linalg.norm(np.linalg.inv(jac))
    return alpha / l3, 3.0 / kappa


def assert_refused(reason, *args, **kwargs):
    with pytest.raises(WorkspaceError) as error:
        solve(Robot(), *args, **kwargs)
    assert error.value.reason == reason
    assert error.value.row is None
    return error.value


def test_alpha_ratio_over_the_cube_is_at_least_0_866():
    robot = Robot()
    axis = np.linspace(-0.3, 0.3, 13)
    grid = np.array(list(itertools.product(axis, repeat=3)))
    status = workspace_status(robot, grid)
    assert status.reachable.all() and status.ok.all()
    assert status.alpha_ratio.min() >= 0.866
    for position, ratio, conditioning in zip(
            grid[::37], status.alpha_ratio[::37], status.conditioning[::37]):
        expected_ratio, expected_conditioning = independent_status(
            robot, position)
        assert np.abs(ratio - expected_ratio).max() <= 1e-12
        assert abs(conditioning - expected_conditioning) <= 1e-12


def test_status_of_one_point_matches_solve():
    robot = Robot()
    position = (0.25, -0.28, 0.3)
    status = workspace_status(robot, position)
    s = solve(robot, position)
    assert status.reachable and status.ok
    assert np.abs(status.alpha_ratio - s.alpha_ratio).max() <= 1e-12
    assert abs(status.conditioning - s.conditioning) <= 1e-12
    expected = min(min(s.alpha_ratio), s.conditioning)
    assert status.singularity_distance == pytest.approx(expected, abs=1e-12)
    assert s.singularity_distance == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize('position', [(0.0, 0.9, 0.0), (0.0, 0.6, 0.61),
                                      (1.0, 1.0, 1.0), (-2.0, 0.0, 0.0)])
def test_unreachable_points(position):
    error = assert_refused('unreachable', position)
    assert 'leg' in str(error)
    status = workspace_status(Robot(), position)
    assert not status.reachable and not status.ok
    for value in status[1:4]:
        assert np.isfinite(value).all() and np.all(np.asarray(value) == 0.0)


@pytest.mark.parametrize('position', [(0.0, 0.84, 0.0), (0.6, 0.6, 0.6),
                                      (0.0, 0.0, -0.835)])
def test_points_near_a_singularity_of_j1(position):
    assert_refused('singular', position)
    ratio, _ = independent_status(Robot(), position)
    assert ratio.min() < DEFAULT_SINGULARITY_MARGIN
    assert not workspace_status(Robot(), position).ok


@pytest.mark.parametrize('kind', sorted(J2_SINGULAR))
@pytest.mark.parametrize('ulps', range(-3, 4))
def test_points_at_a_singularity_of_j2(kind, ulps):
    t = J2_SINGULAR[kind]
    for _ in range(abs(ulps)):
        t = math.nextafter(t, math.copysign(math.inf, ulps))
    position = (t, t, t)
    assert_refused('singular', position)
    status = workspace_status(Robot(), position)
    assert status.reachable and not status.ok
    assert status.conditioning < 1e-6
    assert status.alpha_ratio.min() > 0.5
    with pytest.raises(WorkspaceError) as error:
        solve_batch(Robot(), np.array([(0.0, 0.0, 0.0), position]))
    assert error.value.reason == 'singular' and error.value.row == 1


def test_the_sphere_where_every_slider_reads_l3_is_singular():
    # |G| = l3 with x, y, z > 0: every lambda_i = l3, the three spheres of
    # eq. (14) one, J_lambda = [G/x; G/y; G/z] of rank one, det J a rounding
    # (the diagonal point above is one of them). Before RANK_ONE, 1/kappa_F
    # there was a ratio of roundings: up to 0.53, accepted by the margin.
    rng = np.random.default_rng(31)
    directions = rng.uniform(0.3, 1.0, (400, 3))
    points = L3 * directions / np.linalg.norm(directions, axis=1)[:, None]
    for position in points:
        # alpha_i^2 = l3^2 - (|G|^2 - x_i^2) (eq. 9): here alpha_i = x_i.
        alpha = np.sqrt(L3 ** 2 - (position @ position - position ** 2))
        assert (alpha / L3).min() > 0.2     # J1 regular: J2 decides
        assert_refused('singular', tuple(position), margin=1e-6)
        assert workspace_status(Robot(), position).conditioning < 1e-6


def test_the_other_assembly_mode_is_refused():
    # det J_lambda < 0 (eq. 16) with 1/kappa_F = 0.25 by its absolute value:
    # eq. (9) has these lambda, but the robot assembled as at home is at
    # their mirror point, beyond a singularity of J2.
    position = (-0.55242263, 0.58549502, 0.43323122)
    alpha = np.array([L3 ** 2 - position[1] ** 2 - position[2] ** 2,
                      L3 ** 2 - position[2] ** 2 - position[0] ** 2,
                      L3 ** 2 - position[0] ** 2 - position[1] ** 2]) ** 0.5
    j2 = np.array([[alpha[0], position[1], position[2]],
                   [position[0], alpha[1], position[2]],
                   [position[0], position[1], alpha[2]]])
    assert np.linalg.det(j2) < -0.01 and (alpha / L3).min() > 0.3
    error = assert_refused('singular', position, margin=0.0)
    assert 'beyond a singularity of J2' in str(error)
    status = workspace_status(Robot(), position)
    assert status.conditioning == 0.0 and not status.ok
    with pytest.raises(WorkspaceError) as batch:
        solve_batch(Robot(), np.array([(0.0, 0.0, 0.0), position]), margin=0.0)
    assert batch.value.reason == 'singular' and batch.value.row == 1


def test_the_margin_decides():
    robot = Robot()
    position = (0.28, 0.28, -0.3)
    distance = workspace_status(robot, position).singularity_distance
    ratio, conditioning = independent_status(robot, position)
    assert distance == pytest.approx(min(ratio.min(), conditioning),
                                     abs=1e-12)
    assert solve(robot, position, margin=0.99 * distance).force
    with pytest.raises(WorkspaceError) as error:
        solve(robot, position, margin=1.01 * distance)
    assert error.value.reason == 'singular'
    assert workspace_status(robot, position, margin=0.99 * distance).ok
    assert not workspace_status(robot, position, margin=1.01 * distance).ok
    # A J1-refused point is accepted with a smaller margin.
    near = (0.0, 0.0, 0.82)    # alpha/l3 = 0.26 for legs A and B
    assert_refused('singular', near, margin=0.3)
    assert np.isfinite(solve(robot, near, margin=0.1).force).all()


@pytest.mark.parametrize('where', ['position', 'velocity', 'acceleration'])
@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_inputs(where, bad):
    args = {'position': [0.1, 0.0, 0.0], 'velocity': [0.0, 0.0, 0.0],
            'acceleration': [0.0, 0.0, 0.0]}
    args[where][1] = bad
    error = assert_refused('non_finite', args['position'], args['velocity'],
                           args['acceleration'])
    assert where in str(error)


@pytest.mark.parametrize('velocity, acceleration', [
    ((1e200, 1e200, 1e200), (0.0, 0.0, 0.0)),
    ((0.0, 1e160, 0.0), (0.0, 0.0, 0.0)),
    ((0.0, 0.0, 0.0), (1e308, 1e308, 1e308)),
    ((0.0, 0.0, 0.0), (-1.7e308, 0.0, 0.0))])
def test_overflow(velocity, acceleration):
    assert_refused('overflow', (0.1, 0.2, -0.1), velocity, acceleration)


BATCH_CASES = {
    'non_finite': ('velocities', (0.0, math.nan, 0.0)),
    'unreachable': ('positions', (0.0, 0.9, 0.0)),
    'singular': ('positions', (0.0, 0.84, 0.0)),
    'overflow': ('accelerations', (1e308, 1e308, 1e308)),
}


@pytest.mark.parametrize('reason', REASONS)
def test_batch_error_names_the_first_bad_row(reason):
    arrays = {'positions': np.full((9, 3), 0.05),
              'velocities': np.zeros((9, 3)),
              'accelerations': np.zeros((9, 3))}
    name, value = BATCH_CASES[reason]
    arrays[name][5] = value
    arrays[name][7] = value
    with pytest.raises(WorkspaceError) as error:
        solve_batch(Robot(), **arrays)
    assert error.value.reason == reason
    assert error.value.row == 5
    assert 'sample 5' in str(error.value)


@pytest.mark.parametrize('position', ((0.5, 0.5, 0.5), (0.787, 0.0, 0.0)))
def test_a_refused_position_is_a_field_beside_what_is_said_of_it(position):
    """Callers name the point their own way: no message is parsed."""
    with pytest.raises(WorkspaceError) as batch:
        solve_batch(Robot(), np.array([[0.0, 0.0, 0.0], position]))
    error = batch.value
    assert error.position.tolist() == list(position)
    assert error.finding.startswith(('is out of reach', 'is too near'))
    assert error.detail == (f'position {format_vector(position)} m '
                            f'{error.finding}')
    assert str(error) == f'sample 1: {error.detail}'


def test_no_nan_anywhere_around_the_reachable_region():
    """Every point of a grid over [-1, 1]^3 is solved or refused."""
    robot = Robot()
    axis = np.linspace(-1.0, 1.0, 17)
    rng = np.random.default_rng(15)
    outcomes = set()
    for i, position in enumerate(itertools.product(axis, repeat=3)):
        velocity = rng.uniform(-3.0, 3.0, 3)
        try:
            s = solve(robot, position, velocity, (1.0, -2.0, 3.0))
        except WorkspaceError as error:
            outcomes.add(error.reason)
            continue
        outcomes.add('solved')
        for value in s:
            assert np.isfinite(value).all()
        if i % 5:
            continue
        e = elements(robot, position, velocity)
        for leg in e.values():
            for body in leg['bodies'].values():
                for value in body.values():
                    assert np.isfinite(value).all()
    assert outcomes == {'solved', 'unreachable', 'singular'}
    status = workspace_status(
        robot, np.array(list(itertools.product(axis, repeat=3))))
    for value in status:
        assert np.isfinite(np.asarray(value, dtype=float)).all()
