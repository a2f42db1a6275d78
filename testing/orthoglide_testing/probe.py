"""
A node in the test's or demo's own process: a probe of the feedforward.

- :class:`Probe`: publishes setpoints (pose/twist/accel or one trajectory
  point) and records every message on the feedforward's outputs and on
  ``/diagnostics``, with arrival times;
- :func:`spin_until`, :func:`spin_for`: spin an executor until a predicate
  holds or time runs out; :func:`wait_diagnostics`: until a diagnostics
  message matches;
- :func:`probed`: a probe on its own executor, ended afterwards (the
  process tests'); :func:`node_graphs`: a node under test and its probe
  on one executor, matched, destroyed afterwards (the in-process tests');
- :func:`call` and :func:`parameter_client`: services from a probe.
"""

from contextlib import contextmanager
import gc
import time
from types import SimpleNamespace

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import AccelStamped, PoseStamped, TwistStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import MultiDOFJointTrajectory

from orthoglide_testing.messages import (diagnostic_values,
                                         header_stamp, IDENTITY,
                                         trajectory_point, ZERO)

# Reliable like the node; deep, so that no output is lost while a test
# spins at its own pace.
PROBE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                       reliability=ReliabilityPolicy.RELIABLE)
OUTPUTS = ('joint_states', 'forces', 'power')


