r"""
Hostile peers against the logs: refusals throttled, no line forged.

Over real DDS with the installed executables; the client is an rclpy node
of this process (:mod:`orthoglide_testing.hostile.logs`). The rules
of doc/robustness.md#logs:

1. one client asking for an unavailable lifecycle transition as fast as
   it is answered gets at most one WARN line a second (the seconds it
   lasted + 1), each saying how many it left out, and the node still
   changes state;
2. the simulator's ``~/reset`` called as fast: the same bound;
3. a transition label holding ``\n[FATAL] ...``: every line of the log
   is an rcutils line, none holds a control character, and the forged
   text is inside WARN lines only.
"""

import pytest

from node_checks import needs_scripts

pytestmark = [pytest.mark.ros, needs_scripts('feedforward', 'simulator')]

logs = pytest.importorskip('orthoglide_testing.hostile.logs')


def check_throttled(result):
    print({k: v for k, v in vars(result).items() if k != 'stderr'})
    assert result.code == 0, result.stderr
    # The client hammers on until it has these (logs._hammer): short of
    # them only if the node stopped answering for HAMMER_LIMIT.
    assert result.answered >= logs.ANSWERS_PER_SECOND * (
        int(result.seconds) + 1), result
    assert 1 <= result.lines <= int(result.seconds) + 1, result.stderr
    # What the lines say they left out: the rest, but for the requests
    # after the last line.
    assert result.lines + result.left_out <= result.sent
    assert result.left_out > 0, result.stderr
    assert result.after, 'the service no longer does its work'


def test_refused_transitions_are_logged_once_a_second():
    result = logs.refused_transitions(seconds=3.0)
    # Every request but the last (deactivate) refused.
    assert result.refused == result.answered - 1, result
    check_throttled(result)


def test_resets_are_logged_once_a_second():
    result = logs.resets(seconds=3.0)
    assert result.refused == 0, result
    check_throttled(result)


def test_peer_text_cannot_forge_a_log_line():
    result = logs.forged_text()
    assert result.refused
    assert result.codes == {'feedforward': 0}, result
    assert not result.not_log_lines, result.not_log_lines
    assert not result.control, result.control
    forged = [line for line in result.lines if 'FORGED' in line]
    # The label, the refused parameter value, the frame id: each quoted in
    # one WARN line.
    assert len(forged) >= 3, result.lines
    assert all(line.startswith('[WARN]') for line in forged), forged
