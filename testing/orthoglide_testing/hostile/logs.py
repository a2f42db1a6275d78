"""
Hostile peers against the nodes' logs: floods of refusals, forged lines.

A client that asks for a lifecycle transition the node's state does not
offer as fast as it is answered, one that calls the simulator's
``~/reset`` as fast, and peer text holding line breaks and control
characters (a transition label, a parameter value, a frame id). Each case
starts the node from its console script, plays the client from this
process (:class:`Peer`), stops the node and reads its standard error.
"""

from dataclasses import dataclass
import re
import threading
import time

from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import MultiDOFJointTrajectory

from orthoglide_testing.hostile.peer import (
    diagnostic_counter, handshake, HarnessError, home_setpoint, log_lines,
    Nodes, Peer, START_TIMEOUT, wait_running)

# A log line as rcutils prints it: severity, time, logger, message.
LOG_LINE = re.compile(r'^\[(DEBUG|INFO|WARN|ERROR|FATAL)\] \[\d+\.\d+\] '
                      r'\[[\w.]+\]: ')
# Peer text that forges a line of its own: a FATAL line, a cleared screen.
FORGERY = ('x\n[FATAL] [1796000000.000000000] [feedforward]: FORGED\r'
           '\x1b[2J\u2028[ERROR] FORGED\u202e')
CALL_TIMEOUT = 5.0   # s for one answer
# Answers a hammering client gets per second of its run (one second more
# than it lasted): ten per log line the node may write. A client slowed by
# a busy host hammers on until it has them, at most HAMMER_LIMIT s.
ANSWERS_PER_SECOND = 10
HAMMER_LIMIT = 60.0


@dataclass
class Hammered:
    """What a client hammering one service saw, and what the node logged."""

    seconds: float      # from the first request sent to the last answer
    sent: int           # requests sent (the last one included)
    answered: int       # requests answered
    refused: int        # of them, success false
    lines: int          # log lines of the hammered reason
    left_out: int       # what those lines said they left out
    after: bool         # the last request (one that must succeed) did
    code: int
    stderr: str


@dataclass
class Forged:
    """:func:`forged_text`: every line of the nodes' logs, and the bad ones."""

    refused: bool       # the forged label was refused
    lines: list         # every log line of the nodes
    not_log_lines: list     # lines that are no rcutils line (forged)
    control: list       # lines holding a control character
    codes: dict


def _call(client, request, timeout=CALL_TIMEOUT):
    """Call ``client``; return its answer, None after ``timeout`` s."""
    done = threading.Event()
    future = client.call_async(request)
    future.add_done_callback(lambda _: done.set())
    return future.result() if done.wait(timeout) else None


def _hammer(client, requests, seconds, last):
    """
    Send ``requests`` in turn for ``seconds`` at least, then ``last``.

    Each once the one before is answered (or CALL_TIMEOUT has passed): a
    client as fast as the node answers it. Past ``seconds`` it goes on
    until ANSWERS_PER_SECOND times (whole seconds so far + 2) are answered
    (one second to spare for ``last``), or HAMMER_LIMIT s have passed.
    Returns (the answers, None for each unanswered, the time from the
    first request to the last answer). The last answer is ``last``'s.
    """
    if not client.wait_for_service(timeout_sec=START_TIMEOUT):
        raise HarnessError(f'{client.srv_name} never came')
    answers = []
    answered = 0
    start = time.monotonic()
    while True:
        elapsed = time.monotonic() - start
        if elapsed >= HAMMER_LIMIT or elapsed >= seconds and (
                answered >= ANSWERS_PER_SECOND * (int(elapsed) + 2)):
            break
        answer = _call(client, requests[len(answers) % len(requests)])
        answers.append(answer)
        answered += answer is not None
    answers.append(_call(client, last))
    if not any(answers):
        raise HarnessError(f'no answer from {client.srv_name}')
    return answers, time.monotonic() - start


