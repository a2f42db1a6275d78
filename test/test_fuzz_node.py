"""
Fuzzed messages into the feedforward node's raw callbacks, in-process.

The node (``FeedforwardNode``) and a :class:`orthoglide_testing.probe.Probe` share one
rclpy context and executor. Hypothesis builds PoseStamped, TwistStamped,
AccelStamped and MultiDOFJointTrajectory messages (stamps zero, negative,
repeated, near the int32 limit; frames base_link, empty or other;
orientations identity, -identity, just below and above 1e-3 rad, zero,
huge, tiny, NaN; positions, velocities and accelerations of
``fuzz_strategies``; empty points, transforms, velocities), serializes them
with rclpy, may cut them, overwrite a byte or replace them with random
bytes, and hands the bytes to the node's inputs exactly as DDS delivers
them (``node.inputs.deliver(input, data, arrival)``, as the input thread
does).

Properties: every callback returns None (nothing escapes), the node counts
no internal error, every output the probe receives is finite and equals
``mechanics.solve`` for its setpoint with the node's robot and margin, and
the node's ``received`` and ``rejected`` counters equal those of a small
model of doc/feedforward.md's rules (so every input is an output or counted in
exactly one rejection reason). Each example starts from no partial
setpoint; at its end the partials left are dropped (``expire`` with a
time far ahead: ``pairing_timeout`` is long here, so real time never
expires one) and counted ``unpaired`` by node and model alike.
"""

from collections import namedtuple
import math
import time
from types import SimpleNamespace

from hypothesis import given, HealthCheck, settings, strategies as st
from hypothesis_profiles import examples
import pytest
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rclpy.serialization import serialize_message

from geometry_msgs.msg import (AccelStamped, PoseStamped, Transform, Twist,
                               TwistStamped)
