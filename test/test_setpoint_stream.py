"""
The setpoint publisher's stream without ROS: eq. (6), the way back, loops.

Without ``loop`` one pass of eq. (6), then the end. With it the pass and
the way back (a quintic from the pass's end state to its start state)
repeat with period ``duration + return_duration``, and the motion is
continuous in position, velocity and acceleration at every joint of the
pieces (no jump back to home between passes).
"""

import numpy as np
import pytest

from orthoglide_ros.model import trajectory
from orthoglide_ros.cores.setpoint_publisher import PARAMETERS, Stream


def stream(**changes):
    return Stream(PARAMETERS.parse(changes))


def test_one_pass_is_eq6_then_ends():
    s = stream(duration=1.0)
    for t in (0.0, 0.3, 1.0):
        assert s.sample(t) == trajectory.paper_sample(t)
    assert s.sample(1.0 + 1e-9) is None


@pytest.mark.parametrize('duration, back', [(2.0, 4.0), (0.5, 0.5),
                                            (2.0, 0.2)])
def test_loop_is_continuous_at_both_joints(duration, back):
    s = stream(loop=True, duration=duration, return_duration=back)
    period = duration + back
    for joint in (duration, period, 2 * period + duration):
        before, after = s.sample(joint - 1e-12), s.sample(joint + 1e-12)
        for a, b in zip(before, after):
            assert np.allclose(a, b, atol=1e-6), (joint, a, b)
    # Each pass starts where eq. (6) starts: home, at rest.
    assert s.sample(period) == trajectory.paper_sample(0.0)


def test_way_back_meets_both_states_exactly():
    end = trajectory.paper_sample(2.0)
    start = trajectory.paper_sample(0.0)
    way = trajectory.quintic(end, start, 4.0)
    for got, want in zip(way(0.0), end):
        assert np.allclose(got, want, rtol=0, atol=1e-15)
    for got, want in zip(way(4.0), start):
        assert np.allclose(got, want, rtol=0, atol=1e-12)


def test_default_way_back_keeps_the_pass_peaks():
    """The default 4 s: peak speed and acceleration within 2 % of the pass's."""
    s = stream(loop=True)
    times = np.linspace(0.0, 6.0, 6001)
    samples = [s.sample(t) for t in times]
    speed = np.linalg.norm([v for _, v, _ in samples], axis=1)
    accel = np.linalg.norm([a for _, _, a in samples], axis=1)
    on_pass = times <= 2.0
    assert speed[~on_pass].max() <= 1.02 * speed[on_pass].max()
    assert accel[~on_pass].max() <= 1.02 * accel[on_pass].max()


def test_stream_counts_passes_and_gaps():
    s = stream(loop=True, duration=0.5, return_duration=0.5)
    for k in range(30):
        assert s.next(10**9 + k * 100_000_000) is not None
    assert s.passes == 3 and s.published == 30
    assert s.largest_gap_ns == 100_000_000
    assert '3 pass(es)' in s.summary()


def test_excitation_is_the_trajectory_modules_motion_then_ends():
    s = stream(motion='excitation', seed=3, duration=4.0)
    motion = trajectory.excitation(3, 4.0)
    for t in (0.0, 0.7, 2.5, 4.0):
        assert s.sample(t) == trajectory.excitation_sample(motion, t)
    assert s.sample(4.0 + 1e-9) is None
    assert max(map(abs, sum(s.sample(0.0), ()))) < 1e-15    # home, at rest


def test_looped_excitation_repeats_its_period_without_a_way_back():
    s = stream(motion='excitation', seed=5, duration=3.0, loop=True,
               return_duration=7.0)
    for t in (0.4, 1.9, 2.999):
        for a, b in zip(s.sample(t), s.sample(t + 3.0)):
            assert np.allclose(a, b, rtol=0, atol=1e-12), t
    assert s.passes == 2
    for joint in (3.0, 6.0):
        before, after = s.sample(joint - 1e-9), s.sample(joint + 1e-9)
        for a, b in zip(before, after):
            assert np.allclose(a, b, rtol=0, atol=1e-6), joint


def test_seeds_make_different_motions():
    one = stream(motion='excitation', seed=1).sample(0.5)
    two = stream(motion='excitation', seed=2).sample(0.5)
    assert one != two
    assert one == stream(motion='excitation', seed=1).sample(0.5)


@pytest.mark.parametrize('changes', [
    {'motion': 'excitation', 'duration': 0.0}, {'motion': 'bogus'},
    {'seed': -1}, {'seed': 2**31}, {'seed': 1.0}])
def test_bad_motion_settings_are_refused(changes):
    with pytest.raises(ValueError):
        PARAMETERS.parse(changes)
