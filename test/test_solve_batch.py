"""
``solve_batch`` against models written apart from it, across its chunks.

Every row's joint states against eq. (9) in closed form, written out here:
for leg A, ``lambda = x + l3 - s`` with ``s = alpha_1 = sqrt(l3^2 - y^2 -
z^2)`` (eq. 17), so ``lambdadot = xd + u / s`` and ``lambdaddot = xdd + ud /
s + u^2 / s^3`` with ``u = y yd + z zd``, ``ud = yd^2 + zd^2 + y ydd + z
zdd`` (legs B and C cyclically); ``J_lambda``'s row ``(1, y / s, z / s)``
(eq. 16, ``J1^-1 J2``) gives the conditioning ``3 / kappa_F(J_lambda)``.
The forces and powers of the rows on both sides of the batch's chunk
boundaries, and of random rows, against ``mechanics_reference``'s
Lagrange model (which shares no code with the package; it also checks the
closed form's ``lambda`` and ``J_lambda`` there).

Tolerances. The closed form and the kernel each round some twenty times,
each time by at most eps/2 of a term: ``ROUNDING = 1e-14`` (45 eps) of the
sum of the terms' magnitudes (the worst measured: 3 eps). ``RATIO =
1e-14`` absolute for ``alpha_i / l3``, for ``J_lambda`` against the
reference's complex step and for the conditioning, whose rounding
``kappa_F / 3`` (below 2.6 on these rows) amplifies (measured: 3 eps).
Forces to ``mechanics_reference.force_tolerance``, the Lagrange model's
own error (derived in test_lagrange.py; the worst measured is 1.5e-3 of
it); a power ``lambdadot f`` to ``|lambdadot|`` times that plus ``|f|``
times lambdadot's.
"""

from mechanics_reference import (
    actuator_displacements, batch_rows, force_tolerance, lagrange_forces,
    LEG_AXES, OTHER_ROBOT_VALUES)
import numpy as np
from orthoglide_ros.model.mechanics import BATCH_CHUNK, solve_batch
from orthoglide_ros.model.robot import Robot
import pytest

ROUNDING = 1e-14
RATIO = 1e-14
ROBOTS = {'paper': Robot(),
          'other': Robot(**OTHER_ROBOT_VALUES, gravity=(2.0, -5.0, -7.5))}


def random_states(seed, n):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.3, 0.3, (n, 3)), rng.uniform(-3.0, 3.0, (n, 3)),
            rng.uniform(-30.0, 30.0, (n, 3)))


def closed_form(robot, positions, velocities, accelerations):
    """
    Eq. (9) in closed form and its rates, row by row (module docstring).

    Returns per-leg (N, 3) ``lambda``, ``lambdadot``, ``lambdaddot``, the
    size of each one's terms (TERMS), ``alpha / l3``, and ``J_lambda``
    (N, 3, 3).
    """
    n = len(positions)
    values = {name: np.empty((n, 3)) for name in (
        'lambda_', 'lambdadot', 'lambdaddot', 'alpha_ratio')}
    terms = {name: np.empty((n, 3)) for name in (
        'lambda_', 'lambdadot', 'lambdaddot')}
    jacobian = np.zeros((n, 3, 3))
    l3 = robot.l3
    for leg, (i, j, k) in enumerate(LEG_AXES.values()):
        x, y, z = positions[:, i], positions[:, j], positions[:, k]
        xd, yd, zd = velocities[:, i], velocities[:, j], velocities[:, k]
        xdd, ydd, zdd = (accelerations[:, i], accelerations[:, j],
                         accelerations[:, k])
        s = np.sqrt(l3 * l3 - y * y - z * z)
        u = y * yd + z * zd
        ud = yd * yd + zd * zd + y * ydd + z * zdd
        values['lambda_'][:, leg] = x + l3 - s
        values['lambdadot'][:, leg] = xd + u / s
        values['lambdaddot'][:, leg] = xdd + ud / s + u * u / s ** 3
        values['alpha_ratio'][:, leg] = s / l3
        terms['lambda_'][:, leg] = np.abs(x) + l3 + s
        terms['lambdadot'][:, leg] = np.abs(xd) + (
            np.abs(y * yd) + np.abs(z * zd)) / s
        terms['lambdaddot'][:, leg] = np.abs(xdd) + (
            yd * yd + zd * zd + np.abs(y * ydd) + np.abs(z * zdd)) / s \
            + u * u / s ** 3
        jacobian[:, leg, i] = 1.0
        jacobian[:, leg, j] = y / s
        jacobian[:, leg, k] = z / s
    return values, terms, jacobian