from trajectory_msgs.msg import (MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from orthoglide_ros.formats import cdr
from orthoglide_ros.model import mechanics
from orthoglide_ros.cores.feedforward import INPUTS
from orthoglide_ros.cores.parameters import joint_limit
from orthoglide_ros.cores.setpoint_rules import ORIENTATION_TOLERANCE
from orthoglide_ros.ros.feedforward_node import FeedforwardNode

from fuzz_strategies import any_float, inside, states
from orthoglide_testing.messages import header_stamp
from orthoglide_testing.probe import Probe, spin_until

pytestmark = pytest.mark.ros  # DDS and node processes

WAIT = 10.0     # s for outputs to arrive: generous, the machine is shared
BASE_FRAME = 'base_link'
ZERO = (0.0, 0.0, 0.0)
INT32_MAX = 2**31 - 1
MALFORMED = object()      # what a reader gives for an unreadable buffer
NOW = 'now'               # a trajectory header stamp of zero
# The setpoint inputs the model follows (a whole cartesian_trajectory's
# refusals are counted apart: test_trajectory_conversion).
SETPOINT_INPUTS = tuple(i for i in INPUTS if i != 'cartesian_trajectory')
BAD = 'bad'               # a trajectory stamp part with nanosec >= 1e9
Window = namedtuple('Window', 'low high')   # ns: where "now" + offset lies
L3 = 0.85                 # the node's robot here: the paper's
FUZZ = settings(deadline=None,
                suppress_health_check=[HealthCheck.too_slow,
                                       HealthCheck.data_too_large])


@pytest.fixture
def rig(ros_context):
    """Return the node, a probe and their executor, matched; clean up."""
    node = FeedforwardNode(context=ros_context, parameter_overrides=[
        Parameter('setpoint_timeout', value=3600.0),
        Parameter('pairing_timeout', value=600.0)])
    probe = Probe(ros_context)
    executor = EventsExecutor(context=ros_context)
    executor.add_node(node)
    executor.add_node(probe)
    try:
        assert spin_until(executor, lambda: probe.matched(node), WAIT), (
            'probe and node did not match')
        yield SimpleNamespace(node=node, probe=probe, executor=executor,
                              fresh=iter(range(100_000, 10**9)),
                              last_fresh=(99_999, 0))
    finally:
        executor.shutdown()
        probe.destroy_node()
        node.destroy_node()


# The model ---------------------------------------------------------------
class Model:
    """
    The rules of doc/feedforward.md, written again for the test (no timers).

    ``receive`` returns ``('output', stamp, (p, v, a))``, ``('rejected',
    reason)`` or None, and keeps counters like the node's.
    """

    def __init__(self, received, rejected, settings):
        self.received = dict(received)
        self.rejected = dict(rejected)
        self.settings = settings
        self.pending = {}

    def reject(self, reason):
        self.rejected[reason] += 1
        return ('rejected', reason)

    @staticmethod
    def bad_stamp(stamp):
        return (stamp[0] < 0 or stamp[0] > INT32_MAX or stamp == (0, 0)
                or not 0 <= stamp[1] < 10**9)

    def receive(self, source, fields):
        """Apply one read message (or MALFORMED) on input ``source``."""
        self.received[source] += 1
        if fields is MALFORMED:
            return self.reject('malformed')
        if source == 'trajectory':
            return self.trajectory(*fields)
        pose_only = self.settings.pose_only
        if source != 'pose' and pose_only:
            return None
        stamp = fields[0]
        if self.bad_stamp(stamp):
            return self.reject('stamp')
        if pose_only:
            _, frame, p, q = fields
            return self.complete(stamp, [frame], (p, ZERO, ZERO), q)
        slot = INPUTS.index(source)
        entry = self.pending.setdefault(stamp, [None, None, None])
        entry[slot] = fields
        if None in entry:
            return None
        del self.pending[stamp]
        older = [s for s in self.pending if s < stamp]
        for s in older:
            del self.pending[s]
        self.rejected['unpaired'] += len(older)
        (_, f1, p, q), (_, f2, v), (_, f3, a) = entry
        return self.complete(stamp, [f1, f2, f3], (p, v, a), q)

    def trajectory(self, stamp, frame, point):
        if point is None:
            return self.reject('malformed')
        p, q, v, a, _ = point
        if stamp is BAD or stamp is not NOW and self.bad_stamp(stamp):
            return self.reject('stamp')
        if v is None or a is None:
            if not self.settings.pose_only:
                return self.reject('malformed')
            v, a = v or ZERO, a or ZERO
        return self.complete(stamp, [frame], (p, v, a), q)

    def complete(self, stamp, frames, state, q):
        if any(f not in ('', self.settings.base_frame) for f in frames):
            return self.reject('frame')
        if not all(math.isfinite(c) for c in q):
            return self.reject('non_finite')
        if math.hypot(*q) == 0.0:
            return self.reject('orientation')
        angle = 2.0 * math.atan2(math.hypot(*q[:3]), abs(q[3]))
        if angle > ORIENTATION_TOLERANCE:
            return self.reject('orientation')
        settings = self.settings
        if all(math.isfinite(c) for part in state for c in part):
            for reason, vector, bound in (
                    ('speed_limit', state[1], settings.max_speed),
                    ('acceleration_limit', state[2],
                     settings.max_acceleration)):
                if math.hypot(*vector) > bound:
                    return self.reject(reason)
        try:
            solution = mechanics.solve(settings.robot, *state,
                                       settings.singularity_margin)
        except mechanics.WorkspaceError as error:
            return self.reject(error.reason)
        for reason, values, key in (
                ('velocity_limit', solution.lambdadot, 'max_velocity'),
                ('force_limit', solution.force, 'max_effort')):
            if any(abs(v) > limit for v, limit in zip(
                    values, joint_limit(settings, key))):
                return self.reject(reason)
        return ('output', stamp, solution)

    def flush(self):
        self.rejected['unpaired'] += len(self.pending)
        self.pending.clear()


# Messages ----------------------------------------------------------------
KINDS = {'pose': PoseStamped, 'twist': TwistStamped, 'accel': AccelStamped,
         'trajectory': MultiDOFJointTrajectory}
READERS = {'pose': cdr.pose_stamped, 'twist': cdr.vector3_stamped,
           'accel': cdr.vector3_stamped, 'trajectory': cdr.trajectory_point}


def read_like_node(source, data):
    """Read a (corrupted) buffer the node's way: the cdr reader, else bad."""
    try:
        return READERS[source](data)
    except Exception:
        return MALFORMED


def topic_message(part, stamp, frame, state, q):
    """Return the PoseStamped, TwistStamped or AccelStamped of a setpoint."""
    p, v, a = state
    msg = KINDS[part]()
    if part == 'pose':
        msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = p
        o = msg.pose.orientation
        o.x, o.y, o.z, o.w = q
    else:
        body = msg.twist if part == 'twist' else msg.accel
        body.linear.x, body.linear.y, body.linear.z = \
            v if part == 'twist' else a
        body.angular.x = 5.0    # ignored by the node
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    return msg


def twist_of(linear):
    t = Twist()
    t.linear.x, t.linear.y, t.linear.z = linear
    t.angular.z = -3.0          # ignored by the node
    return t


def trajectory_message(t):
    """Return the MultiDOFJointTrajectory of a drawn trajectory item."""
    msg = MultiDOFJointTrajectory()
    msg.header.stamp.sec, msg.header.stamp.nanosec = t.header
    msg.header.frame_id = t.frame
    msg.joint_names = t.names
    if not t.has_point:
        return msg
    p, v, a = t.state
    point = MultiDOFJointTrajectoryPoint()
    if t.has_transform:
        first = Transform()
        first.translation.x, first.translation.y, first.translation.z = p
        r = first.rotation
        r.x, r.y, r.z, r.w = t.orientation
        point.transforms = [first] + [Transform()] * t.extra
    if t.with_velocity:
        point.velocities = [twist_of(v)] + [twist_of(ZERO)] * t.extra
    if t.with_acceleration:
        point.accelerations = [twist_of(a)] + [twist_of(ZERO)] * t.extra
    point.time_from_start.sec, point.time_from_start.nanosec = t.offset
    later = MultiDOFJointTrajectoryPoint(transforms=[Transform()])
    msg.points = [point] + [later] * t.extra
    return msg


def trajectory_fields(t, header):
    """Return what the node reads from an intact trajectory message."""
    if not t.has_point or not t.has_transform:
        return (header, t.frame, None)
    p, v, a = t.state
    return (header, t.frame, (p, t.orientation,
                              v if t.with_velocity else None,
                              a if t.with_acceleration else None, t.offset))


def corrupt(data, how):
    """Apply a drawn corruption to serialized bytes."""
    if how is None:
        return data
    kind, where, extra = how
    if kind == 'cut':
        return data[:int(where * len(data))]
    if kind == 'flip':
        i = int(where * len(data))
        return data[:i] + bytes([extra[0] if extra else 0xff]) + data[i + 1:]
    return extra    # random bytes instead


# Strategies --------------------------------------------------------------
def _near_identity(angle, axis, sign, scale):
    n = math.hypot(*axis)
    if n == 0.0:
        axis, n = (1.0, 0.0, 0.0), 1.0
    s = math.sin(angle / 2.0) / n
    q = (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2.0))
    return tuple(c * sign * scale for c in q)


