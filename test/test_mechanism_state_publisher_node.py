"""
Tests of the mechanism_state_publisher node over real DDS.

In-process: the node and a :class:`MechanismProbe` share one rclpy context
and one EventsExecutor; messages go through Fast DDS. The probe publishes
slider states (by name, shuffled, with an extra joint), and every
``mechanism/joint_states`` the node publishes is applied to the URDF loaded
by yourdfpy: ``platform`` at G (``mechanics.forward_kinematics`` of the
sliders) with frame 0's orientation, each ``x_leg_end`` on its
``x_platform_mount`` and each parallelogram's two A7 frames together, to
1e-9 m and 1e-9 rad, on random reachable configurations and on the paper's
trajectory. A node given a robot as built (``robots_as_built.BUILT`` as
``robot.*`` parameters) with that robot's URDF (``orthoglide urdf`` of the
same rows) puts every body where ``bodies.elements`` does, and closes
every cut, where the drawing's URDF would leave them open by about a
millimetre. Bad input publishes nothing and is counted in /diagnostics; the
topics' QoS is the other nodes'. As a process: the console script answers,
exits 0 on SIGINT and 2 on an invalid parameter.
"""

import random

from mechanics_reference import COMPLEX_STEP, leg_geometry, LEGS
import numpy as np
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.bodies import elements
from orthoglide_ros.model.urdf import link_name, urdf
from orthoglide_ros.ros.mechanism_state_publisher_node import (
    AS_BUILT, MechanismStatePublisherNode)
from orthoglide_ros.model.robot import Robot
import pytest
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import JointState

from node_checks import needs_scripts
from orthoglide_testing.probe import (matched, node_graphs, PROBE_QOS,
                                      spin_until,
                                      wait_diagnostics as harness_wait_diagnostics)
from orthoglide_testing.processes import node_executable, run_to_exit
from orthoglide_testing.robots_as_built import BUILT
from urdf_harness import COMMITTED_URDF, cut_errors, load, TOLERANCE

pytestmark = pytest.mark.ros  # DDS and node processes

WAIT = 10.0
START_WAIT = 40.0
NAMES = ['slider_a', 'slider_b', 'slider_c']
ROBOT = Robot()
EXECUTABLE = node_executable('mechanism_state_publisher')


class MechanismProbe(Node):
    """Publishes slider joint states; records the node's outputs."""

    def __init__(self, context, name='mechanism_probe'):
        super().__init__(name, context=context)
        self.pub = self.create_publisher(JointState, 'joint_states',
                                         PROBE_QOS)
        self.outputs = []
        self.diagnostics = []
        self.sub = self.create_subscription(
            JointState, 'mechanism/joint_states', self.outputs.append,
            PROBE_QOS)
        self.sub_diagnostics = self.create_subscription(
            DiagnosticArray, '/diagnostics', self.diagnostics.append,
            PROBE_QOS)

    def matched(self):
        """Whether the input and both outputs are matched."""
        return matched((self.pub,), (self.sub, self.sub_diagnostics))

    def send(self, stamp, lam, lamd=None, names=NAMES, extra=True):
        """Publish the sliders shuffled by name, with an extra joint."""
        rows = list(zip(names, lam, lamd if lamd is not None else lam))
        if extra:
            rows.append(('gripper', 7.0, 7.0))
        random.Random(stamp[1]).shuffle(rows)
        msg = JointState()
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
        msg.header.frame_id = 'base_link'
        msg.name = [r[0] for r in rows]
        msg.position = [float(r[1]) for r in rows]
        msg.velocity = [] if lamd is None else [float(r[2]) for r in rows]
        self.pub.publish(msg)


@pytest.fixture
def graph(ros_context):
    def ready(probe, node):
        return probe.matched() and all(
            p.get_subscription_count() > 0 for p in node.publishers
            if p.topic_name != '/parameter_events')
    with node_graphs(ros_context, MechanismStatePublisherNode,
                     MechanismProbe, ready, WAIT) as make:
        yield make


