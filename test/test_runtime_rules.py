"""
The rules of the node runtime that need no DDS.

- ``text.clip``: the one place text from messages is shortened, and
  ``text.printable``, the one filter between a node's text and its log;
- the set-parameters requests refused before rclpy sees them;
- the feedforward's trajectory stamp rule (header + time_from_start, the
  zero header meaning "now", nanosec in [0, 1e9) on both);
- the simulator's real-time grid (``Simulator.step_due``).
"""

import pytest

from orthoglide_ros.cores import feedforward, simulator
from orthoglide_ros.formats import text
from orthoglide_ros.cores.inputs import Rejected

reply_guard = pytest.importorskip('orthoglide_ros.ros.reply_guard')
from rcl_interfaces.msg import Parameter, ParameterValue  # noqa: E402
from rcl_interfaces.srv import (GetParameters,  # noqa: E402
                                SetParameters, SetParametersAtomically)

IDENTITY = (0.0, 0.0, 0.0, 1.0)
ZERO = (0.0, 0.0, 0.0)


def test_clip_keeps_short_text_and_cuts_long_text_in_the_middle():
    assert text.clip('short') == 'short'
    long = 'a' * 1000 + 'b' * 5_000_000 + 'c' * 1000
    cut = text.clip(long)
    assert len(cut) <= text.TEXT_LIMIT + 60
    assert cut.startswith('a' * 1000) and cut.endswith('c' * 1000)
    assert '5000000 characters cut' in cut


@pytest.mark.parametrize('bad', [
    '\n', '\r', '\r\n', '\t', '\x00', '\x1b[2J', '\x7f', '\x85', '\u2028',
    '\u2029', '\u202e', '\u200b', '\ufeff', '\x1c', '\ud800'])
def test_printable_leaves_one_line_without_a_control_character(bad):
    forged = f'label{bad}[FATAL] [1.0] [feedforward]: FORGED{bad}'
    shown = text.printable(forged)
    assert shown.isprintable() and len(shown.splitlines()) == 1, shown
    # Written as Python writes it: the text can be told back.
    assert shown == repr(forged)[1:-1].replace("\\'", "'")
    assert text.printable('plain, é, 中文, \\n') == 'plain, é, 中文, \\n'
    assert len(text.printable(bad * 100_000)) <= text.TEXT_LIMIT + 60


@pytest.mark.parametrize('srv_type', [SetParameters,
                                      SetParametersAtomically])
def test_a_value_type_that_does_not_exist_is_refused(srv_type):
    bad = srv_type.Request(parameters=[
        Parameter(name='rate_hz', value=ParameterValue(type=3)),
        Parameter(name='x' * 500, value=ParameterValue(type=200))])
    reason = reply_guard._malformed_parameters(srv_type, bad)
    assert reason.startswith('malformed request') and '200' in reason
    assert len(reason) < 300
    good = srv_type.Request(parameters=bad.parameters[:1])
    assert reply_guard._malformed_parameters(srv_type, good) is None
    assert reply_guard._malformed_parameters(
        GetParameters, GetParameters.Request()) is None


def feedforward_core():
    return feedforward.Feedforward(feedforward.PARAMETERS.parse({}))


@pytest.mark.parametrize('header, offset', [
    ((5, 10**9), (0, 0)), ((5, 0), (0, 10**9)), ((0, 10**9), (0, 0)),
    ((5, 2**32 - 1), (1, 5))])
def test_trajectory_nanoseconds_beyond_a_second_are_stamp_errors(header,
                                                                 offset):
    ff = feedforward_core()
    with pytest.raises(Rejected) as info:
        ff.trajectory_message(header, offset, (100, 0), '', ZERO, IDENTITY,
                              ZERO, ZERO, 0.0)
    assert info.value.reason == 'stamp'
    assert ff.rejected['stamp'] == 1 and ff.received['trajectory'] == 1


def test_trajectory_stamp_is_header_plus_offset_or_now():
    ff = feedforward_core()
    out = ff.trajectory_message((5, 900_000_000), (1, 200_000_000),
                                (100, 0), '', ZERO, IDENTITY, ZERO, ZERO,
                                0.0)
    assert out.stamp == (7, 100_000_000)
    now = ff.trajectory_message((0, 0), (0, 5), (100, 7), '', ZERO,
                                IDENTITY, ZERO, ZERO, 0.0)
    assert now.stamp == (100, 12)


def test_grid_catches_up_then_drops_time():
    """Steps due at a late wake-up: up to MAX_CATCH_UP, then time dropped."""
    sim = simulator.Simulator(simulator.PARAMETERS.parse({}), now=0.0)
    sim.command([0.0, 0.0, 256.5315], 0.0)
    period = 1e-3
    first = sim.step_due(0.0)
    assert first is not None and sim.step_due(0.0) is None
    made = 0
    while sim.step_due(0.0045) is not None:
        made += 1
    assert made == 4 and sim.overruns == 0      # 0.5, 1.5, ... 4.5 ms
    late = 0.0045 + 50 * period
    made = 0
    while sim.step_due(late) is not None:
        made += 1
    assert made == simulator.MAX_CATCH_UP and sim.overruns == 1
    # The grid stood at 4.5 ms and restarts 9.5 periods before ``late``.
    assert sim.dropped_time == pytest.approx(
        late - (simulator.MAX_CATCH_UP - 0.5) * period - 0.0045, abs=1e-9)


def test_own_stall_longer_than_the_command_timeout_brakes():
    """
    Woken up past command_timeout: the commands read then are not fresh.

    A command that waited in the queue while the process stood still is
    read "now"; held on, it would drive the plant until the controller
    answers. The next step is a timeout instead; a later command resumes.
    """
    sim = simulator.Simulator(simulator.PARAMETERS.parse(
        {'command_timeout': 0.1}), now=0.0)
    sim.command([50.0, 50.0, 300.0], 0.0)
    while sim.step_due(0.05) is not None:
        pass
    assert sim.state == simulator.RUNNING and sim.plant.velocity != (0.0,) * 3
    # A stall shorter than the timeout: caught up, still running.
    sim.command([50.0, 50.0, 300.0], 0.12)
    tick, _ = sim.step_due(0.12)
    assert tick.event is None and sim.state == simulator.RUNNING
    assert sim.stall_brakes == 0
    while sim.step_due(0.12) is not None:
        pass
    # 2 s standing still; a queued command is read on waking, then the tick.
    sim.command([80.0, 80.0, 120.0], 2.12)
    tick, _ = sim.step_due(2.12)
    assert (tick.event, tick.state) == ('timeout', simulator.HELD)
    assert sim.plant.velocity == (0.0,) * 3 and sim.timed_out
    # Counted as a timeout and as this process's own (a stall brake).
    assert (sim.timeouts, sim.stall_brakes) == (1, 1)
    # The controller's next command resumes from rest.
    sim.command([0.0, 0.0, 256.5315], 2.125)
    tick, _ = sim.step_due(2.126)
    assert tick.state == simulator.RUNNING and tick.event is None