def assert_rows_match(robot, batch, states, rows):
    """Every row's kinematics, and ``rows``' forces and powers."""
    positions, velocities, accelerations = states
    n = len(positions)
    assert batch.force.shape == batch.power.shape == (n, 3)
    assert batch.conditioning.shape == batch.singularity_distance.shape \
        == (n,)
    values, terms, jacobian = closed_form(robot, *states)
    for name in ('lambda_', 'lambdadot', 'lambdaddot'):
        error = np.abs(getattr(batch, name) - values[name])
        assert (error <= ROUNDING * terms[name]).all(), name
    assert np.abs(batch.alpha_ratio - values['alpha_ratio']).max() <= RATIO
    kappa = np.linalg.norm(jacobian, axis=(1, 2)) * np.linalg.norm(
        np.linalg.inv(jacobian), axis=(1, 2))
    assert np.abs(batch.conditioning - 3.0 / kappa).max() <= RATIO
    nearest = np.minimum(values['alpha_ratio'].min(axis=1), 3.0 / kappa)
    assert np.abs(batch.singularity_distance - nearest).max() <= RATIO
    for row in rows:
        state = positions[row], velocities[row], accelerations[row]
        ref = lagrange_forces(robot, *state)
        assert np.abs(ref.jacobian - jacobian[row]).max() <= RATIO, row
        assert np.abs(values['lambda_'][row] - actuator_displacements(
            robot, positions[row])).max() <= ROUNDING, row
        tolerance = force_tolerance(ref, velocities[row], accelerations[row])
        assert np.abs(batch.force[row] - ref.force).max() <= tolerance, row
        rates = values['lambdadot'][row]
        power = np.abs(batch.power[row] - rates * ref.force)
        assert (power <= np.abs(rates) * tolerance + np.abs(ref.force)
                * ROUNDING * terms['lambdadot'][row]).all(), row


@pytest.mark.parametrize('name', sorted(ROBOTS))
def test_every_row_matches_eq9_and_the_lagrange_model_across_chunks(name):
    robot = ROBOTS[name]
    n = BATCH_CHUNK + 37
    states = random_states(11, n)
    batch = solve_batch(robot, *states)
    assert_rows_match(robot, batch, states, batch_rows(n, BATCH_CHUNK, 1))


def test_missing_rates_mean_zero():
    robot = Robot(gravity=(1.0, -2.0, -9.0))
    positions, _, accelerations = random_states(12, 50)
    zeros = np.zeros_like(positions)
    rows = [0, 17, 49]
    assert_rows_match(robot, solve_batch(robot, positions),
                      (positions, zeros, zeros), rows)
    assert_rows_match(robot, solve_batch(robot, positions, None,
                                         accelerations),
                      (positions, zeros, accelerations), rows)


def test_a_batch_of_one_sample():
    robot = Robot()
    states = random_states(13, 1)
    assert_rows_match(robot, solve_batch(robot, *states), states, [0])


@pytest.mark.parametrize('shape', [(3,), (4, 2), (2, 3, 1)])
def test_batch_refuses_wrong_shapes(shape):
    with pytest.raises(ValueError):
        solve_batch(Robot(), np.zeros(shape))
    with pytest.raises(ValueError):
        solve_batch(Robot(), np.zeros((4, 3)), np.zeros((5, 3)))
