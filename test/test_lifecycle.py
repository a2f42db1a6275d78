"""
The managed lifecycle of ``feedforward`` and ``tracking_controller``.

Each node runs as a process (its console script) with ``autostart:=false``;
this test drives every transition through the standard
``~/change_state`` and ``~/get_state`` services (lifecycle_msgs), as
``ros2 lifecycle set`` or a lifecycle manager does, and watches the
node's topics and ``/diagnostics`` with a probe:

- unconfigured: nothing published but the diagnostics, which say so;
- configure: inputs read and counted, nothing published (inactive);
- activate: outputs; deactivate: none from the next input on, inputs
  still counted; the tracking controller holds and says so, and once
  active again commands that hold until a desired state starts where the
  robot is;
- cleanup: the inputs are gone from the graph; configure again works;
- shutdown: finalized;
- configure refused (invalid parameters): stays unconfigured, a one-line
  reason; an exception in configure (an invalid QoS override): the error
  state, then unconfigured, a one-line message, no traceback;
- autostart (the default): active at once, as ``ros2 run`` always was.
"""

import pytest
from rclpy.experimental import EventsExecutor

from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from orthoglide_testing.messages import diagnostic_values, stamp_of
from orthoglide_testing.probe import PROBE_QOS, Probe, spin_for, spin_until
from orthoglide_testing.processes import (node_executable,
                                          start_node_process, stop_process)
from orthoglide_ros.model.trajectory import paper_sample

pytestmark = pytest.mark.ros

WAIT = 15.0
T = Transition


class Lifecycle:
    """A node process, its lifecycle clients and a probe on one executor."""

    def __init__(self, context, name, *params):
        self.name = name
        self.stopped = None
        self.proc = start_node_process(
            ['--ros-args', *params], command=[node_executable(name)])
        self.probe = Probe(context)
        self.change = self.probe.create_client(ChangeState,
                                               f'/{name}/change_state')
        self.get = self.probe.create_client(GetState, f'/{name}/get_state')
        self.executor = EventsExecutor(context=context)
        self.executor.add_node(self.probe)
        assert spin_until(self.executor, lambda: (
            self.change.service_is_ready() and self.get.service_is_ready()),
            WAIT), f'{name} lifecycle services'
        # A node of the same name that left the graph moments ago (an
        # earlier test's) may still be listed: its services made the
        # clients ready, and a request sent now could miss this process.
        # Its diagnostics (published in every state) prove it is there.
        self.diagnostics()

    def call(self, client, request, attempts=1):
        """Call a service; ``attempts`` > 1 only for idempotent requests."""
        for _ in range(attempts):
            future = client.call_async(request)
            if spin_until(self.executor, future.done, WAIT / attempts):
                return future.result()
        raise AssertionError(f'no answer from {client.srv_name}')

    def state(self):
        """Return the node's state label (``~/get_state``, asked again)."""
        return self.call(self.get, GetState.Request(),
                         attempts=3).current_state.label

    def transition(self, transition_id):
        """Ask for a transition; return whether it succeeded."""
        request = ChangeState.Request()
        request.transition.id = transition_id
        return self.call(self.change, request).success

    def diagnostics(self, until=None):
        """
        Return the next /diagnostics of the node: its status and values.

        With ``until``, the next whose values satisfy it (a count the node
        may take a while to reach on a busy host).
        """
        index = len(self.probe.diagnostics)

        def matching(m):
            return m.status[0].name.startswith(self.name) and (
                until is None or until(diagnostic_values(m)))
        found = spin_until(self.executor, lambda: any(
            matching(m) for m in self.probe.diagnostics[index:]), WAIT)
        assert found, [diagnostic_values(m) for m in
                       self.probe.diagnostics[index:]][-1:]
        msg = next(m for m in self.probe.diagnostics[index:] if matching(m))
        return msg.status[0], diagnostic_values(msg)

    def close(self):
        """Stop the process (once); return its exit code and stderr."""
        if self.stopped is None:
            self.executor.shutdown()
            self.probe.destroy_node()
            self.stopped = stop_process(self.proc)
        return self.stopped


