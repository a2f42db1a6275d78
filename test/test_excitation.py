"""
The excitation motion: a periodic Fourier series within its bounds.

``trajectory.excitation`` promises (doc/identification.md): five harmonics
of ``1 / period`` per axis; home, at rest, zero acceleration at t = 0 and
so, being periodic, at every multiple of the period; each axis within the
position box, the speed and the acceleration bounds (each reached to
within a few % by the scaling, so the bounds are what limits the motion);
inside the workspace with the singularity margin; the same seed the same
motion. Velocities and accelerations are checked against finite
differences of the positions, not against the formulas.
"""

from mechanics_reference import derivative
import numpy as np
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot
import pytest

SEEDS = (0, 1, 17, 123456)
PERIODS = (2.0, 5.0, 30.0)


@pytest.mark.parametrize('seed', SEEDS)
@pytest.mark.parametrize('period', PERIODS)
def test_starts_at_home_at_rest_and_is_periodic(seed, period):
    motion = trajectory.excitation(seed, period)
    for t in (0.0, period, 3 * period):
        for values in trajectory.excitation_sample(motion, t):
            assert np.abs(values).max() < 1e-12, (t, values)
    for t in (0.3, 1.7):
        for a, b in zip(trajectory.excitation_sample(motion, t),
                        trajectory.excitation_sample(motion, t + period)):
            assert np.allclose(a, b, rtol=0.0, atol=1e-12)


@pytest.mark.parametrize('seed', SEEDS)
def test_rates_are_the_derivatives_of_the_positions(seed):
    motion = trajectory.excitation(seed, 5.0)
    h = 1e-3
    for t in (0.1, 1.3, 2.9, 4.4):
        p, v, a = (np.array(x) for x in trajectory.excitation_sample(
            motion, t))
        fd_v = derivative(
            lambda s: trajectory.excitation_sample(motion, s)[0], t, h)
        fd_a = derivative(
            lambda s: trajectory.excitation_sample(motion, s)[1], t, h)
        assert np.abs(fd_v - v).max() <= 1e-9
        assert np.abs(fd_a - a).max() <= 1e-8
    times = np.linspace(0.0, 5.0, 7)
    batch = trajectory.excitation_batch(motion, times)
    for i, t in enumerate(times):
        for whole, single in zip(batch, trajectory.excitation_sample(
                motion, t)):
            assert np.allclose(whole[i], single, rtol=0.0, atol=1e-15)


@pytest.mark.parametrize('seed', SEEDS)
@pytest.mark.parametrize('period', PERIODS)
def test_each_axis_stays_within_its_bounds_and_meets_one(seed, period):
    motion = trajectory.excitation(seed, period)
    assert motion.sines.shape == (3, trajectory.EXCITATION_HARMONICS)
    # Ten times finer than the grid the scaling used.
    times = np.linspace(0.0, period, 40001)
    p, v, a = trajectory.excitation_batch(motion, times)
    ratios = np.array([
        np.abs(p).max(0) / trajectory.EXCITATION_BOX,
        np.abs(v).max(0) / trajectory.EXCITATION_MAX_VELOCITY,
        np.abs(a).max(0) / trajectory.EXCITATION_MAX_ACCELERATION])
    assert ratios.max() <= 1.0
    assert (ratios.max(axis=0) >= 0.98).all(), ratios
    status = mechanics.workspace_status(Robot(), p)
    assert status.ok.all()


def test_the_same_seed_gives_the_same_motion():
    one, again = (trajectory.excitation(9, 4.0) for _ in range(2))
    assert np.array_equal(one.sines, again.sines)
    assert np.array_equal(one.cosines, again.cosines)
    other = trajectory.excitation(10, 4.0)
    assert not np.array_equal(one.sines, other.sines)


def test_a_path_outside_the_workspace_is_refused():
    small = Robot(l3=0.2)   # the 0.15 m box nears its J1 singularity
    with pytest.raises(ValueError, match='workspace'):
        trajectory.excitation(0, 5.0, robot=small)
    motion = trajectory.excitation(0, 5.0, box=0.05, robot=small,
                                   margin=0.5)
    positions = trajectory.excitation_batch(
        motion, np.linspace(0.0, 5.0, 1000))[0]
    assert mechanics.workspace_status(small, positions, 0.5).ok.all()


@pytest.mark.parametrize('kwargs', [
    {'seed': -1}, {'seed': 1.5}, {'seed': True}, {'period': 0.0},
    {'period': float('nan')}, {'harmonics': 0}, {'box': -0.1},
    {'max_velocity': 0.0}, {'max_acceleration': float('inf')}])
def test_bad_arguments_are_refused(kwargs):
    arguments = {'seed': 0, 'period': 5.0} | kwargs
    with pytest.raises(ValueError):
        trajectory.excitation(**arguments)
