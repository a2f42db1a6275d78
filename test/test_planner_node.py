"""
The planner node over real DDS: a nav_msgs/Path in, the fastest motion out.

The installed ``planner`` and ``feedforward`` run as processes, on the
robot of doc/programs/drives.yaml without its friction (drives and a
payload) within the force limits 160, 250, 520 N. A circle of 400 poses
becomes a ``cartesian_trajectory`` within 60 um of the circle, within 5 %
of toppra's optimum on the exact circle (on its own fine grid), every
force within its limit; the feedforward converts it. An infeasible or
malformed path publishes nothing, is counted by reason, and the node goes
on: a pose 1e300 m away, a path of 10^5 poses with corners (beyond the
node's memory) and poses whose curve leaves the workspace too; a straight
path of 100 poses is planned.
"""

import math

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
import numpy as np
from planning_checks import toppra_duration
import pytest
from trajectory_msgs.msg import JointTrajectory, MultiDOFJointTrajectory

from orthoglide_testing.chord_programs import bulge_points
from orthoglide_testing.hostile import Nodes, Peer
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.planning import gcode
from orthoglide_ros.planning.limits import limits_from_mapping
from orthoglide_ros.planning.path import from_moves

pytestmark = pytest.mark.ros

WAIT = 30.0
ROBOT = Robot(armature=(3.2, 1.1, 0.45), payload=5.0)
EFFORTS = {'slider_a': 160.0, 'slider_b': 250.0, 'slider_c': 520.0}
RADIUS = 0.1
CENTRE = np.array([0.0, 0.05, -0.05])
ROBOT_ARGS = ('-p', 'robot.armature:=[3.2, 1.1, 0.45]',
              '-p', 'robot.payload:=5.0')


def circle(count=400):
    angles = np.linspace(0.0, 2.0 * math.pi, count)
    return CENTRE + RADIUS * np.stack((np.cos(angles), np.sin(angles),
                                       np.zeros(count)), 1)


def path_message(points, frame='base_link'):
    message = Path()
    message.header.frame_id = frame
    for point in points:
        pose = PoseStamped()
        pose.header.frame_id = frame
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = (
            float(c) for c in point)
        pose.pose.orientation.w = 1.0
        message.poses.append(pose)
    return message


def positions(message):
    return np.array([(p.transforms[0].translation.x,
                      p.transforms[0].translation.y,
                      p.transforms[0].translation.z) for p in message.points])


@pytest.fixture(scope='module')
def graph():
    limits = [arg for joint, value in EFFORTS.items() for arg in (
        '-p', f'joint_limits.{joint}.max_effort:={value}')]
    with Nodes() as nodes, Peer() as peer:
        nodes.start('planner', *ROBOT_ARGS, *limits)
        nodes.start('feedforward', *ROBOT_ARGS)
        pub = peer.publisher(Path, 'path')
        planned = peer.record('cartesian_trajectory',
                              MultiDOFJointTrajectory, depth=20)
        converted = peer.record('feedforward/joint_trajectory',
                                JointTrajectory, depth=20)
        assert peer.wait(lambda: pub.get_subscription_count() > 0, WAIT)
        assert peer.wait(lambda: peer.node.count_publishers(
            'cartesian_trajectory') > 0, WAIT)
        # Until both outputs have come here: each reader of this process
        # matches its writer on its own time.
        short = path_message([(0.0, 0.0, 0.0), (0.01, 0.0, 0.0)])
        assert peer.wait(lambda: pub.publish(short) or (
            len(planned) > 0 and len(converted) > 0), WAIT), \
            'no output to a handshake'
        yield peer, pub, planned, converted, nodes
        assert nodes.alive('planner') and nodes.alive('feedforward')


def send(graph, message):
    """
    Publish a path; return (the motion planned from it, its conversion).

    None where it was refused. The motion is the output that ends at the
    path's last pose (a handshake's late outputs are not); its conversion
    the JointTrajectory with as many points.
    """
    peer, pub, planned, converted, _ = graph
    last = message.poses[-1].pose.position
    end = np.array([last.x, last.y, last.z])
    before = len(planned)
    refused = counted(peer)

    def own():
        return [m for _, m in planned[before:]
                if np.allclose(positions(m)[-1], end, atol=1e-12)]
    pub.publish(message)
    peer.wait(lambda: own() or counted(peer) > refused, WAIT)
    if not own():
        return None
    motion = own()[0]

    def conversion():
        return [m for _, m in converted if len(m.points) == len(
            motion.points)]
    assert peer.wait(conversion, WAIT), 'the feedforward did not convert it'
    return motion, conversion()[-1]