@pytest.fixture
def managed(ros_context):
    """Return make(name, *params): a Lifecycle, stopped afterwards."""
    made = []

    def make(name, *params):
        made.append(Lifecycle(ros_context, name, *params))
        return made[-1]
    yield make
    for lifecycle in made:
        code, stderr = lifecycle.close()
        assert code == 0, stderr
        assert 'Traceback' not in stderr, stderr


def stream(lc, first, seconds=0.3, rate=100.0):
    """Send setpoints ``first``, ``first`` + 1/rate, ...; return stamps."""
    stamps = []
    for k in range(round(seconds * rate)):
        t = first + k / rate
        stamps.append(stamp_of(t))
        lc.probe.send_trajectory(stamps[-1], *paper_sample(t % 2.0))
        spin_for(lc.executor, 1.0 / rate)
    return stamps


def test_feedforward_every_transition(managed):
    # An input deep enough for every setpoint sent, however late the node
    # reads them: all of them are counted.
    lc = managed('feedforward', '-p', 'autostart:=false', '-p',
                 'qos_overrides./setpoint/trajectory.subscription.depth:=1000')
    probe = lc.probe
    assert lc.state() == 'unconfigured'
    status, values = lc.diagnostics()
    assert values['lifecycle state'] == 'unconfigured'
    assert status.message.startswith('unconfigured')
    assert probe.count_publishers('feedforward/joint_states') == 0

    assert lc.transition(T.TRANSITION_CONFIGURE)
    assert lc.state() == 'inactive'
    assert spin_until(lc.executor, lambda: probe.matched(), WAIT)
    stream(lc, 0.0)
    status, values = lc.diagnostics()
    assert values['lifecycle state'] == 'inactive'
    assert int(values['received trajectory']) > 0
    assert int(values['outputs withheld (inactive)']) > 0
    assert probe.joint_states == []

    assert lc.transition(T.TRANSITION_ACTIVATE)
    assert lc.state() == 'active'
    sent = stream(lc, 1.0)
    assert spin_until(lc.executor, lambda: sent[-1] in probe.output_stamps(),
                      WAIT)
    assert lc.diagnostics()[1]['lifecycle state'] == 'active'

    assert lc.transition(T.TRANSITION_DEACTIVATE)
    after = stream(lc, 2.0)
    # Once the node has taken them all, and an output of any would have
    # come meanwhile:
    status, values = lc.diagnostics(
        lambda v: int(v['received trajectory']) >= 90)
    assert status.message.startswith('inactive'), status.message
    spin_for(lc.executor, 0.3)
    assert not set(after) & set(probe.output_stamps())

    assert lc.transition(T.TRANSITION_CLEANUP)
    assert lc.state() == 'unconfigured'
    assert spin_until(lc.executor, lambda: probe.count_subscribers(
        'setpoint/trajectory') == 0, WAIT), 'inputs left after cleanup'
    assert lc.transition(T.TRANSITION_CONFIGURE)
    assert lc.transition(T.TRANSITION_ACTIVATE)
    sent = stream(lc, 3.0)
    assert spin_until(lc.executor, lambda: sent[-1] in probe.output_stamps(),
                      WAIT), 'no output after cleanup and configure again'

    assert lc.transition(T.TRANSITION_ACTIVE_SHUTDOWN)
    assert lc.state() == 'finalized'
    # A transition the state does not offer is refused, not a defect.
    assert not lc.transition(T.TRANSITION_ACTIVATE)
    status, values = lc.diagnostics()
    assert status.message.startswith('finalized'), status.message
    assert values['internal errors'] == '0'


def test_configure_refused_or_failing_returns_to_unconfigured(managed):
    refused = managed('feedforward', '-p', 'autostart:=false',
                      '-p', 'setpoint_timeout:=0.01',
                      '-p', 'pairing_timeout:=0.05')
    assert not refused.transition(T.TRANSITION_CONFIGURE)
    assert refused.state() == 'unconfigured'
    failing = managed(
        'tracking_controller', '-p', 'autostart:=false', '-p',
        'qos_overrides./commands.publisher.reliability:=sometimes')
    assert not failing.transition(T.TRANSITION_CONFIGURE)
    assert failing.state() == 'unconfigured'
    refused_log, failing_log = refused.close()[1], failing.close()[1]
    assert 'configure refused: invalid parameters: pairing_timeout' \
        in refused_log, refused_log
    assert 'configure failed:' in failing_log, failing_log
    for log in (refused_log, failing_log):
        assert 'Traceback' not in log, log


