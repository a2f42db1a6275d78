"""
The ``planner`` ROS 2 node: a nav_msgs/Path in, the fastest motion out.

A thin layer over :class:`orthoglide_ros.cores.planner.Planner`: it
declares the parameters of :data:`orthoglide_ros.cores.planner.PARAMETERS`,
reads each ``path`` (``nav_msgs/Path``, poses of G in ``base_link``,
untimed), hands its positions to the core and publishes the planned motion
on ``cartesian_trajectory`` (a ``trajectory_msgs/MultiDOFJointTrajectory``
of the body ``platform``: every point's position, velocity, acceleration
and time from the start, header stamp zero: start on reception), which the
feedforward turns into ``feedforward/joint_trajectory``. A refused path
publishes nothing; the reason is logged (throttled) and on
``/diagnostics``. A managed node (:mod:`orthoglide_ros.ros.managed_node`).
Run it with ``ros2 run orthoglide_ros planner``; ``doc/planner.md`` has the
topics, parameters and rules.
"""

import time

import numpy as np
from nav_msgs.msg import Path
from rclpy.serialization import deserialize_message
from trajectory_msgs.msg import MultiDOFJointTrajectory

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.planner import (MAX_POSES, PARAMETERS, PATH_BYTES,
                                          Planner)
from orthoglide_ros.formats import cdr
from orthoglide_ros.ros.managed_node import ManagedNode


def read_path(data):
    """Return a serialized Path's ``(frame, pose frames, positions)``."""
    try:
        message = deserialize_message(bytes(data), Path)
    except Exception as error:      # rclpy's RMWError: not a Path
        raise Rejected('malformed', 'a Path rclpy cannot read: '
                       + str(error).strip().split('\n')[0]) from None
    if len(message.poses) > MAX_POSES:
        raise Rejected('oversize', f'{len(message.poses)} poses: at most '
                       f'{MAX_POSES}')
    poses = message.poses
    positions = np.array([(p.pose.position.x, p.pose.position.y,
                           p.pose.position.z) for p in poses],
                         dtype=float).reshape(-1, 3)
    return (message.header.frame_id,
            tuple(p.header.frame_id for p in poses), positions)


class PlannerNode(ManagedNode):
    """
    Node ``planner``: the time-optimal motion along each path received.

    The input is read on the ``inputs`` thread; the planning runs there,
    with ``self.lock`` held (about a tenth of a second for 400 poses).
    """

    NAME = 'planner'
    TITLE = 'Orthoglide planner'
    PARAMETERS = PARAMETERS

    def build(self, settings):
        """Configure: the core, the output and the input."""
        self.core = Planner(settings, time.monotonic())
        self._publisher = self.create_output(MultiDOFJointTrajectory,
                                             'cartesian_trajectory')
        # Low rate and whole: rclpy's reader, named here (read_path).
        self.inputs.subscribe('path', Path, read_path, self.core.path,
                              self._publish, max_bytes=PATH_BYTES)

    def _publish(self, planned):
        """Publish one planned motion, serialized once."""
        frame, motion = planned
        ns = np.round(motion.t * 1e9).astype(np.int64)
        times = np.column_stack(divmod(ns, 1_000_000_000))
        self._publisher.publish(cdr.multi_dof_trajectory(
            (0, 0), frame, ('platform',), times, motion.position,
            motion.velocity, motion.acceleration))
