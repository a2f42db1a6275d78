"""
Stale and missing input, over real DDS: doc/feedforward.md's rules hold.

The node (``FeedforwardNode``) and a probe
(:class:`orthoglide_testing.probe.Probe`) share one rclpy context and one
EventsExecutor; the probe is also the producer. A producer streams at about 250
Hz and stops: with ``rate_hz > 0`` the outputs stop within ``setpoint_timeout``
(plus one tick and the delivery slack) of the last setpoint's arrival and the
``/diagnostics`` computed past it say ``stale`` (WARN); the producer comes
back: the first output carries the first fresh setpoint's stamp and the
diagnostics return to OK. With ``rate_hz`` 0 only the diagnostics change. A
setpoint missing its twist or accel, or whose accel comes later than
``pairing_timeout``, gives no output and is counted ``unpaired``; with
``pose_only`` a pose alone is served.

Times are the node's and the probe's ``time.monotonic()`` (one process).
"""

import time
from types import SimpleNamespace

import pytest
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter

from diagnostic_msgs.msg import DiagnosticStatus

from orthoglide_ros.model import mechanics
from orthoglide_ros.ros.feedforward_node import FeedforwardNode
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.trajectory import paper_sample

from orthoglide_testing.messages import (diagnostic_values, header_stamp,
                                         stamp_of)
from orthoglide_testing.probe import paced, Probe, spin_for, spin_until

pytestmark = pytest.mark.ros  # DDS and node processes

WAIT = 15.0         # s for anything to arrive: generous, the machine is shared
PRODUCER_HZ = 250.0
STREAM = 1.0        # s of streaming before the producer stops
SLACK = 0.5         # s: delivery of an output and scheduling, on a busy host
ZERO = (0.0, 0.0, 0.0)


@pytest.fixture
def graph(ros_context):
    """Return make(params): node and probe on one executor, matched."""
    made = []

    def make(params):
        node = FeedforwardNode(context=ros_context, parameter_overrides=[
            Parameter(k, value=v) for k, v in params.items()])
        probe = Probe(ros_context)
        executor = EventsExecutor(context=ros_context)
        made.append((executor, node, probe))
        executor.add_node(node)
        executor.add_node(probe)
        assert spin_until(executor, lambda: probe.matched(node), WAIT), (
            'probe and node did not match')
        return SimpleNamespace(node=node, probe=probe, executor=executor,
                               core=node.core)

    yield make
    for executor, node, probe in made:
        executor.shutdown()
        probe.destroy_node()
        node.destroy_node()


def sample(t):
    """Return the setpoint of time t (s): eq. (6), a slow loop, periodic."""
    return paper_sample(t % 6.0)


def solve(t):
    """Return mechanics.solve of the setpoint of time t (paper robot)."""
    return mechanics.solve(Robot(), *sample(t))


def send(g, form, t):
    """Send the setpoint of time t, stamped stamp_of(t), in ``form``."""
    if form == 'trajectory':
        g.probe.send_trajectory(stamp_of(t), *sample(t))
    else:
        g.probe.send(stamp_of(t), *sample(t))


def stream(g, form, first_t, duration=STREAM, until=None, sent_at=None):
    """
    Publish setpoints at PRODUCER_HZ, spinning in between; return them.

    Setpoint k has t = first_t + k / PRODUCER_HZ. Stops after
    ``duration`` s, or (if given) once ``until()`` holds. Behind schedule
    it does not burst: one setpoint, then at least one spin. ``sent_at``
    (a list, optional) gets each setpoint's ``time.monotonic()``.
    """
    period = 1.0 / PRODUCER_HZ
    sent = []

    def publish():
        t = first_t + len(sent) * period
        send(g, form, t)
        sent.append(t)
        if sent_at is not None:
            sent_at.append(time.monotonic())
    paced(g.executor, PRODUCER_HZ, publish, duration, until, WAIT)
    return sent


def wait_diagnostics_after(g, index):
    """Spin until a /diagnostics message beyond ``index`` arrives; return it."""
    probe = g.probe
    assert spin_until(g.executor, lambda: len(probe.diagnostics) > index,
                      WAIT), 'no /diagnostics message'
    return probe.diagnostics[index]


def wait_stale_diagnostics(g, index, timeout):
    """
    Return the first /diagnostics message beyond ``index`` past the timeout.

    Computed more than ``timeout`` s after the last setpoint (its
    'time since last setpoint (s)'), spinning until one comes.
    """
    probe = g.probe

    def after(m):
        return float(diagnostic_values(m)['time since last setpoint (s)']) \
            > timeout

    assert spin_until(g.executor, lambda: any(
        after(m) for m in probe.diagnostics[index:]), WAIT), (
        'no /diagnostics message after the timeout')
    return next(m for m in probe.diagnostics[index:] if after(m))


