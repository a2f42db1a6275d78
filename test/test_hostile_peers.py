"""
Hostile peers and stalls: no other process may stop, starve or fool a node.

Over real DDS with the installed executables.

One test per attack of a hostile peer, each played by a client of this test
(or a child process of its own), never by the node's code; the cases
themselves are ``orthoglide_testing.hostile`` and
``orthoglide_testing.reliability`` functions that
``scripts/reliability_report.sh`` runs too:

1. a set-parameters request with a value type that does not exist;
2. huge but finite lengths, at run time and at start-up;
3. 4-18 MB messages on an input beside a legitimate 500 Hz stream;
4. a 2 s stall (SIGSTOP) of each process of the closed loop;
5. stamps whose nanosec is >= 1e9;
6. SIGINT and SIGTERM while a node starts, and as a pass ends;
7. long text inside messages, a flood of malformed ones;
8. a client that sends 100 requests and leaves; one whose reply reader can
   never match, which stays; stalls of a node while it answers;
9. the simulator at 10 kHz, commanded at 500 Hz;
10. the looping setpoint publisher's way back.
"""


import pytest

from node_checks import needs_scripts
from orthoglide_testing import netns

pytestmark = [pytest.mark.ros, needs_scripts()]

harness = pytest.importorskip('orthoglide_testing.hostile')
from orthoglide_testing import reliability  # noqa: E402


def test_malformed_parameter_request_is_refused_and_the_node_stays_up():
    for name, node in harness.malformed_parameters().items():
        assert node.answered and node.refused, (name, node)
        assert node.answers_after and node.alive, (name, node)
        assert node.code == 0, (name, node.stderr)
        assert 'Traceback' not in node.stderr, node.stderr


def test_absurd_lengths_refused_at_run_time_exit_2_at_start():
    result = harness.absurd_parameters()
    for name, changes in result.runtime.items():
        for key, (successful, reason) in changes.items():
            assert successful is False, (name, key, reason)
            assert reason, (name, key)
        assert result.alive[name], name
    for name, (code, stderr) in result.startup.items():
        assert code == 2, (name, code, stderr)
        assert 'robot.l3' in stderr and 'Traceback' not in stderr, stderr


def late(result):
    """Whether the attack made the stream more than 100 ms later."""
    return result['latency_during_max'] > \
        result['latency_outside_max'] + 0.1


ATTACKS_NEEDED = 4      # of the 8 the attacker's 2 s at 4 Hz would send


# serial: its verdict is a latency, and its attacker (normal scheduling)
# must send while real-time processes run.
@pytest.mark.serial
def test_big_messages_do_not_starve_a_stream_on_the_same_input():
    result = reliability.big_messages()
    print(result)
    if late(result) or result['attacks'] < ATTACKS_NEEDED:
        # A second pass when only the timing missed: on two busy cores a
        # spike of the machine (not of the node) can pass 100 ms once, and
        # the attacker, at normal scheduling, may send too few of its 3-16
        # MB messages to test anything (2 beside a parallel neighbour and
        # the pure set, a fresh clone, 2026-12-06).
        result = reliability.big_messages()
        print(result)
    assert result['crashes'] == 0 and result['internal_errors'] == 0
    assert result['attacks'] >= ATTACKS_NEEDED
    assert result['missing'] == 0 and result['duplicates'] == 0, result
    assert not late(result), result
    assert int(result['rejected'].get('rejected oversize', 0)) >= 2, result
    assert int(result['rejected'].get('rejected malformed', 0)) >= 2, result


# serial: the loop's stall verdicts failed beside a parallel neighbour (the
# ros set with -n 2, three runs, 2026-12-05); on plain settings alone too
# (robustness.md#stalls).
@pytest.mark.serial
def test_stalled_process_never_makes_the_loop_saturate_or_race():
    """
    A 2 s SIGSTOP of each process: no saturated command, no race.

    On the one-host profile in a network namespace where one can be made
    (root), elsewhere on plain settings: on shared memory a stop this long
    meets Fast DDS's port health check (robustness.md#stalls), a stall of
    the transport, not the loop's.
    """
    result = (harness.stall_resume() if netns.unavailable()
              else harness.stall_resume_one_host())
    print(result)
    assert all(result.alive.values()), result
    for name, stall in result.stalls.items():
        assert stall.commands > 0, (name, stall)
        assert stall.max_force < result.max_effort, (name, stall)
        assert stall.max_speed <= 2.0 * result.peak_speed, (name, stall)


def test_nanoseconds_beyond_a_second_are_rejected_on_every_input():
    result = harness.stamps()
    assert result.outputs == 0, result
    assert result.good == 2, result
    # Pose, twist and accel each, and three trajectory messages.
    assert result.rejected_stamp == 6, result
    assert result.alive


def test_signals_while_starting_exit_0_quietly():
    for tried in harness.startup_signals():
        assert tried.code == 0, tried
        assert harness.quiet(tried.stderr), tried


def test_text_from_messages_never_makes_long_or_many_log_lines():
    result = harness.log_amplification()
    for name, node in result.items():
        assert node.alive and node.code == 0, (name, node)
        assert node.longest <= harness.LOG_LINE_LIMIT, (name, node)
        assert node.lines <= 20, (name, node)
    assert int(result['feedforward'].counters['rejected frame']) == 1
    assert int(result['feedforward'].counters['rejected oversize']) == 1
    counters = result['tracking_controller'].counters
    assert int(counters['rejected measured oversize']) == 1, counters
    assert int(counters['rejected measured malformed']) >= 400, counters