class Probe(Node):
    """
    Publishes setpoints to the feedforward node and records its outputs.

    ``joint_states``, ``forces``, ``power``, ``diagnostics``: every message
    received, in order; ``arrivals``: the monotonic time (s) each joint
    state arrived. ``forces_topic`` lets a test follow a remapped topic.
    """

    def __init__(self, context, name='feedforward_probe', namespace='',
                 forces_topic='feedforward/forces'):
        super().__init__(name, namespace=namespace, context=context)
        qos = PROBE_QOS
        self.publishers_by_input = {
            'pose': self.create_publisher(PoseStamped, 'setpoint/pose', qos),
            'twist': self.create_publisher(TwistStamped, 'setpoint/twist',
                                           qos),
            'accel': self.create_publisher(AccelStamped, 'setpoint/accel',
                                           qos),
            'trajectory': self.create_publisher(
                MultiDOFJointTrajectory, 'setpoint/trajectory', qos),
        }
        self.joint_states = []
        self.arrivals = []
        self.forces = []
        self.power = []
        self.diagnostics = []
        self.subscriptions_by_output = {
            'joint_states': self.create_subscription(
                JointState, 'feedforward/joint_states', self._on_joints, qos),
            'forces': self.create_subscription(
                Float64MultiArray, forces_topic, self.forces.append, qos),
            'power': self.create_subscription(
                Float64MultiArray, 'feedforward/power', self.power.append,
                qos),
            'diagnostics': self.create_subscription(
                DiagnosticArray, '/diagnostics', self.diagnostics.append,
                qos),
        }

    def _on_joints(self, msg):
        self.joint_states.append(msg)
        self.arrivals.append(time.monotonic())

    # Sending --------------------------------------------------------------
    def send(self, stamp, position, velocity=ZERO, acceleration=ZERO,
             frame='', orientation=IDENTITY, order=('pose', 'twist', 'accel')):
        """
        Publish one setpoint as pose, twist and accel (in ``order``).

        ``stamp`` is (sec, nanosec); ``order`` may leave parts out. The
        messages are built first and published back to back with the
        garbage collector off: a full collection of this test process
        (tens of ms) between two parts would make them arrive farther
        apart than ``pairing_timeout``, which the node rightly refuses.
        """
        messages = []
        for part in order:
            if part == 'pose':
                msg = PoseStamped()
                p, q = msg.pose.position, msg.pose.orientation
                p.x, p.y, p.z = (float(v) for v in position)
                q.x, q.y, q.z, q.w = (float(v) for v in orientation)
            elif part == 'twist':
                msg = TwistStamped()
                v = msg.twist.linear
                v.x, v.y, v.z = (float(c) for c in velocity)
            else:
                msg = AccelStamped()
                a = msg.accel.linear
                a.x, a.y, a.z = (float(c) for c in acceleration)
            msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
            msg.header.frame_id = frame
            messages.append((self.publishers_by_input[part], msg))
        gc.disable()
        try:
            for publisher, msg in messages:
                publisher.publish(msg)
        finally:
            gc.enable()

    def send_trajectory(self, stamp, position, velocity=ZERO,
                        acceleration=ZERO, frame='', orientation=IDENTITY,
                        time_from_start=(0, 0), extra_points=(),
                        with_point=True, with_transform=True):
        """
        Publish one MultiDOFJointTrajectory; its first point is the setpoint.

        ``stamp`` is the header stamp (sec, nanosec); the node adds
        ``time_from_start``. A None ``velocity`` or ``acceleration`` leaves
        that list empty. ``extra_points``: (position, velocity,
        acceleration) of further points, which the node must ignore.
        """
        msg = MultiDOFJointTrajectory()
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
        msg.header.frame_id = frame
        msg.joint_names = ['platform']
        if with_point:
            first = trajectory_point(position, velocity, acceleration,
                                     orientation, time_from_start,
                                     with_transform)
            msg.points = [first] + [
                trajectory_point(p, v, a, IDENTITY, time_from_start)
                for p, v, a in extra_points]
        self.publishers_by_input['trajectory'].publish(msg)

    # Reading --------------------------------------------------------------
    def clear(self):
        """Forget every message recorded so far."""
        for name in OUTPUTS + ('diagnostics', 'arrivals'):
            getattr(self, name).clear()

    def output_stamps(self):
        """Return the header stamps of the joint states received."""
        return [header_stamp(m) for m in self.joint_states]

    def matched(self, node=None):
        """
        Whether every input and output is matched with the node.

        ``node``, when the node runs in this process, also lets the node's
        own publishers on this probe's topics confirm that they match its
        subscriptions (``feedforward/joint_trajectory`` is not one).
        """
        if any(p.get_subscription_count() == 0
               for p in self.publishers_by_input.values()):
            return False
        if any(s.get_publisher_count() == 0
               for s in self.subscriptions_by_output.values()):
            return False
        if node is not None:
            topics = {s.topic_name
                      for s in self.subscriptions_by_output.values()}
            return all(p.get_subscription_count() > 0
                       for p in node.publishers if p.topic_name in topics)
        return True

    def handshake(self, executor, timeout=30.0, outputs=OUTPUTS):
        """
        Wait until the node answers; then forget the answers.

        For a node in another process, whose publishers cannot be asked:
        sends home setpoints on the trajectory input (stamps (1, k)) until
        every output in ``outputs`` has delivered a message. Returns the
        number of setpoints sent.
        """
        deadline = time.monotonic() + timeout
        assert spin_until(executor, self.matched, timeout), (
            'the node did not appear on the graph')
        sent = 0
        while not all(getattr(self, name) for name in outputs):
            assert time.monotonic() < deadline, (
                'the node did not answer: '
                + ', '.join(f'{n}: {len(getattr(self, n))}' for n in outputs))
            sent += 1
            self.send_trajectory((1, sent), ZERO)
            spin_until(executor, lambda: all(
                getattr(self, name) for name in outputs), 0.5)
        spin_until(executor, lambda: False, 0.1)    # drain stragglers
        self.clear()
        return sent


@contextmanager
def probed(context, **kwargs):
    """Yield ``(probe, executor)``: a :class:`Probe` (``kwargs``) spun alone."""
    probe = Probe(context, **kwargs)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(probe)
    try:
        yield probe, executor
    finally:
        executor.shutdown()
        probe.destroy_node()


def matched(publishers=(), subscriptions=()):
    """Whether each publisher has a subscription and each one a publisher."""
    return (all(p.get_subscription_count() > 0 for p in publishers)
            and all(s.get_publisher_count() > 0 for s in subscriptions))