def assert_output(g, k, t):
    """Check the k-th joint state and force against the setpoint of t."""
    joints = g.probe.joint_states[k]
    assert header_stamp(joints) == stamp_of(t)
    expected = solve(t)
    assert list(joints.position) == list(expected.lambda_)
    assert list(joints.effort) == list(expected.force)


@pytest.mark.parametrize('rate, form', [
    (100.0, 'trajectory'), (100.0, 'topics'), (0.0, 'trajectory')])
def test_producer_stops_then_comes_back(graph, rate, form):
    """Outputs stop after setpoint_timeout, diagnostics say stale; resume."""
    # Longer than this process (node and producer in one, normal
    # scheduling) is stalled on a busy host: at 0.2 s the last setpoint
    # went stale before the node's timer published it once (the last
    # output one setpoint short, a fresh clone's parallel phase, 2026-12-06).
    timeout = 1.0
    # A generous pairing window: with ``topics`` 250 setpoints' parts
    # meet in it, and a stall of this process must not leave one unpaired.
    g = graph({'rate_hz': rate, 'setpoint_timeout': timeout,
               'pairing_timeout': timeout})
    probe, core = g.probe, g.core
    sent = stream(g, form, 10.0)
    spin_until(g.executor, lambda: core.latest is not None
               and core.latest.stamp == stamp_of(sent[-1]), WAIT)
    assert core.latest.stamp == stamp_of(sent[-1])
    last_arrival = core.latest_arrival
    # Let the timeout run out, then note where the diagnostics stand.
    spin_for(g.executor, last_arrival + timeout + 0.1 - time.monotonic())
    index = len(probe.diagnostics)
    spin_for(g.executor, 0.5)
    n = len(probe.joint_states)
    stamps = probe.output_stamps()
    sent_stamps = [stamp_of(t) for t in sent]
    assert set(stamps) <= set(sent_stamps)
    assert stamps == sorted(stamps)     # never an older setpoint again
    assert stamps[-1] == sent_stamps[-1]
    if rate > 0.0:
        # The last result at the rate until the timeout, then nothing.
        assert stamps.count(sent_stamps[-1]) >= 3, stamps[-5:]
        assert probe.arrivals[-1] - last_arrival <= (
            timeout + 1.0 / rate + SLACK), (
            f'outputs went on {probe.arrivals[-1] - last_arrival:.3f} s '
            'after the last setpoint')
    else:
        # One output per setpoint taken, at once.
        assert len(set(stamps)) == n == core.computed
        assert probe.arrivals[-1] - last_arrival <= SLACK
    print(f'rate_hz {rate}, {form}: {len(sent)} setpoints streamed, '
          f'{core.computed} computed, {n} outputs; last output '
          f'{probe.arrivals[-1] - last_arrival:.3f} s after the last '
          'setpoint arrived')
    for k in range(0, n, max(1, n // 20)):
        t = sent[sent_stamps.index(stamps[k])]
        assert_output(g, k, t)
    # Stale: nothing more, and the diagnostics say so once the timeout has
    # run out (by the node's own clock: a status computed just before it,
    # but received late on a busy host, is not the one to judge).
    msg = wait_stale_diagnostics(g, index, timeout)
    status, values = msg.status[0], diagnostic_values(msg)
    assert status.level == DiagnosticStatus.WARN, status.message
    assert status.message.startswith('stale'), status.message
    assert values['stale'] == 'true'
    assert len(probe.joint_states) == n, 'outputs after setpoint_timeout'

    # The producer comes back: the first output is the first fresh setpoint.
    resume = 100.0
    send(g, form, resume)
    assert spin_until(g.executor, lambda: len(probe.joint_states) > n,
                      WAIT), 'no output after the producer came back'
    assert_output(g, n, resume)
    # Back to OK at the next diagnostics, unless this process (the
    # producer) itself fell silent longer than the timeout meanwhile.
    index = len(probe.diagnostics)
    sent_at = [time.monotonic()]
    stream(g, form, resume + 1.0, sent_at=sent_at, until=lambda: any(
        m.status[0].level == DiagnosticStatus.OK
        for m in probe.diagnostics[index:]))
    first = probe.diagnostics[index].status[0]
    if first.level != DiagnosticStatus.OK:
        silence = max(b - a for a, b in zip(sent_at, sent_at[1:]))
        assert first.message.startswith('stale') and silence > timeout, (
            f'{first.message} while the producer sent every '
            f'{silence:.3f} s or more often')
    msg = next(m for m in probe.diagnostics[index:]
               if m.status[0].level == DiagnosticStatus.OK)
    status, values = msg.status[0], diagnostic_values(msg)
    assert status.message == 'ok', status.message
    assert values['stale'] == 'false'
    assert not any(core.rejected.values()), core.rejected
    assert g.node.internal_errors == 0


def received(g, **counts):
    """Return a predicate: the node received at least these messages."""
    return lambda: all(g.core.received[k] >= v for k, v in counts.items())


@pytest.mark.parametrize('missing', ['twist', 'accel'])
def test_missing_part_unpaired_after_pairing_timeout(graph, missing):
    """Pose with only one of twist/accel: no output, unpaired after timeout."""
    pairing = 1.0
    g = graph({'setpoint_timeout': 2.0, 'pairing_timeout': pairing})
    probe, core = g.probe, g.core
    parts = tuple(p for p in ('pose', 'twist', 'accel') if p != missing)
    # Before sending: a lower bound of the arrival, however late this
    # process notices it.
    taken = time.monotonic()
    probe.send(stamp_of(1.0), *sample(1.0), order=parts)
    assert spin_until(g.executor, received(g, **dict.fromkeys(parts, 1)),
                      WAIT)
    assert core.pending == 1
    assert core.rejected['unpaired'] == 0
    # The diagnostics timer drops it once pairing_timeout has run out.
    assert spin_until(g.executor, lambda: core.rejected['unpaired'] == 1,
                      pairing + WAIT)
    assert time.monotonic() - taken >= pairing - 0.05
    assert core.pending == 0
    msg = wait_diagnostics_after(g, len(probe.diagnostics))
    values = diagnostic_values(msg)
    assert values['rejected unpaired'] == '1'
    assert values['pending partial setpoints'] == '0'
    assert probe.joint_states == []
    # The node goes on with the next complete setpoint.
    probe.send(stamp_of(2.0), *sample(2.0))
    assert spin_until(g.executor, lambda: probe.joint_states, WAIT)
    assert_output(g, 0, 2.0)
    spin_for(g.executor, 0.1)
    assert len(probe.joint_states) == 1
    assert core.rejected['unpaired'] == 1
    assert sum(core.rejected.values()) == 1


def test_late_accel_unpaired(graph):
    """An accel later than pairing_timeout after its pose: no output."""
    pairing = 0.3
    g = graph({'setpoint_timeout': 1.0, 'pairing_timeout': pairing})
    probe, core = g.probe, g.core
    probe.send(stamp_of(1.0), *sample(1.0), order=('pose', 'twist'))
    assert spin_until(g.executor, received(g, pose=1, twist=1), WAIT)
    spin_for(g.executor, pairing + 0.2)
    probe.send(stamp_of(1.0), *sample(1.0), order=('accel',))
    assert spin_until(g.executor, received(g, accel=1), WAIT)
    # The pose and twist are dropped (at the latest when the accel came);
    # the accel, alone with its stamp, waits and is dropped in turn.
    assert core.rejected['unpaired'] >= 1
    assert spin_until(g.executor, lambda: core.rejected['unpaired'] == 2,
                      pairing + WAIT)
    assert core.pending == 0
    spin_for(g.executor, 0.1)
    assert probe.joint_states == []
    assert core.computed == 0
    probe.send(stamp_of(2.0), *sample(2.0))
    assert spin_until(g.executor, lambda: probe.joint_states, WAIT)
    assert_output(g, 0, 2.0)
    assert core.rejected['unpaired'] == 2
    assert sum(core.rejected.values()) == 2


def test_newer_setpoint_drops_partial_at_once(graph):
    """A partial setpoint is dropped when a newer one completes."""
    g = graph({'setpoint_timeout': 20.0, 'pairing_timeout': 10.0})
    probe, core = g.probe, g.core
    probe.send(stamp_of(1.0), *sample(1.0), order=('pose', 'twist'))
    assert spin_until(g.executor, received(g, pose=1, twist=1), WAIT)
    assert core.pending == 1
    start = time.monotonic()
    probe.send(stamp_of(2.0), *sample(2.0))
    assert spin_until(g.executor, lambda: probe.joint_states, WAIT)
    assert time.monotonic() - start < 10.0
    assert_output(g, 0, 2.0)
    assert core.rejected['unpaired'] == 1
    assert core.pending == 0


def test_pose_only_serves_pose_alone(graph):
    """pose_only: a pose alone is a setpoint (zero rates); others ignored."""
    g = graph({'pose_only': True})
    probe, core = g.probe, g.core
    position = sample(1.0)[0]
    probe.send(stamp_of(1.0), position, order=('pose',))
    assert spin_until(g.executor, lambda: probe.joint_states, WAIT)
    joints = probe.joint_states[0]
    expected = mechanics.solve(Robot(), position, ZERO, ZERO)
    assert header_stamp(joints) == stamp_of(1.0)
    assert list(joints.position) == list(expected.lambda_)
    assert list(joints.velocity) == [0.0, 0.0, 0.0]
    assert list(joints.effort) == list(expected.force)
    # Twist and accel (of this stamp or another) change nothing.
    probe.send(stamp_of(1.0), *sample(1.0), order=('twist', 'accel'))
    probe.send(stamp_of(3.0), *sample(3.0), order=('accel', 'twist'))
    assert spin_until(g.executor, received(g, twist=2, accel=2), WAIT)
    spin_for(g.executor, 0.1)
    assert len(probe.joint_states) == 1
    assert core.pending == 0
    assert not any(core.rejected.values()), core.rejected
