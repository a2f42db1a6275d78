"""
Whole Cartesian trajectories through the installed ``feedforward``, over DDS.

A client here publishes trajectory_msgs/MultiDOFJointTrajectory on
``cartesian_trajectory`` and reads ``feedforward/joint_trajectory``: every
field of every point must equal ``mechanics.solve_batch`` (1, 2 and 5,000
points), the header and the times pass unchanged, the joint names are the
parameter's; a trajectory with any bad point, an empty one, or one beyond
the limits publishes nothing and is counted by reason.
"""


import numpy as np
import pytest

from orthoglide_testing.hostile import Nodes, Peer
from node_checks import needs_scripts
from orthoglide_testing.messages import cartesian_message
from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot

pytestmark = [pytest.mark.ros, needs_scripts()]

from trajectory_msgs.msg import (JointTrajectory,  # noqa: E402
                                 MultiDOFJointTrajectory)

NAMES = ['ax_a', 'ax_b', 'ax_c']
WAIT = 20.0


def cartesian(p, v, a, times, stamp=(41, 7), frame='base_link',
              rotation=None):
    """Build the message; ``rotation`` (k, (x, w)) turns point k."""
    rotations = None
    if rotation is not None:
        rotations = np.tile([0.0, 0.0, 0.0, 1.0], (len(p), 1))
        rotations[rotation[0], [0, 3]] = rotation[1]
    return cartesian_message(times, p, v, a, stamp, frame, rotations)


def paper(n):
    """Return the paper's trajectory in n points over 2 s, and the times."""
    t = trajectory.paper_times(max(n, 2))[:n] + 1e-9   # t = 0 allowed too
    p, v, a = trajectory.paper_batch(t)
    return p, v, a, t


HANDSHAKE = (1, 0)      # the stamp of the fixture's first trajectories


@pytest.fixture(scope='module')
def graph():
    """
    Run the installed feedforward: named joints, two limits.

    B's effort limit is 40 N (the paper's points need up to 35.9 N), C's
    velocity limit 0.25 m/s (they need up to 0.195 m/s).
    """
    with Nodes() as nodes, Peer() as peer:
        nodes.start('feedforward', '-p', f'joint_names:={NAMES}',
                    '-p', 'joint_limits.slider_b.max_effort:=40.0',
                    '-p', 'joint_limits.slider_c.has_velocity_limits:=true',
                    '-p', 'joint_limits.slider_c.max_velocity:=0.25')
        pub = peer.publisher(MultiDOFJointTrajectory, 'cartesian_trajectory')
        out = peer.record('feedforward/joint_trajectory', JointTrajectory,
                          depth=100)
        assert peer.wait(lambda: pub.get_subscription_count() > 0, WAIT)
        assert peer.wait(lambda: peer.node.count_publishers(
            'feedforward/joint_trajectory') > 0, WAIT)
        # Both sides of both topics matched: a good trajectory, sent until
        # its output comes back (the node's reader may see this writer
        # after this writer saw it, and drops what comes before).
        # Its stamp (1, 0) is no test's: send() keeps to its own output.
        p, v, a, times = paper(2)
        assert peer.wait(lambda: pub.publish(cartesian(
            p, v, a, times, stamp=HANDSHAKE)) or len(out) > 0, WAIT), \
            'no output to a handshake'
        yield peer, pub, out, nodes
        assert nodes.alive('feedforward')


def send(graph, msg, expect_output):
    """Publish ``msg``; return the JointTrajectory it gave (or None)."""
    peer, pub, out, _ = graph
    before, refused = len(out), rejections(peer)
    pub.publish(msg)

    def own():
        stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec)
        return [m for _, m in out[before:]
                if (m.header.stamp.sec, m.header.stamp.nanosec) == stamp]
    if expect_output:
        assert peer.wait(lambda: own(), WAIT), 'no output'
        return own()[0]
    # Refused: once the node has counted it, no output can follow.
    assert peer.wait(lambda: rejections(peer) > refused, WAIT), \
        'the refusal was not counted'
    assert not own(), 'a refused trajectory gave an output'
    return None


def rejections(peer):
    """Count the feedforward's refused trajectories (its diagnostics)."""
    with peer.lock:
        found = peer.diagnostics.get('feedforward')
    return sum(int(v) for k, v in (found[2] if found else {}).items()
               if k.startswith('rejected trajectory '))


@pytest.mark.parametrize('n', [1, 2, 5000])
def test_every_point_equals_solve_batch(graph, n):
    p, v, a, times = paper(n)
    got = send(graph, cartesian(p, v, a, times), True)
    s = mechanics.solve_batch(Robot(), p, v, a)
    assert (got.header.stamp.sec, got.header.stamp.nanosec) == (41, 7)
    assert got.header.frame_id == 'base_link'
    assert list(got.joint_names) == NAMES
    assert len(got.points) == n
    for k, point in enumerate(got.points):
        assert list(point.positions) == list(s.lambda_[k])
        assert list(point.velocities) == list(s.lambdadot[k])
        assert list(point.accelerations) == list(s.lambdaddot[k])
        assert list(point.effort) == list(s.force[k])
        assert (point.time_from_start.sec,
                point.time_from_start.nanosec) == divmod(
                    round(times[k] * 1e9), 10**9)


def test_zero_stamp_passes_unchanged(graph):
    p, v, a, times = paper(3)
    got = send(graph, cartesian(p, v, a, times, stamp=(0, 0)), True)
    assert (got.header.stamp.sec, got.header.stamp.nanosec) == (0, 0)


def test_bad_trajectories_publish_nothing_and_are_counted(graph):
    peer = graph[0]
    p, v, a, times = paper(20)
    late = times.copy()
    late[12] = late[11]
    far = p.copy()
    far[9] = (0.9, 0.0, 0.0)
    cases = {
        'empty': MultiDOFJointTrajectory(),
        'frame': cartesian(p, v, a, times, frame='world'),
        'stamp': cartesian(p, v, a, times, stamp=(5, 10**9)),
        'time': cartesian(p, v, a, late),
        'malformed': cartesian(p, None, a, times),
        'orientation': cartesian(p, v, a, times, rotation=(4, (0.1, 0.995))),
        'unreachable': cartesian(far, v, a, times),
        # Ten times the paper's accelerations need 50.6 N of B; twice its
        # velocities 0.39 m/s of C.
        'force_limit': cartesian(p, v, 10.0 * a, times),
        'velocity_limit': cartesian(p, 2.0 * v, a, times),
    }
    for reason, msg in cases.items():
        send(graph, msg, False)
    status = peer.status('feedforward', timeout=5.0)
    assert status is not None
    values = status[2]
    for reason in cases:
        key = f'rejected trajectory {reason}'
        assert values[key] == '1', (reason, values)
    assert int(values['trajectories converted']) >= 4


def test_node_goes_on_after_refusals(graph):
    p, v, a, times = paper(10)
    got = send(graph, cartesian(p, v, a, times), True)
    assert len(got.points) == 10
