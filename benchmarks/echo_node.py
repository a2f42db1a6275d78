#!/usr/bin/env python3
"""
Baseline for bench_node.py: a bare rclpy echo of the setpoint stamp.

Subscribes to the same input topic(s) as the ``feedforward`` node and
publishes one ``sensor_msgs/JointState`` on ``feedforward/joint_states``
carrying the setpoint's stamp, computing nothing (one message, built once,
reused). Trajectory input: stamp = header.stamp + time_from_start of the
first point. Three-topic input: one output per complete trio, when the
accel (sent last) arrives with the stamp of the pose and twist.

Executors: ``single`` is ``rclpy.spin`` (SingleThreadedExecutor);
``events`` runs the EventsExecutor as ``spin_once(timeout_sec=0.1)`` in a
loop, because its ``spin()`` (rclpy 7.1.6 wheels) polls without sleeping,
about half a core when idle, and ignores SIGINT and SIGTERM (the
feedforward node spins the same way).

Usage: python benchmarks/echo_node.py --input trajectory|topics
       [--executor single|events] [--qos reliable|best_effort]
"""

import argparse

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

from geometry_msgs.msg import AccelStamped, PoseStamped, TwistStamped
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import MultiDOFJointTrajectory


class Echo(Node):
    """Publish the setpoint's stamp on ``feedforward/joint_states``."""

    def __init__(self, kind, qos):
        super().__init__('echo')
        self._out = JointState(name=['q1', 'q2', 'q3'], position=[0.0] * 3,
                               velocity=[0.0] * 3, effort=[0.0] * 3)
        self._pub = self.create_publisher(
            JointState, 'feedforward/joint_states', qos)
        if kind == 'trajectory':
            self.create_subscription(MultiDOFJointTrajectory,
                                     'setpoint/trajectory',
                                     self._on_trajectory, qos)
        else:
            self._pose = self._twist = None
            self.create_subscription(PoseStamped, 'setpoint/pose',
                                     self._on_pose, qos)
            self.create_subscription(TwistStamped, 'setpoint/twist',
                                     self._on_twist, qos)
            self.create_subscription(AccelStamped, 'setpoint/accel',
                                     self._on_accel, qos)

    def _on_trajectory(self, msg):
        stamp, offset = msg.header.stamp, msg.points[0].time_from_start
        ns = stamp.nanosec + offset.nanosec
        out = self._out.header.stamp
        out.sec = stamp.sec + offset.sec + ns // 1000000000
        out.nanosec = ns % 1000000000
        self._pub.publish(self._out)

    def _on_pose(self, msg):
        self._pose = msg.header.stamp

    def _on_twist(self, msg):
        self._twist = msg.header.stamp

    def _on_accel(self, msg):
        stamp = msg.header.stamp
        if stamp == self._pose and stamp == self._twist:
            self._out.header.stamp = stamp
            self._pub.publish(self._out)


def main():
    """Spin the echo until SIGINT."""
    parser = argparse.ArgumentParser(
        description=__doc__.strip().split('\n')[0])
    parser.add_argument('--input', choices=('trajectory', 'topics'),
                        default='trajectory')
    parser.add_argument('--executor',
                        choices=('single', 'events'),
                        default='single')
    parser.add_argument('--qos', choices=('reliable', 'best_effort'),
                        default='reliable')
    args, ros_args = parser.parse_known_args()
    rclpy.init(args=ros_args)
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                     reliability=ReliabilityPolicy.RELIABLE
                     if args.qos == 'reliable'
                     else ReliabilityPolicy.BEST_EFFORT)
    node = Echo(args.input, qos)
    try:
        if args.executor == 'single':
            rclpy.spin(node)
        else:
            from rclpy.experimental import EventsExecutor
            executor = EventsExecutor()
            executor.add_node(node)
            while rclpy.ok():
                executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
