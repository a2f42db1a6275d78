"""
The raw CDR reader reads what rclpy's deserializer reads.

Messages built with random contents (hypothesis) are serialized by rclpy
(the rmw's own encoding) and read back by ``orthoglide_ros.formats.cdr``; every
field the node uses must come back bit for bit.
"""

import math

from hypothesis import example, given, settings, strategies as st
from hypothesis_profiles import examples
import pytest

from orthoglide_ros.formats import cdr

pytest.importorskip('rclpy')
from geometry_msgs.msg import (AccelStamped, PoseStamped,  # noqa: E402
                               Transform, Twist, TwistStamped)
import numpy as np  # noqa: E402
from rclpy.serialization import (deserialize_message,  # noqa: E402
                                 serialize_message)
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import (Float64MultiArray,  # noqa: E402
                          MultiArrayDimension)
from trajectory_msgs.msg import (JointTrajectory,  # noqa: E402
                                 JointTrajectoryPoint,
                                 MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

floats = st.floats(allow_nan=True, allow_infinity=True, width=64)
stamps = st.tuples(st.integers(-2**31, 2**31 - 1), st.integers(0, 2**32 - 1))
# ROS strings are UTF-8 C strings: no NUL inside, no lone surrogates.
frames = st.text(st.characters(blacklist_characters='\x00',
                               blacklist_categories=('Cs',)), max_size=12)
vectors = st.tuples(floats, floats, floats)


def same(a, b):
    """Bitwise equality of float tuples, NaN included."""
    return len(a) == len(b) and all(
        x == y or (math.isnan(x) and math.isnan(y)) for x, y in zip(a, b))


def header(msg, stamp, frame):
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    return msg


@settings(max_examples=examples(200), deadline=None)
@given(stamps, frames, vectors, st.tuples(floats, floats, floats, floats))
def test_pose_stamped(stamp, frame, position, orientation):
    msg = header(PoseStamped(), stamp, frame)
    p, q = msg.pose.position, msg.pose.orientation
    p.x, p.y, p.z = position
    q.x, q.y, q.z, q.w = orientation
    got = cdr.pose_stamped(serialize_message(msg))
    assert got[:2] == (stamp, frame)
    assert same(got[2], position) and same(got[3], orientation)


@settings(max_examples=examples(200), deadline=None)
@given(stamps, frames, vectors, vectors, st.booleans())
def test_twist_and_accel_stamped(stamp, frame, linear, angular, is_twist):
    msg = header(TwistStamped() if is_twist else AccelStamped(), stamp, frame)
    body = msg.twist if is_twist else msg.accel
    body.linear.x, body.linear.y, body.linear.z = linear
    body.angular.x, body.angular.y, body.angular.z = angular
    got = cdr.vector3_stamped(serialize_message(msg))
    assert got[:2] == (stamp, frame) and same(got[2], linear)


def twist(linear):
    t = Twist()
    t.linear.x, t.linear.y, t.linear.z = linear
    t.angular.x = 7.0
    return t


@settings(max_examples=examples(300), deadline=None)
@given(stamps, frames, st.lists(frames, max_size=3),
       st.lists(st.tuples(
           st.lists(st.tuples(vectors, st.tuples(floats, floats, floats,
                                                 floats)), max_size=3),
           st.lists(vectors, max_size=2), st.lists(vectors, max_size=2),
           st.tuples(st.integers(-2**31, 2**31 - 1),
                     st.integers(0, 2**32 - 1))), max_size=3))
def test_trajectory_first_point(stamp, frame, names, points):
    msg = header(MultiDOFJointTrajectory(), stamp, frame)
    msg.joint_names = names
    for transforms, velocities, accelerations, offset in points:
        point = MultiDOFJointTrajectoryPoint()
        for translation, rotation in transforms:
            t = Transform()
            t.translation.x, t.translation.y, t.translation.z = translation
            t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w = rotation
            point.transforms.append(t)
        point.velocities = [twist(v) for v in velocities]
        point.accelerations = [twist(a) for a in accelerations]
        point.time_from_start.sec, point.time_from_start.nanosec = offset
        msg.points.append(point)
    got_stamp, got_frame, got = cdr.trajectory_point(serialize_message(msg))
    assert (got_stamp, got_frame) == (stamp, frame)
    if not points or not points[0][0]:
        assert got is None
        return
    transforms, velocities, accelerations, offset = points[0]
    translation, rotation, velocity, acceleration, duration = got
    assert same(translation, transforms[0][0])
    assert same(rotation, transforms[0][1])
    for read, sent in ((velocity, velocities), (acceleration, accelerations)):
        assert read is None if not sent else same(read, sent[0])
    assert duration == offset


@pytest.mark.parametrize('reader, msg', [
    (cdr.pose_stamped, PoseStamped()),
    (cdr.vector3_stamped, TwistStamped()),
    (cdr.trajectory_point, MultiDOFJointTrajectory(
        points=[MultiDOFJointTrajectoryPoint(transforms=[Transform()])])),
])
def test_unreadable_buffers_raise_cdr_error(reader, msg):
    """
    Truncated or foreign buffers raise CdrError, never a value.

    (The trajectory reader stops at the first point: what follows it is
    not read, so a cut there goes unnoticed; the tested message has one
    point.)
    """
    data = serialize_message(msg)
    for cut in range(len(data)):
        try:
            reader(data[:cut])
        except cdr.CdrError:
            continue
        pytest.fail(f'a buffer cut at {cut} of {len(data)} bytes was read')
    with pytest.raises(cdr.CdrError):
        reader(b'\x00\x00' + data[2:])       # big-endian encapsulation


names = st.lists(frames.filter(bool), max_size=6)
doubles = st.lists(floats, max_size=6)


@settings(max_examples=examples(200), deadline=None)
@given(stamps, frames, names, doubles, doubles, doubles)
def test_joint_state(stamp, frame, joint_names, position, velocity, effort):
    msg = header(JointState(), stamp, frame)
    msg.name = joint_names
    msg.position, msg.velocity, msg.effort = position, velocity, effort
    got = cdr.joint_state(serialize_message(msg))
    assert got[:3] == (stamp, frame, tuple(joint_names))
    for read, sent in zip(got[3:], (position, velocity, effort)):
        assert same(read, sent)


@settings(max_examples=examples(200), deadline=None)
@given(st.lists(st.tuples(frames, st.integers(0, 2**32 - 1),
                          st.integers(0, 2**32 - 1)), max_size=3),
       st.integers(0, 2**32 - 1), doubles)
def test_float64_array(dims, data_offset, data):
    msg = Float64MultiArray(data=data)
    msg.layout.dim = [MultiArrayDimension(label=label, size=size,
                                          stride=stride)
                      for label, size, stride in dims]
    msg.layout.data_offset = data_offset
    assert same(cdr.float64_array(serialize_message(msg)), data)


def test_too_many_joint_names_is_a_limit_not_a_decoding_failure():
    names = ['j'] * (cdr.MAX_JOINT_NAMES + 1)
    msg = MultiDOFJointTrajectory(joint_names=names)
    with pytest.raises(cdr.LimitError):
        cdr.trajectory_point(serialize_message(msg))
    msg.joint_names = msg.joint_names[:cdr.MAX_JOINT_NAMES]
    assert cdr.trajectory_point(serialize_message(msg))[2] is None


def _trajectory_point(draw_point):
    transforms, velocities, accelerations, time = draw_point
    point = MultiDOFJointTrajectoryPoint()
    made = []
    for pose in transforms:
        t = Transform()
        t.translation.x, t.translation.y, t.translation.z = pose[:3]
        r = t.rotation
        r.x, r.y, r.z, r.w = pose[3:]
        made.append(t)
    point.transforms = made
    for name, twists in (('velocities', velocities),
                         ('accelerations', accelerations)):
        items = []
        for linear in twists:
            twist = Twist()
            twist.linear.x, twist.linear.y, twist.linear.z = linear
            twist.angular.z = 7.0
            items.append(twist)
        setattr(point, name, items)
    point.time_from_start.sec, point.time_from_start.nanosec = time
    return point


poses = st.tuples(*[floats] * 7)
trajectory_points = st.tuples(
    st.lists(poses, max_size=2), st.lists(vectors, max_size=2),
    st.lists(vectors, max_size=2),
    st.tuples(st.integers(-2**31, 2**31 - 1), st.integers(0, 2**32 - 1)))
regular_points = st.tuples(
    st.lists(poses, min_size=1, max_size=1),
    st.lists(vectors, min_size=1, max_size=1),
    st.lists(vectors, min_size=1, max_size=1),
    st.tuples(st.integers(0, 9), st.integers(0, 10**9 - 1)))


@settings(max_examples=examples(150), deadline=None)
@given(stamps, frames, names, st.one_of(
    st.lists(trajectory_points, max_size=6),
    st.lists(regular_points, min_size=2, max_size=9)))
# Found by the fuzzer: one empty point, a message of five doubles; an
# absent item's offset must not be read, even masked out.
@example(stamp=(0, 0), frame='', joint_names=[], drawn=[([], [], [], (0, 0))])
def test_cartesian_trajectory_reads_every_point(stamp, frame, joint_names,
                                                drawn):
    """Irregular counts (walked) and regular ones (the numpy pass)."""
    msg = header(MultiDOFJointTrajectory(), stamp, frame)
    msg.joint_names = joint_names
    msg.points = [_trajectory_point(p) for p in drawn]
    got = cdr.cartesian_trajectory(serialize_message(msg))
    assert (got.stamp, got.frame) == (stamp, frame)
    assert len(got.time) == len(drawn)
    for k, (transforms, velocities, accelerations, time) in enumerate(drawn):
        assert got.transform[k] == bool(transforms)
        assert got.velocity[k] == bool(velocities)
        assert got.acceleration[k] == bool(accelerations)
        if transforms:
            assert same(tuple(got.position[k]), transforms[0][:3])
            assert same(tuple(got.orientation[k]), transforms[0][3:])
        if velocities:
            assert same(tuple(got.linear_velocity[k]), velocities[0])
        if accelerations:
            assert same(tuple(got.linear_acceleration[k]),
                        accelerations[0])
        assert tuple(got.time[k]) == time


@settings(max_examples=examples(100), deadline=None)
@given(stamps, frames, names.filter(bool), st.integers(0, 7), st.data())
def test_joint_trajectory_writes_what_rclpy_reads(stamp, frame, joint_names,
                                                  count, data):
    width = len(joint_names)
    arrays = [np.array(data.draw(st.lists(
        st.lists(floats, min_size=width, max_size=width),
        min_size=count, max_size=count))).reshape(count, width)
        for _ in range(4)]
    time = np.array(data.draw(st.lists(st.tuples(
        st.integers(-2**31, 2**31 - 1), st.integers(0, 2**32 - 1)),
        min_size=count, max_size=count))).reshape(count, 2)
    msg = deserialize_message(cdr.joint_trajectory(
        stamp, frame, joint_names, time, *arrays), JointTrajectory)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == stamp
    assert msg.header.frame_id == frame
    assert list(msg.joint_names) == joint_names
    assert len(msg.points) == count
    for k, point in enumerate(msg.points):
        for got, sent in zip((point.positions, point.velocities,
                              point.accelerations, point.effort), arrays):
            assert same(tuple(got), tuple(sent[k]))
        assert (point.time_from_start.sec,
                point.time_from_start.nanosec) == tuple(time[k])


@settings(max_examples=examples(100), deadline=None)
@given(stamps, frames, names, st.lists(st.tuples(
    *[st.lists(floats, max_size=4)] * 4,
    st.tuples(st.integers(-2**31, 2**31 - 1), st.integers(0, 2**32 - 1))),
    max_size=6))
def test_joint_trajectory_points_reads_what_rclpy_writes(
        stamp, frame, joint_names, drawn):
    msg = header(JointTrajectory(), stamp, frame)
    msg.joint_names = joint_names
    msg.points = []
    for positions, velocities, accelerations, effort, time in drawn:
        point = JointTrajectoryPoint(
            positions=positions, velocities=velocities,
            accelerations=accelerations, effort=effort)
        point.time_from_start.sec, point.time_from_start.nanosec = time
        msg.points.append(point)
    got = cdr.joint_trajectory_points(serialize_message(msg))
    assert (got.stamp, got.frame) == (stamp, frame)
    assert got.names == tuple(joint_names)
    width = len(joint_names)
    for k, (*arrays, time) in enumerate(drawn):
        assert tuple(got.time[k]) == time
        for field, (sent, read) in enumerate(zip(arrays, (
                got.positions, got.velocities, got.accelerations,
                got.efforts))):
            assert got.lengths[field, k] == len(sent)
            kept = min(width, len(sent))
            assert same(tuple(read[k, :kept]), tuple(sent[:kept]))
            assert np.isnan(read[k, kept:]).all()


def test_multi_dof_trajectory_reads_back_and_as_rclpy_reads_it():
    """The planner's writer: the fast reader and rclpy read the same."""
    rng = np.random.default_rng(3)
    n = 7
    p, v, a = (rng.normal(size=(n, 3)) for _ in range(3))
    times = np.column_stack((np.arange(n), rng.integers(0, 10**9, n)))
    data = cdr.multi_dof_trajectory((4, 5), 'base_link', ('platform',),
                                    times, p, v, a)
    read = cdr.cartesian_trajectory(data)
    assert read.frame == 'base_link' and tuple(read.stamp) == (4, 5)
    assert np.array_equal(read.position, p)
    assert np.array_equal(read.linear_velocity, v)
    assert np.array_equal(read.linear_acceleration, a)
    assert np.array_equal(read.time, times)
    message = deserialize_message(data, MultiDOFJointTrajectory)
    assert message.joint_names == ['platform']
    assert message.points[3].transforms[0].rotation.w == 1.0
    assert message.points[3].time_from_start.nanosec == times[3, 1]