def mostly(common, rare, tenths=7):
    """Draw from ``common`` ``tenths`` times in ten, else from ``rare``."""
    return st.integers(0, 9).flatmap(
        lambda i: common if i < tenths else rare)


identity_like = st.builds(
    _near_identity,
    st.one_of(st.just(0.0), st.floats(0.0, 0.999e-3)),
    st.tuples(*[st.floats(-1.0, 1.0)] * 3), st.sampled_from([1.0, -1.0]),
    st.sampled_from([1.0, 1e-3, 1e3]))
orientations = mostly(identity_like, st.one_of(
    st.sampled_from([(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, -1.0),
                     (0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1e-300),
                     (1e-200, 0.0, 0.0, 1e-200), (1e200, 0.0, 0.0, 1.0),
                     (1e308, 1e308, 0.0, 1e308), (0.0, 0.0, 0.0, math.nan),
                     (math.inf, 0.0, 0.0, 1.0)]),
    st.builds(_near_identity,
              st.one_of(st.floats(0.0, 2e-3), st.floats(0.999e-3, 1.001e-3),
                        st.floats(0.0, math.pi)),
              st.tuples(*[st.floats(-1.0, 1.0)] * 3),
              st.sampled_from([1.0, -1.0]),
              st.sampled_from([1.0, 1e-3, 1e3, 1e-160])),
    st.tuples(any_float, any_float, any_float, any_float)))
