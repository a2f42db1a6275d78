"""
``solve_batch`` gives the same numbers as ``solve`` sample by sample.

Both run the same kernel, on numpy arrays and on Python floats; every
output (joint states, forces, powers, alpha_ratio, conditioning and
singularity distance) must agree to 1e-12 of its size, across the
batch's internal chunk boundary too.
"""

from mechanics_reference import OTHER_ROBOT_VALUES
import numpy as np
from orthoglide_ros.model.mechanics import BATCH_CHUNK, Solution, solve, \
    solve_batch
from orthoglide_ros.model.robot import Robot
import pytest

RELATIVE = 1e-12


def random_states(seed, n):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.3, 0.3, (n, 3)), rng.uniform(-3.0, 3.0, (n, 3)),
            rng.uniform(-30.0, 30.0, (n, 3)))


def assert_same(batch, singles):
    for i, field in enumerate(Solution._fields):
        expected = np.array([s[i] for s in singles])
        got = np.asarray(batch[i])
        assert got.shape == expected.shape, field
        scale = np.abs(expected).max() + 1e-300
        assert np.abs(got - expected).max() <= RELATIVE * scale, field


@pytest.mark.parametrize('values', [{}, OTHER_ROBOT_VALUES],
                         ids=['paper', 'other'])
def test_batch_equals_single_samples_across_chunks(values):
    robot = Robot(**values)
    n = BATCH_CHUNK + 37
    positions, velocities, accelerations = random_states(11, n)
    batch = solve_batch(robot, positions, velocities, accelerations)
    singles = [solve(robot, p, v, a) for p, v, a in
               zip(positions, velocities, accelerations)]
    assert_same(batch, singles)
    assert batch.force.shape == (n, 3)
    assert batch.conditioning.shape == (n,)


def test_missing_rates_mean_zero():
    robot = Robot(gravity=(1.0, -2.0, -9.0))
    positions, _, accelerations = random_states(12, 50)
    singles = [solve(robot, p) for p in positions]
    assert_same(solve_batch(robot, positions), singles)
    singles = [solve(robot, p, (0.0, 0.0, 0.0), a)
               for p, a in zip(positions, accelerations)]
    assert_same(solve_batch(robot, positions, None, accelerations), singles)


def test_single_sample_batch():
    robot = Robot()
    position, velocity, acceleration = (a[0] for a in random_states(13, 1))
    batch = solve_batch(robot, position[None], velocity[None],
                        acceleration[None])
    assert_same(batch, [solve(robot, position, velocity, acceleration)])


@pytest.mark.parametrize('shape', [(3,), (4, 2), (2, 3, 1)])
def test_batch_refuses_wrong_shapes(shape):
    with pytest.raises(ValueError):
        solve_batch(Robot(), np.zeros(shape))
    with pytest.raises(ValueError):
        solve_batch(Robot(), np.zeros((4, 3)), np.zeros((5, 3)))
