"""
The demos' verdict: a run the machine spoiled is FAILED, named why.

``orthoglide_testing.verdicts``, without DDS: a stream with fewer
setpoints than the rate promises, a gap of several periods, outputs lost
(``scripts/demo.py``); a reliable stream whose producer was late past the
node's input history (``reliability``); a closed-loop pass with the plant
braked, the controller held, simulated time skipped or one force applied
too long (the loop demos and tests).
"""

from types import SimpleNamespace

import numpy as np
import pytest

from orthoglide_testing import verdicts


def test_a_stream_that_kept_its_rate_is_not_spoiled():
    assert verdicts.stream_spoiled_by(2.0, 500.0, 1001, 2.3, 0) == []


def test_a_slow_gapped_lossy_stream_is_spoiled_and_says_why():
    """662 of 1000 setpoints at 330 Hz, a 170 ms gap, 5 lost."""
    reasons = verdicts.stream_spoiled_by(2.0, 500.0, 662, 170.0, 5)
    assert len(reasons) == 3, reasons
    assert reasons[0] == '662 of 1000 setpoints sent (331 of 500 Hz)'
    assert reasons[1].startswith('a gap of 170.0 ms')
    assert reasons[2] == '5 of 662 outputs lost'


def test_no_word_from_the_publisher_is_spoiled():
    assert verdicts.stream_spoiled_by(2.0, 500.0, None, None, None) == [
        'the setpoint publisher did not say what it sent']


def loop_pass(braked=0, joint_error=0.0, skipped_s=0.0, same_command_s=0.004):
    return SimpleNamespace(braked=braked, skipped_s=skipped_s,
                           same_command_s=same_command_s,
                           joint_error=np.full((10, 3), joint_error))


def test_a_closed_loop_pass_is_spoiled_by_a_brake_a_hold_a_skip_a_stuck_force():
    tolerance = float(verdicts.PATH_TOLERANCE.max())
    assert verdicts.pass_spoiled_by(loop_pass()) is None
    assert verdicts.pass_spoiled_by(
        loop_pass(joint_error=0.5 * tolerance)) is None
    assert verdicts.pass_spoiled_by(loop_pass(braked=4)) == \
        'the plant was braked for 4 states'
    assert 'path tolerance' in verdicts.pass_spoiled_by(
        loop_pass(joint_error=-1.01 * tolerance))
    assert verdicts.pass_spoiled_by(loop_pass(skipped_s=0.25)) == \
        'the plant skipped 0.250 s of simulated time'
    assert verdicts.pass_spoiled_by(loop_pass(skipped_s=0.1)) is None
    assert verdicts.pass_spoiled_by(loop_pass(same_command_s=0.074)) == \
        'the plant applied one force for 74 ms'
    assert verdicts.pass_spoiled_by(loop_pass(same_command_s=0.05)) is None


def test_the_longest_unchanged_force_is_timed_from_the_states():
    """Two states per loop period, then one force over 5 states: 10 ms."""
    harness = pytest.importorskip('orthoglide_testing.closed_loop')
    period = 0.002
    efforts = np.array([[0.0] * 3] * 4 + [[1.0, 2.0, 3.0]] * 2
                       + [[1.5, 2.0, 3.0]] * 5 + [[1.0, 2.0, 3.0]] * 2)
    times = np.arange(len(efforts)) * period
    assert harness.longest_same_force(times, efforts, period) == \
        pytest.approx(0.010)
    assert harness.longest_same_force(times, np.zeros((5, 3)), period) == 0.0


def test_a_reliable_run_is_stalled_when_its_producer_was_later_than_the_cover():
    """Depth 100 at 1 kHz covers 100 ms: the producer 233 ms late is beyond."""
    checks = pytest.importorskip('orthoglide_testing.reliability.checks')
    run = dict(depth=100, rate=1000, late_max_ms=99.0)
    assert checks.stalled_by(run) is None
    assert checks.stalled_by(dict(run, late_max_ms=233.0)) == (
        'the producer was 233 ms late, past the 100 ms the input history '
        'covers')
    assert checks.stalled_by(dict(run, depth=10, late_max_ms=11.0))


def test_a_spoiled_run_is_run_again_up_to_the_attempts_the_last_kept():
    results, heard = iter([1, 2, 3, 4, 5, 6]), []
    spoiled = lambda n: None if n == 3 else f'run {n} stalled'  # noqa: E731
    assert verdicts.first_unspoiled(lambda: next(results), spoiled,
                                    lambda *a: heard.append(a)) == 3
    assert heard == [(1, 'run 1 stalled', 1), (2, 'run 2 stalled', 2)]
    always = iter(range(10))
    assert verdicts.first_unspoiled(lambda: next(always), str,
                                    attempts=verdicts.ATTEMPTS) == \
        verdicts.ATTEMPTS - 1