frames = mostly(st.sampled_from(['', BASE_FRAME]), st.one_of(
    st.sampled_from(['world', 'base_link/', 'BASE_LINK', ' base_link']),
    st.text(st.characters(blacklist_categories=('Cs',),
                          blacklist_characters='\x00'), max_size=6)), 8)
# Nanoseconds of a stamp: mostly valid, now and then not (>= 1e9).
nanoseconds = mostly(st.integers(0, 10**9 - 1), st.integers(10**9,
                                                            2**32 - 1), 8)
# ('fresh', nanosec): a new stamp; 'repeat': the last fresh one again.
stamps = mostly(st.tuples(st.just('fresh'), nanoseconds),
                st.one_of(
    st.just(('zero',)), st.just(('repeat',)),
    st.tuples(st.just('negative'), st.integers(-2**31, -1),
              st.integers(0, 2**32 - 1)),
    st.tuples(st.just('high'), st.integers(INT32_MAX - 3, INT32_MAX),
              st.integers(0, 2**32 - 1))))
offsets = mostly(
    st.one_of(st.just((0, 0)),
              st.tuples(st.integers(0, 3), nanoseconds)),
    st.tuples(st.sampled_from([-2**31, -5, INT32_MAX - 1, INT32_MAX]),
              nanoseconds))
corruptions = mostly(st.none(), st.one_of(
    st.tuples(st.just('cut'), st.floats(0.0, 0.999), st.none()),
    st.tuples(st.just('flip'), st.floats(0.0, 0.999),
              st.binary(min_size=1, max_size=1)),
    st.tuples(st.just('bytes'), st.none(),
              st.one_of(st.binary(max_size=160),
                        st.binary(max_size=160).map(
                            lambda b: b'\x00\x01\x00\x00' + b)))), 8)
setpoint_states = mostly(
    st.tuples(inside(), st.tuples(*[st.floats(-3.0, 3.0)] * 3),
              st.tuples(*[st.floats(-30.0, 30.0)] * 3)),
    states(L3), 5)
orders = mostly(st.permutations(['pose', 'twist', 'accel']),
                st.permutations(['pose', 'twist', 'accel']).flatmap(
                    lambda order: st.integers(1, 2).map(
                        lambda n: order[:n])))

groups = st.builds(
    lambda stamp, order, fr, state, q, bad: SimpleNamespace(
        item='group', stamp=stamp, order=order, frames=fr, state=state,
        orientation=q, corruption=bad),
    stamps,
    orders,
    st.fixed_dictionaries({p: frames for p in ('pose', 'twist', 'accel')}),
    setpoint_states, orientations,
    st.fixed_dictionaries({p: corruptions for p in ('pose', 'twist',
                                                    'accel')}))
trajectories = st.builds(
    lambda stamp, offset, frame, state, q, flags, extra, names, bad:
    SimpleNamespace(item='trajectory', stamp=stamp, offset=offset,
                    frame=frame, state=state, orientation=q,
                    has_point=flags[0], has_transform=flags[1],
                    with_velocity=flags[2], with_acceleration=flags[3],
                    extra=extra, names=names, corruption=bad),
    stamps, offsets, frames, setpoint_states, orientations,
    st.tuples(*[st.sampled_from([True] * 11 + [False])] * 4),
    st.integers(0, 2), st.lists(frames, max_size=2), corruptions)