# serial: its 0.2 s bound on an output gap failed beside a parallel
# neighbour (the ros set with -n 2, three runs, 2026-12-05); alone, none.
@pytest.mark.serial
def test_departed_clients_pause_no_output_stream():
    result = harness.departed_clients()
    print(result)
    if max(result.gaps.values()) > 0.2:
        # A second pass when only the timing missed (see above); one
        # 100 ms stall per departure can remain (doc/robustness.md). Gaps
        # that began while a child was joining the graph are reported
        # apart ('joining'): a participant joining can stall a node by
        # itself, without any request (doc/robustness.md).
        result = harness.departed_clients()
        print(result)
    assert all(result.alive.values()), result
    assert result.client_exits == [0, 0, 0], result
    for stream, gap in result.gaps.items():
        assert gap <= 0.2, (stream, gap)


def test_a_client_that_cannot_take_replies_costs_no_one_else_theirs():
    """
    A TRANSIENT_LOCAL client stays; three fresh ones are all answered.

    Its own requests are carried out (rclpy answers after the work) but
    their replies dropped at once; every fresh client of the feedforward's
    ``~/change_state`` and the simulator's ``~/set_parameters`` gets its
    reply, and after 150 ms stalls of the feedforward while it answered,
    the same client and a fresh process are answered every time.
    """
    result = harness.isolated_clients()
    print(result)
    assert all(result.alive.values()), result
    assert all(result.carried_out.values()), result
    assert result.answered == dict.fromkeys(result.answered, result.fresh), \
        result
    assert result.after_stalls == {'same client': result.stalls,
                                   'fresh process': result.stalls}, result
    assert result.dropped['feedforward'] >= 1, result


# serial: the simulator at 10 kHz takes a core at real-time priority, and
# its verdict counts brakes, which a neighbour's real-time work can cause.
@pytest.mark.serial
def test_simulator_at_10_khz_keeps_taking_commands_and_says_it_is_slow():
    """
    Steps it cannot keep up with never stop its commands, and it says so.

    The behaviour: no spurious timeout brake (one brake, after the last
    command, besides those of the simulator's own stalls longer than its
    command timeout, a drive's brake on a stalled cycle that a loaded
    machine can cause, and those of the sender's stalls), so commands kept
    coming in while the steps ran late, and a WARN whenever real time is
    not kept. How many of the 1,600 commands one run takes is a figure of
    the machine's load (1557 with one core busy):
    ``scripts/reliability_report.sh`` prints it.
    """
    result = harness.fast_simulator()
    print(result)
    assert result.alive
    assert result.received > 0, result
    assert result.stall_brakes >= 0, result
    # The brake at the end, and one after each stall of its own; one more
    # at most for each of the sender's.
    least = 1 + result.stall_brakes
    assert least <= result.timeouts <= least + result.sender_stalls, result
    # Every run: real time kept, or a WARN that says it is not.
    slow = result.step_rate < 0.9 * 10000.0
    assert not slow or (result.level == 1 and 'slower than real time'
                        in result.message), result


def test_looping_setpoints_go_back_smoothly():
    result = harness.setpoint_loop()
    print(result)
    assert result.passes >= 2, result
    assert result.jump_p <= result.jump_p_bound, result
    assert result.jump_v <= result.jump_v_bound, result


# serial: beside a parallel neighbour and the pure set (load 4-7), 2 of 585
# commands reached the effort limit (a fresh clone, 2026-12-06); alone,
# none in the runs of that day.
@pytest.mark.serial
def test_a_trajectory_flood_never_saturates_and_a_normal_one_follows():
    """
    A new joint trajectory every millisecond to the controller.

    Alternating targets 0 and 10 mm, 50 ms ahead, with the simulator as
    plant: the controller keeps commanding, at least a quarter as often
    as after the flood in the same run (a starved one falls near zero;
    the flood's own cost slows it on a loaded machine: 0.52-0.99 at load
    5.5, where a count of 500 commands failed with 480, 2026-12-06),
    no command at the effort limit, no slider faster than 0.5 m/s, and
    the normal trajectory sent afterwards brings the robot home (within
    6.5 s: its 1 s and the settling a loaded machine needs; 1.3 mm off
    after 1.5 s at load 5.5, 2026-12-06).
    """
    result = harness.trajectory_flood()
    assert result.alive and result.sent > 1000, result
    assert result.pace >= 0.25 and result.saturated == 0, result
    assert result.max_speed <= 0.5, result
    assert result.mode == 'following' and result.final_error < 1e-3, result


def test_absurd_finite_values_are_refused_by_reason_never_published():
    """
    1e200 m/s^2, 1e300 N and m/s, a spoofed 5 m.

    The feedforward publishes no joint state and no joint trajectory for
    them, the controller no command; each is counted under its reason.
    """
    result = harness.absurd_values()
    assert result.alive, result
    assert result.feedforward_outputs == 0 and result.commands == 0, result
    assert result.feedforward_rejected == {
        'rejected acceleration_limit': 1,
        'rejected trajectory acceleration_limit': 1}, result
    assert result.controller_rejected == {
        'rejected measured position_limit': 1,
        'rejected measured velocity_limit': 1,
        'rejected desired effort_limit': 1,
        'rejected trajectory effort_limit': 1}, result