@pytest.fixture(scope='module')
def model():
    return load(COMMITTED_URDF.read_text())


def exchange(g, stamp, lam, lamd=None):
    """Send one state; return the node's answer (one message)."""
    count = len(g.probe.outputs)
    g.probe.send(stamp, lam, lamd)
    assert spin_until(g.executor, lambda: len(g.probe.outputs) > count,
                      WAIT), 'no mechanism/joint_states'
    return g.probe.outputs[-1]


def check_closes(model, msg, lam, with_velocity, robot=ROBOT):
    """Check that the published state closes every cut of the URDF at G."""
    centre = mechanics.forward_kinematics(robot, lam)
    phi32 = np.arcsin([leg_geometry(robot, leg, centre).sin32
                       for leg in LEGS])
    assert len(msg.name) == len(msg.position) == 18
    assert len(msg.velocity) == (18 if with_velocity else 0)
    distance, angle = cut_errors(model, msg.name, msg.position, centre,
                                 phi32)
    assert distance <= TOLERANCE and angle <= TOLERANCE, (distance, angle)
    sliders = dict(zip(msg.name, msg.position))
    assert [sliders[n] for n in NAMES] == list(lam)


def test_published_states_close_the_urdf(graph, model, capfd):
    """Random reachable configurations and the paper's trajectory."""
    g = graph()
    assert AS_BUILT not in capfd.readouterr().err     # the drawing's robot
    rng = np.random.default_rng(4)
    points = rng.uniform(-0.35, 0.35, (40, 3))
    points = points[mechanics.workspace_status(ROBOT, points).ok][:20]
    for k, p in enumerate(points):
        lam = mechanics.solve(ROBOT, p).lambda_
        msg = exchange(g, (100, k), lam)
        assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (100, k)
        assert msg.header.frame_id == 'base_link'
        check_closes(model, msg, lam, False)
    times = trajectory.paper_times(21)
    for k, (p, v, a) in enumerate(zip(*trajectory.paper_batch(times))):
        s = mechanics.solve(ROBOT, p, v, a)
        msg = exchange(g, (200, k), s.lambda_, s.lambdadot)
        check_closes(model, msg, s.lambda_, True)
        rates = dict(zip(msg.name, msg.velocity))
        assert [rates[n] for n in NAMES] == list(s.lambdadot)
        # The rates of eq. (9) by complex step along the velocity.
        step = np.asarray(p, complex) + 1j * COMPLEX_STEP * np.asarray(v)
        for leg in LEGS:
            geo = leg_geometry(ROBOT, leg, step)
            x = leg.lower()
            for name, value in ((f'{x}_phi21', geo.sin21),
                                (f'{x}_phi54', geo.sin21),
                                (f'{x}_phi32', geo.sin32),
                                (f'{x}_phi62', geo.sin32),
                                (f'{x}_phi43', geo.sin32)):
                assert rates[name] == pytest.approx(
                    np.arcsin(value).imag / COMPLEX_STEP, abs=1e-11)


@pytest.mark.slow     # its URDF: 6-9 s of CPU, one process, 2026-12-06
def test_a_robot_as_built_with_its_own_urdf(graph, model, capfd):
    """
    robot.* of a robot as built, and the URDF of the same rows.

    The node says at configure that it needs that URDF. Every body's TF
    (yourdfpy's forward kinematics of that URDF with the published
    joints) is where ``bodies.elements`` of the robot puts it; the
    drawing's URDF with the same joints leaves a cut open.
    """
    robot = Robot(**BUILT)
    g = graph({f'robot.{name}': list(value) for name, value in BUILT.items()})
    assert AS_BUILT in capfd.readouterr().err
    built_model = load(urdf(robot))
    rng = np.random.default_rng(6)
    points = rng.uniform(-0.35, 0.35, (40, 3))
    points = points[mechanics.workspace_status(robot, points).ok][:10]
    for k, p in enumerate(points):
        lam = mechanics.solve(robot, p).lambda_
        msg = exchange(g, (400, k), lam)
        check_closes(built_model, msg, lam, False, robot)
        legs = elements(robot, p)
        for leg in LEGS:
            for body, frame in legs[leg]['bodies'].items():
                tf = built_model.get_transform(link_name(leg, body))
                assert np.allclose(tf[:3, 3], frame['origin'], rtol=0,
                                   atol=1e-10)
                assert np.allclose(tf[:3, :3], frame['rotation'].T, rtol=0,
                                   atol=1e-10)
        distance, _ = cut_errors(model, msg.name, msg.position, p,
                                 np.zeros(3))
        assert distance > 1e-4, distance