garbage = st.builds(
    lambda source, data: SimpleNamespace(item='garbage', source=source,
                                         data=data),
    st.sampled_from(SETPOINT_INPUTS),
    st.one_of(st.binary(max_size=200),
              st.binary(max_size=200).map(lambda b: b'\x00\x01\x00\x00' + b),
              st.binary(max_size=200).map(lambda b: b'\x00\x00\x00\x00' + b)))
node_settings = st.tuples(
    st.booleans(),
    mostly(st.sampled_from([0.2, 0.0, 0.5]),
           st.one_of(st.just(0.99), st.floats(0.0, 0.99))))


# Driving the node --------------------------------------------------------
class Run:
    """One example: resolve stamps, call the callbacks, check everything."""

    def __init__(self, rig):
        self.rig = rig
        node = rig.node
        core = node.core
        self.model = Model(core.received, core.rejected, core.settings)
        self.expected = []      # (stamp or Window, Solution), in order
        self.published = node.core.published

    def stamp(self, spec):
        if spec[0] == 'fresh':
            self.rig.last_fresh = (next(self.rig.fresh), spec[1])
            return self.rig.last_fresh
        if spec[0] == 'repeat':
            return self.rig.last_fresh
        if spec[0] == 'zero':
            return (0, 0)
        return spec[1:]

    def deliver(self, source, data, fields):
        """Deliver one message as the input thread does; check everything."""
        node = self.rig.node
        before = node.get_clock().now().nanoseconds
        assert node.inputs.deliver(node.inputs.sources[source], data,
                                   time.monotonic()) is None
        after = node.get_clock().now().nanoseconds
        window = None
        if fields is not MALFORMED and source == 'trajectory' and \
                fields[2] is not None:
            fields, window = self.point_stamp(fields, before, after)
        predicted = self.model.receive(source, fields)
        published = node.core.published - self.published
        self.published = node.core.published
        if predicted is not None and predicted[0] == 'output':
            assert published == 1, (source, fields, predicted)
            stamp = window if predicted[1] is NOW else predicted[1]
            self.expected.append((stamp, predicted[2]))
        else:
            assert published == 0, (source, fields, predicted)
        assert node.internal_errors == 0
        core = node.core
        assert core.received == self.model.received, (source, fields)
        assert core.rejected == self.model.rejected, (source, fields,
                                                      predicted)

    @staticmethod
    def point_stamp(fields, before, after):
        """
        Resolve a trajectory's stamp as the node does: header + offset.

        A header or offset whose nanosec is not in [0, 1e9) gives BAD; a
        zero header is the node's clock (between ``before`` and ``after``)
        plus the offset: NOW (valid) or the invalid stamp, and the Window
        the output's stamp must lie in (the drawn offsets keep both ends on
        the same side of the int32 limits). Returns (fields, window).
        """
        header, frame, point = fields
        offset = point[4]
        if not (0 <= header[1] < 10**9 and 0 <= offset[1] < 10**9):
            return (BAD, frame, point), None
        if header != (0, 0):
            total = (header[0] + offset[0]) * 10**9 + header[1] + offset[1]
            return (divmod(total, 10**9), frame, point), None
        ends = [t + offset[0] * 10**9 + offset[1] for t in (before, after)]
        bad = [Model.bad_stamp(divmod(t, 10**9)) for t in ends]
        assert bad[0] == bad[1], ends
        if bad[0]:
            return (divmod(ends[0], 10**9),) + fields[1:], None
        return (NOW,) + fields[1:], Window(*ends)

    def group(self, g):
        stamp = self.stamp(g.stamp)
        for part in g.order:
            data = serialize_message(topic_message(
                part, stamp, g.frames[part], g.state, g.orientation))
            bad = g.corruption[part]
            data = corrupt(data, bad)
            if bad is None:
                fields = {'pose': (stamp, g.frames[part], g.state[0],
                                   g.orientation),
                          'twist': (stamp, g.frames[part], g.state[1]),
                          'accel': (stamp, g.frames[part], g.state[2])}[part]
            else:
                fields = read_like_node(part, data)
            self.deliver(part, data, fields)

    def trajectory(self, t):
        t.header = self.stamp(t.stamp)
        data = serialize_message(trajectory_message(t))
        if t.corruption is None:
            fields = trajectory_fields(t, t.header)
        else:
            data = corrupt(data, t.corruption)
            fields = read_like_node('trajectory', data)
        self.deliver('trajectory', data, fields)

    def garbage(self, g):
        self.deliver(g.source, g.data, read_like_node(g.source, g.data))

    def run(self, items):
        for item in items:
            getattr(self, item.item)(item)
        # The partials left: dropped and counted by node and model.
        self.rig.node.core.expire(time.monotonic() + 1e6)
        self.model.flush()
        assert self.rig.node.core.rejected == self.model.rejected
        assert self.rig.node.core.pending == 0


