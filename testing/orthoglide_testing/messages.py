"""
Messages the harnesses send: setpoints built once, trajectories, QoS.

:class:`Producer` publishes setpoints of one input form (one
MultiDOFJointTrajectory, or pose, twist and accel) with messages built
once, for floods and benchmarks; :func:`cartesian_message` builds a whole
Cartesian trajectory; :func:`trajectory_point` one point of one;
:func:`qos_profile` a keep-last profile; :func:`stamp_of` and
:func:`header_stamp` turn seconds and headers into ``(sec, nanosec)``.
"""

from geometry_msgs.msg import (AccelStamped, PoseStamped, Transform, Twist,
                               TwistStamped)
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from trajectory_msgs.msg import (MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from orthoglide_ros.model.mechanics import ZERO

IDENTITY = (0.0, 0.0, 0.0, 1.0)
INPUT_TOPICS = {'trajectory': ('trajectory',),
                'topics': ('pose', 'twist', 'accel')}


def stamp_of(seconds, base=(1000, 0)):
    """Return ``base`` + ``seconds`` as a (sec, nanosec) stamp."""
    total = base[0] * 10**9 + base[1] + round(seconds * 1e9)
    return divmod(total, 10**9)


def header_stamp(msg):
    """Return a message's header stamp as (sec, nanosec)."""
    return (msg.header.stamp.sec, msg.header.stamp.nanosec)


def diagnostic_values(msg):
    """Return ``{key: value}`` of the first status of a DiagnosticArray."""
    return {kv.key: kv.value for kv in msg.status[0].values}


# Traffic: setpoints built once, published fast ------------------------------
def qos_profile(name, depth=10):
    """Keep-last ``depth`` QoS, ``'reliable'`` or best effort."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE
                      if name == 'reliable'
                      else ReliabilityPolicy.BEST_EFFORT)


class Producer:
    """Publishers of one input form, with messages built once and reused."""

    def __init__(self, node, kind, qos):
        self.kind = kind
        profile = qos_profile(qos)
        if kind == 'trajectory':
            self.msg = MultiDOFJointTrajectory(
                joint_names=['G'], points=[MultiDOFJointTrajectoryPoint(
                    transforms=[Transform()], velocities=[Twist()],
                    accelerations=[Twist()])])
            self.pubs = [node.create_publisher(
                MultiDOFJointTrajectory, 'setpoint/trajectory', profile)]
            point = self.msg.points[0]
            self.vectors = (point.transforms[0].translation,
                            point.velocities[0].linear,
                            point.accelerations[0].linear)
            self.stamps = (self.msg.header.stamp,)
        else:
            self.msgs = (PoseStamped(), TwistStamped(), AccelStamped())
            self.pubs = [node.create_publisher(type(m), f'setpoint/{t}',
                                               profile)
                         for m, t in zip(self.msgs, INPUT_TOPICS[kind])]
            self.vectors = (self.msgs[0].pose.position,
                            self.msgs[1].twist.linear,
                            self.msgs[2].accel.linear)
            self.stamps = tuple(m.header.stamp for m in self.msgs)

    def matched(self):
        """Whether every input publisher has matched a subscription."""
        return all(p.get_subscription_count() > 0 for p in self.pubs)

    def fill(self, stamp_ns, sample):
        """Set the stamp and the (position, velocity, acceleration)."""
        sec, nanosec = divmod(stamp_ns, 1000000000)
        for stamp in self.stamps:
            stamp.sec, stamp.nanosec = sec, nanosec
        for vector, values in zip(self.vectors, sample):
            vector.x, vector.y, vector.z = values

    def publish(self):
        """Publish the setpoint (pose, twist, accel in that order)."""
        if self.kind == 'trajectory':
            self.pubs[0].publish(self.msg)
        else:
            for pub, msg in zip(self.pubs, self.msgs):
                pub.publish(msg)


def trajectory_point(position, velocity=ZERO, acceleration=ZERO,
                     orientation=IDENTITY, time_from_start=(0, 0),
                     with_transform=True):
    """
    Return one MultiDOFJointTrajectoryPoint of the platform centre.

    ``position`` (m), ``velocity`` (m/s), ``acceleration`` (m/s^2): a
    None leaves that list empty; ``orientation`` (x, y, z, w);
    ``time_from_start`` (sec, nanosec); ``with_transform`` false: no
    transform at all.
    """
    point = MultiDOFJointTrajectoryPoint()
    if with_transform:
        transform = Transform()
        t, q = transform.translation, transform.rotation
        t.x, t.y, t.z = (float(v) for v in position)
        q.x, q.y, q.z, q.w = (float(v) for v in orientation)
        point.transforms = [transform]
    for name, vector, field in (('velocities', velocity, 'linear'),
                                ('accelerations', acceleration, 'linear')):
        if vector is not None:
            twist = Twist()
            v = getattr(twist, field)
            v.x, v.y, v.z = (float(c) for c in vector)
            setattr(point, name, [twist])
    point.time_from_start.sec, point.time_from_start.nanosec = time_from_start
    return point


def cartesian_message(times, positions, velocities, accelerations, stamp,
                      frame='base_link', rotations=None):
    """
    Build a MultiDOFJointTrajectory of whole Cartesian trajectory points.

    ``times`` (N,) s from the start; ``positions``, ``velocities``,
    ``accelerations``: (N, 3) arrays (m, m/s, m/s^2), a None leaving that
    list empty in every point; ``stamp`` (sec, nanosec); ``rotations``:
    None (the identity) or (N, 4) quaternions (x, y, z, w).
    """
    msg = MultiDOFJointTrajectory(joint_names=['platform'])
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    msg.points = [trajectory_point(
        positions[k], None if velocities is None else velocities[k],
        None if accelerations is None else accelerations[k],
        IDENTITY if rotations is None else rotations[k],
        divmod(round(float(t) * 1e9), 10**9)) for k, t in enumerate(times)]
    return msg