def rejected(peer, reason):
    """Return the planner's rejections for ``reason``, by its diagnostics."""
    with peer.lock:
        found = peer.diagnostics.get('planner')
    return int((found[2] if found else {}).get(f'rejected {reason}', 0))


def counted(peer):
    """Return the planner's rejections so far, by its diagnostics."""
    with peer.lock:
        found = peer.diagnostics.get('planner')
    return sum(int(v) for k, v in (found[2] if found else {}).items()
               if k.startswith('rejected '))


def test_a_straight_path_of_100_poses_is_planned(graph):
    points = np.linspace((0.0, 0.0, 0.0), (0.07, -0.03, 0.05), 100)
    planned = send(graph, path_message(points))
    assert planned is not None
    assert np.allclose(positions(planned[0])[-1], points[-1], atol=1e-12)


def test_a_circle_of_400_poses_is_planned_near_its_optimum(graph):
    motion, joints = send(graph, path_message(circle()))
    points = positions(motion)
    offset = points - CENTRE
    radial = np.abs(np.hypot(offset[:, 0], offset[:, 1]) - RADIUS)
    assert max(radial.max(), np.abs(offset[:, 2]).max()) <= 60e-6
    last = motion.points[-1].time_from_start
    duration = last.sec + last.nanosec * 1e-9
    start = circle()[0]
    arc = from_moves(gcode.read_gcode(
        f'G21 F1000000\nG3 X{start[0] * 1e3:.9f} Y{start[1] * 1e3:.9f} '
        f'I{-RADIUS * 1e3:.9f} J0', start), 1e-5)
    limits = limits_from_mapping({j: {'max_effort': e}
                                  for j, e in EFFORTS.items()})
    optimum = toppra_duration(ROBOT, arc, limits, intervals=8000)
    assert optimum <= duration * 1.001 and duration <= 1.05 * optimum, (
        duration, optimum)
    velocities = np.array([(p.velocities[0].linear.x, p.velocities[0].linear.y,
                            p.velocities[0].linear.z) for p in motion.points])
    accelerations = np.array([
        (p.accelerations[0].linear.x, p.accelerations[0].linear.y,
         p.accelerations[0].linear.z) for p in motion.points])
    force = mechanics.solve_batch(ROBOT, points, velocities,
                                  accelerations).force
    assert (np.abs(force) <= np.array(list(EFFORTS.values())) * 1.001).all()
    assert np.allclose(velocities[[0, -1]], 0.0)
    assert len(joints.points) == len(motion.points)
    efforts = np.array([p.effort for p in joints.points])
    assert np.allclose(efforts, force, atol=1e-6)


@pytest.mark.parametrize('points, frame, reason', (
    (((0.0, 0.0, 0.0), (0.9, 0.0, 0.0)), 'base_link', 'infeasible'),
    (((0.0, 0.0, 0.0), (1e300, 0.0, 0.0)), 'base_link', 'infeasible'),
    # 10^5 poses with corners: beyond the node's memory, counted first.
    (np.random.default_rng(0).uniform(-0.1, 0.1, (100_000, 3)), 'base_link',
     'oversize'),
    (((0.0, 0.0, 0.0), (math.nan, 0.0, 0.0)), 'base_link', 'non_finite'),
    (((0.0, 0.0, 0.0), (0.01, 0.0, 0.0)), 'map', 'frame'),
    # Poses within the workspace, the curve through them not.
    (bulge_points(), 'base_link', 'infeasible'),
    (((0.0, 0.0, 0.0),), 'base_link', 'too_few_poses'),
))
def test_bad_paths_publish_nothing_and_the_node_goes_on(graph, points,
                                                        frame, reason):
    peer = graph[0]
    before = rejected(peer, reason)
    assert send(graph, path_message(points, frame)) is None
    assert peer.wait(lambda: rejected(peer, reason) > before, 5.0), reason
    assert send(graph, path_message([(0.0, 0.0, 0.0),
                                     (0.0, 0.02, 0.0)])) is not None
