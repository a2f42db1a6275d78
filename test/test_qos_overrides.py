"""
A QoS override of one topic changes that topic only, in this node only.

rclpy's QoS overriding writes the overridden policies into the QoSProfile
object it is given; the nodes must therefore give each entity a profile
of its own, or an override (``qos_overrides./feedforward/joint_states.
publisher.reliability: best_effort``) leaks into every topic created after
it, and into every later node of the process.
"""

import time

from geometry_msgs.msg import PoseStamped
import pytest
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy

from orthoglide_ros.ros.feedforward_node import FeedforwardNode
from orthoglide_ros.ros.setpoint_publisher_node import SetpointPublisher

pytestmark = pytest.mark.ros  # DDS and node processes

BEST_EFFORT, RELIABLE = ReliabilityPolicy.BEST_EFFORT, \
    ReliabilityPolicy.RELIABLE


def reliability(node, topic, kind):
    """Return the reliability of ``node``'s one publisher/subscription."""
    infos = (node.get_publishers_info_by_topic(topic) if kind == 'publisher'
             else node.get_subscriptions_info_by_topic(topic))
    mine = [i for i in infos if i.node_name == node.get_name()
            and i.node_namespace == node.get_namespace()]
    assert len(mine) == 1, (topic, infos)
    return mine[0].qos_profile.reliability


FEEDFORWARD_TOPICS = [
    ('feedforward/joint_states', 'publisher'),
    ('feedforward/forces', 'publisher'),
    ('feedforward/power', 'publisher'),
    ('setpoint/pose', 'subscription'),
    ('setpoint/twist', 'subscription'),
    ('setpoint/accel', 'subscription'),
    ('setpoint/trajectory', 'subscription'),
    ('cartesian_trajectory', 'subscription'),
    ('feedforward/joint_trajectory', 'publisher'),
]


@pytest.mark.parametrize('overridden', FEEDFORWARD_TOPICS,
                         ids=[t for t, _ in FEEDFORWARD_TOPICS])
def test_feedforward_override_stays_on_its_topic(ros_context, overridden):
    """Best effort on one topic; every other topic, and a later node: not."""
    topic, kind = overridden
    node = FeedforwardNode(context=ros_context, parameter_overrides=[
        Parameter(f'qos_overrides./{topic}.{kind}.reliability',
                  value='best_effort')])
    later = FeedforwardNode(context=ros_context, namespace='later')
    try:
        for other, other_kind in FEEDFORWARD_TOPICS:
            expected = BEST_EFFORT if other == topic else RELIABLE
            assert reliability(node, f'/{other}', other_kind) == expected, (
                other)
            assert reliability(later, f'/later/{other}', other_kind) == \
                RELIABLE, other
    finally:
        later.destroy_node()
        node.destroy_node()


def test_setpoint_publisher_override_stays_on_its_topic(ros_context):
    """The producer's pose publisher best effort; twist and accel not."""
    node = SetpointPublisher(context=ros_context, parameter_overrides=[
        Parameter('input', value='topics'),
        Parameter('qos_overrides./setpoint/pose.publisher.reliability',
                  value='best_effort')])
    try:
        assert reliability(node, '/setpoint/pose', 'publisher') == \
            BEST_EFFORT
        for topic in ('/setpoint/twist', '/setpoint/accel'):
            assert reliability(node, topic, 'publisher') == RELIABLE, topic
    finally:
        node.destroy_node()


def test_incompatible_publisher_warned_by_the_input_thread(ros_context,
                                                           capfd):
    """
    A best-effort publisher on a reliable input: the node says so.

    The inputs' QoS events are served by the node's input thread (not by
    an executor, see ``managed_node.ManagedNode.waitables``): rclpy's default
    handler logs the incompatible offer, here with no executor spinning.
    """
    node = FeedforwardNode(context=ros_context)
    other = Node('qos_offer', context=ros_context)
    try:
        other.create_publisher(PoseStamped, 'setpoint/pose', QoSProfile(
            depth=1, reliability=BEST_EFFORT))
        deadline = time.monotonic() + 10.0
        log = ''
        while 'incompatible QoS' not in log and time.monotonic() < deadline:
            time.sleep(0.1)
            log += capfd.readouterr().err
        assert 'incompatible QoS' in log and 'setpoint/pose' in log, log
    finally:
        other.destroy_node()
        node.destroy_node()