def _hammered(answers, seconds, marker, code, stderr):
    """Return :class:`Hammered`: the lines holding ``marker`` counted."""
    lines = [line for line in log_lines(stderr) if marker in line]
    answered = [a for a in answers if a is not None]
    return Hammered(
        seconds=seconds, sent=len(answers), answered=len(answered),
        refused=sum(not a.success for a in answered), lines=len(lines),
        left_out=sum(int(n) for line in lines for n in re.findall(
            r'\((\d+) more like it not logged in between\)', line)),
        after=answers[-1] is not None and answers[-1].success, code=code,
        stderr=stderr)


def _transition(label='', number=0):
    return ChangeState.Request(transition=Transition(id=number, label=label))


def refused_transitions(seconds=3.0):
    """
    Ask an active feedforward for unavailable transitions, hammering.

    For ``seconds`` or more (:func:`_hammer`), by label (``configure``,
    ``cleanup``: not offered when active) and by id, in turn, each
    answered before the next: one reason, "not available". Then a
    transition it offers (``deactivate``) must still succeed. Returns
    :class:`Hammered`; ``lines``: the WARN lines saying ``refused``.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward')
        wait_running(peer, ('feedforward',))
        client = peer.node.create_client(ChangeState,
                                         '/feedforward/change_state')
        answers, elapsed = _hammer(client, (
            _transition('configure'), _transition(number=Transition.
                                                  TRANSITION_CLEANUP),
            _transition('cleanup')), seconds, _transition('deactivate'))
        code, stderr = nodes.stop('feedforward')
    return _hammered(answers, elapsed, 'refused: not available', code,
                     stderr)


def resets(seconds=3.0):
    """
    Call the simulator's ``~/reset`` as fast as it answers.

    For ``seconds`` or more (:func:`_hammer`). Every call must still
    reset (success) and the last one too; returns :class:`Hammered` with
    the ``reset:`` lines of its log.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('simulator')
        wait_running(peer, ('simulator',))
        client = peer.node.create_client(Trigger, '/simulator/reset')
        answers, elapsed = _hammer(client, (Trigger.Request(),), seconds,
                                   Trigger.Request())
        code, stderr = nodes.stop('simulator')
    return _hammered(answers, elapsed, 'reset: ', code, stderr)


def forged_text(text=FORGERY):
    """
    Put ``text`` where a node logs a peer's string; read the logs.

    As a transition label (refused: not a transition), as the value of a
    parameter whose change is refused (``joint_names`` repeated) and as a
    trajectory's frame id (refused: not the base frame), to the
    feedforward. Returns :class:`Forged`: no line may be other than an
    rcutils log line, none may hold a control character.
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward')
        outputs = peer.record('feedforward/joint_states', JointState)
        setpoints = peer.publisher(MultiDOFJointTrajectory,
                                   'setpoint/trajectory')
        wait_running(peer, ('feedforward',))
        handshake(peer, lambda k: setpoints.publish(home_setpoint('', (1, k))),
                  lambda: outputs)
        client = peer.node.create_client(ChangeState,
                                         '/feedforward/change_state')
        if not client.wait_for_service(timeout_sec=START_TIMEOUT):
            raise HarnessError('/feedforward/change_state never came')
        answer = _call(client, _transition(text))
        refused = answer is not None and not answer.success
        peer.set_parameters('feedforward', {'joint_names': [text, text, 'c']})
        setpoints.publish(home_setpoint(text, (2, 0)))
        if not peer.wait(lambda: diagnostic_counter(peer, 'feedforward',
                                                    'rejected frame') >= 1,
                         START_TIMEOUT):
            raise HarnessError('the frame id never reached the node')
        codes = {'feedforward': nodes.stop('feedforward')}
    lines = [line for _, stderr in codes.values() for line in
             log_lines(stderr) if line != '[stdout]']
    return Forged(
        refused=refused, lines=lines,
        not_log_lines=[line for line in lines if not LOG_LINE.match(line)],
        control=[line for line in lines if not line.isprintable()],
        codes={name: code for name, (code, _) in codes.items()})