@pytest.mark.parametrize('names, lam, reason', [
    (['slider_a', 'slider_b', 'other'], [0.0, 0.0, 0.0], 'missing_joint'),
    (NAMES, [0.0, float('nan'), 0.0], 'non_finite'),
    (NAMES, [1.7, 1.7, 1.7], 'unreachable'),
])
def test_bad_input_publishes_nothing_and_counts(graph, names, lam, reason):
    g = graph()
    g.probe.send((300, 1), lam, names=names, extra=False)
    msg = harness_wait_diagnostics(
        g.executor, g.probe.diagnostics,
        lambda values: values.get(f'rejected {reason}') == '1', WAIT)
    assert msg.status[0].level == b'\x01'       # WARN
    assert reason in msg.status[0].message
    assert not g.probe.outputs
    # The next good state is published again.
    exchange(g, (300, 2), [0.0, 0.0, 0.0])


def test_qos_is_reliable_volatile_keep_last_and_overridable(graph):
    g = graph()
    [info] = g.probe.get_publishers_info_by_topic('/mechanism/joint_states')
    assert info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
    assert info.qos_profile.durability == DurabilityPolicy.VOLATILE
    [subscription] = g.probe.get_subscriptions_info_by_topic('/joint_states')
    assert subscription.qos_profile.reliability == ReliabilityPolicy.RELIABLE


def test_qos_overrides(ros_context):
    node = MechanismStatePublisherNode(context=ros_context, parameter_overrides=[
        Parameter('qos_overrides./mechanism/joint_states.publisher.'
                  'reliability', value='best_effort'),
        Parameter('qos_overrides./mechanism/joint_states.publisher.depth',
                  value=3)])
    try:
        [publisher] = [p for p in node.publishers
                       if p.topic_name == '/mechanism/joint_states']
        assert publisher.qos_profile.reliability == \
            ReliabilityPolicy.BEST_EFFORT
        assert publisher.qos_profile.depth == 3
    finally:
        node.destroy_node()


needs_script = needs_scripts('mechanism_state_publisher')


@needs_script
def test_process_exits_2_on_invalid_parameter():
    code, stderr = run_to_exit(
        ['--ros-args', '-p', 'joint_names:=[a, a, b]'], [EXECUTABLE],
        START_WAIT)
    assert code == 2, f'exit code {code}; stderr:\n{stderr}'
    assert 'joint_names' in stderr and 'Traceback' not in stderr, stderr


@needs_script
def test_invalid_stamps_are_refused_counted_and_said():
    """
    A peer's stamps that are no ROS time publish nothing (real processes).

    nanosec 2e9, negative seconds and a "zero" second with nanosec 1e9
    are each refused as ``rejected stamp`` (WARN, the reason in the
    message); a zero stamp passes unchanged, as a valid one does.
    """
    from orthoglide_testing.hostile.streams import mechanism_stamps
    result = mechanism_stamps()
    assert result.alive, result
    assert result.bad_outputs == 0, result
    assert result.rejected_stamp == 4, result
    assert result.level == 1 and 'stamp' in result.message, result
    assert result.stamps_out == [(0, 0), (9, 5)], result