def test_tracking_controller_holds_when_deactivated(managed):
    # The measurement stays fresh however late the desired state follows
    # it (this process and the node's are apart), and no input is lost:
    # every desired state sent while inactive is counted.
    deep = [arg for topic in ('/joint_states', '/feedforward/joint_states')
            for arg in ('-p', f'qos_overrides.{topic}.subscription.'
                        'depth:=1000')]
    lc = managed('tracking_controller', '-p', 'autostart:=false',
                 '-p', 'path_tolerance:=[0.01, 0.01, 0.01]',
                 '-p', 'measurement_timeout:=30.0', *deep)
    probe = lc.probe
    commands = []
    probe.create_subscription(Float64MultiArray, 'commands',
                              lambda m: commands.append(list(m.data)), 10)
    measured = probe.create_publisher(JointState, 'joint_states', PROBE_QOS)
    desired = probe.create_publisher(JointState, 'feedforward/joint_states',
                                     PROBE_QOS)
    names = ['slider_a', 'slider_b', 'slider_c']

    def send(position, effort=(10.0, 20.0, 30.0)):
        measured.publish(JointState(name=names, position=[0.0] * 3,
                                    velocity=[0.0] * 3))
        spin_for(lc.executor, 0.005)
        desired.publish(JointState(name=names, position=list(position),
                                   velocity=[0.0] * 3, effort=list(effort)))
        spin_for(lc.executor, 0.02)

    assert lc.transition(T.TRANSITION_CONFIGURE)
    assert lc.transition(T.TRANSITION_ACTIVATE)
    assert spin_until(lc.executor, lambda: measured.get_subscription_count()
                      and desired.get_subscription_count(), WAIT)
    for _ in range(20):
        send((0.0, 0.0, 0.0))
    assert spin_until(lc.executor, lambda: len(commands) >= 10, WAIT)
    assert lc.transition(T.TRANSITION_DEACTIVATE)
    spin_for(lc.executor, 0.2)
    count = len(commands)
    for _ in range(20):
        send((0.008, 0.0, 0.0))     # the stream moved on meanwhile
    # Once the node has taken them all, and a command for any would have
    # come meanwhile:
    status, values = lc.diagnostics(
        lambda v: int(v['skipped inactive']) >= 20)
    assert status.message.startswith('inactive'), status.message
    assert 'deactivated; holds lambda' in status.message
    spin_for(lc.executor, 0.3)
    assert len(commands) == count, 'commands while inactive'

    assert lc.transition(T.TRANSITION_ACTIVATE)
    for _ in range(10):
        send((0.008, 0.0, 0.0), effort=(99.0, 99.0, 99.0))
    assert spin_until(lc.executor, lambda: len(commands) >= count + 5, WAIT)
    # Holding its last safe command (the bias 10/20/30 N, at the measured
    # position), not chasing the desired state 8 mm away.
    assert commands[-1] == pytest.approx([10.0, 20.0, 30.0]), commands[-1]
    status, values = lc.diagnostics()
    assert values['mode'] == 'holding' and status.level == b'\x01', status
    for _ in range(10):
        send((0.0, 0.0, 0.0))       # starts where the robot is: re-arms
    lc.diagnostics(lambda v: v['mode'] == 'following')


def test_autostart_is_active_at_once(managed):
    lc = managed('feedforward')
    assert lc.state() == 'active'
    assert lc.diagnostics()[1]['lifecycle state'] == 'active'


def test_invalid_start_up_set_still_exits_2():
    proc = start_node_process(['--ros-args', '-p', 'setpoint_timeout:=0.01',
                               '-p', 'pairing_timeout:=0.05'],
                              command=[node_executable('feedforward')])
    proc.wait(WAIT)
    code, stderr = stop_process(proc)
    assert code == 2, stderr
    assert 'pairing_timeout' in stderr and 'Traceback' not in stderr