def spin_until(executor, predicate, timeout):
    """Spin ``executor`` until ``predicate()`` holds; return whether it did."""
    deadline = time.monotonic() + timeout
    while not predicate():
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            return predicate()
        executor.spin_once(timeout_sec=min(0.05, remaining))
    return True


def paced(executor, rate, publish, duration=None, until=None, timeout=10.0,
          due=None):
    """
    Call ``publish()`` at ``rate`` Hz, spinning ``executor`` in between.

    For ``duration`` s, or (if given) until ``until()`` holds, a
    TimeoutError after ``timeout`` s. Behind schedule it does not burst:
    one call, then at least one spin. ``due``: when the first call is due
    (monotonic s, default now); returns when the next one is, for a
    caller that streams on.
    """
    period = 1.0 / rate
    start = time.monotonic()
    due = start if due is None else due
    while True:
        now = time.monotonic()
        if until is not None:
            if until():
                return due
            if now - start >= timeout:
                raise TimeoutError(f'streaming: not reached in {timeout:g} s')
        elif now - start >= duration:
            return due
        if now >= due:
            publish()
            due = max(due + period, now)
        executor.spin_once(timeout_sec=max(0.0, min(due - now, period)))


def wait_diagnostics(executor, messages, predicate, timeout):
    """
    Spin until a DiagnosticArray in ``messages`` satisfies ``predicate``.

    ``messages``: the list a probe appends to; ``predicate`` takes the
    first status's ``{key: value}``. Returns the first such message;
    fails the test (with the last values seen) when ``timeout`` s pass.
    """
    def found():
        return any(predicate(diagnostic_values(m)) for m in messages)
    ok = spin_until(executor, found, timeout)
    last = diagnostic_values(messages[-1]) if messages else None
    assert ok, f'no matching diagnostics; last: {last}'
    return next(m for m in messages if predicate(diagnostic_values(m)))


@contextmanager
def node_graphs(context, node_class, probe_class, ready, timeout):
    """
    Yield ``make(params=None, executor='events')`` for in-process tests.

    ``make`` builds ``node_class`` with ``params`` as parameter overrides
    and ``probe_class(context)``, adds both to an EventsExecutor (or a
    SingleThreadedExecutor for ``executor='single'``), spins until
    ``ready(probe, node)`` and returns ``SimpleNamespace(node, probe,
    executor)``. Everything made is shut down and destroyed on exit.
    """
    from rclpy.experimental import EventsExecutor
    made = []

    def make(params=None, executor='events'):
        overrides = [Parameter(k, value=v) for k, v in (params or {}).items()]
        node = node_class(context=context, parameter_overrides=overrides)
        probe = probe_class(context)
        spinner = (EventsExecutor if executor == 'events'
                   else SingleThreadedExecutor)(context=context)
        made.append((spinner, node, probe))
        spinner.add_node(node)
        spinner.add_node(probe)
        assert spin_until(spinner, lambda: ready(probe, node), timeout), (
            'probe and node did not match')
        return SimpleNamespace(node=node, probe=probe, executor=spinner)

    try:
        yield make
    finally:
        for spinner, node, probe in made:
            spinner.shutdown()
            probe.destroy_node()
            node.destroy_node()


def call(g, future, timeout=10.0):
    """Spin ``g.executor`` until a service future is done; return its result."""
    assert spin_until(g.executor, future.done, timeout), 'no service response'
    return future.result()


def parameter_client(g, node_name, timeout=10.0):
    """Return an AsyncParameterClient of ``node_name``, services ready."""
    client = AsyncParameterClient(g.probe, node_name)
    assert spin_until(g.executor, client.services_are_ready, timeout)
    return client


def spin_for(executor, seconds):
    """Spin ``executor`` for ``seconds``, whatever happens."""
    spin_until(executor, lambda: False, seconds)