def wait_outputs(rig, count):
    """Spin until the probe holds ``count`` joint states, forces, powers."""
    p = rig.probe
    assert spin_until(rig.executor, lambda: min(
        len(p.joint_states), len(p.forces), len(p.power)) >= count, WAIT), (
        f'expected {count} outputs, got {len(p.joint_states)}')


def assert_outputs(rig, expected, names):
    """Check every output against mechanics.solve, exactly, in order."""
    p = rig.probe
    wait_outputs(rig, len(expected))
    assert len(p.joint_states) == len(expected)
    for k, (stamp, s) in enumerate(expected):
        joints = p.joint_states[k]
        got = header_stamp(joints)
        if isinstance(stamp, Window):   # a zero stamp: now + offset
            ns = got[0] * 10**9 + got[1]
            assert stamp.low <= ns <= stamp.high, (got, stamp)
        else:
            assert got == stamp
        assert list(joints.name) == names
        values = [list(joints.position), list(joints.velocity),
                  list(joints.effort), list(p.forces[k].data),
                  list(p.power[k].data)]
        assert all(math.isfinite(x) for v in values for x in v), values
        assert values == [list(s.lambda_), list(s.lambdadot),
                          list(s.force), list(s.force), list(s.power)]


def set_node(rig, pose_only, margin):
    """Set pose_only and singularity_margin the standard way (validated)."""
    results = rig.node.set_parameters([
        Parameter('pose_only', value=pose_only),
        Parameter('singularity_margin', value=margin)])
    assert all(r.successful for r in results), [r.reason for r in results]
    settings = rig.node.core.settings
    assert (settings.pose_only, settings.singularity_margin) == (
        pose_only, margin)


def fresh_start(rig):
    """Drop partials left (by a failed example); forget earlier outputs."""
    rig.node.core.expire(time.monotonic() + 1e6)
    spin_until(rig.executor, lambda: False, 0.01)
    rig.probe.clear()


def test_fuzzed_setpoints(rig):
    """Topic groups, trajectories and garbage: finite, exact, counted."""
    names = list(rig.node.core.settings.joint_names)
    totals = {'outputs': 0}

    @settings(FUZZ, max_examples=examples(200))
    @given(node_settings, st.lists(
        mostly(st.one_of(groups, trajectories), garbage, 9),
        min_size=1, max_size=6))
    def check(setup, items):
        fresh_start(rig)
        set_node(rig, *setup)
        run = Run(rig)
        run.run(items)
        assert_outputs(rig, run.expected, names)
        totals['outputs'] += len(run.expected)

    check()
    assert rig.node.internal_errors == 0
    assert totals['outputs'] > 0
    print(f'fuzzed node: {sum(rig.node.core.received.values())} inputs, '
          f'{rig.node.core.published} outputs, rejected '
          f'{dict(rig.node.core.rejected)}')


def test_random_bytes_on_every_input(rig):
    """Any byte string on any input: no exception, counted, never wrong."""
    names = list(rig.node.core.settings.joint_names)

    @settings(FUZZ, max_examples=examples(150))
    @given(st.lists(garbage, min_size=1, max_size=8))
    def check(items):
        fresh_start(rig)
        run = Run(rig)
        run.run(items)
        assert_outputs(rig, run.expected, names)

    check()
    assert rig.node.internal_errors == 0
    assert rig.node.core.rejected['malformed'] > 0
