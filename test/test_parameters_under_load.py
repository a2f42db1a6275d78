"""
Parameter changes while the node streams at 1 kHz: refused or atomic.

The node runs as its own process (the ``feedforward`` console script with
``config/orthoglide.yaml``). This process is the producer and the recorder:
its node publishes one MultiDOFJointTrajectory per millisecond (stamps
``(7000 + k // 1000, (k % 1000) ms)``, eq. (6)'s shape on a fast loop
inside the cube), records every output raw with its arrival time, and
talks to the node through the standard parameter services
(``AsyncParameterClient``). One thread: the loop publishes when a
setpoint is due and spins the EventsExecutor in between, so the service
responses, the outputs and the timer-free producer share it.

The script, all under load:

(a) invalid changes, each through ``set_parameters`` and through
    ``set_parameters_atomically``: ``robot.m5 = -1``, ``robot.l3 = 0``,
    ``pairing_timeout > setpoint_timeout``, two ``joint_names``,
    ``singularity_margin = 2`` (rclpy's range), a 2-element
    ``robot.gravity``, and ``m5 = 18`` atomically with ``l3 = 0``: each is
    refused with a reason and changes nothing;
(b) ``robot.m5`` 15 -> 18 with ``robot.gravity`` [0, 0, -9.81] -> [0, 0,
    -9.0] in one ``set_parameters_atomically``, back and forth;
(c) the same two through ``set_parameters``, which rclpy applies one by
    one, each validated and applied on its own: the parameters pass
    through m5-new/gravity-old (a consistent, valid model) on the way;
    and a ``set_parameters`` whose second value is refused, which leaves
    exactly that intermediate model in force.

Every output (joint state, forces, power) must equal, to 1e-9, the result
of one of the models the parameter history went through, the models being
told apart at each setpoint (old, new and both "mixed" models give forces
that differ by far more than 1e-9). Each output's model must be allowed by
the times: not a change requested after the output arrived, not a model
older than a change answered before its setpoint was sent; and along the
outputs the model only moves forwards through the history. During (a) and
(b) the mixed models must never appear.
"""

from collections import Counter
import math
from pathlib import Path
import sys
import time

import pytest
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.serialization import deserialize_message

from geometry_msgs.msg import Transform, Twist
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import (MultiDOFJointTrajectory,
                                 MultiDOFJointTrajectoryPoint)

from orthoglide_ros.model import mechanics
from orthoglide_ros.formats.params_file import load_robot
from orthoglide_ros.model.trajectory import paper_sample

from node_checks import close, needs_scripts  # noqa: E402
from orthoglide_testing.probe import paced, PROBE_QOS  # noqa: E402
from orthoglide_testing.processes import (start_node_process,  # noqa: E402
                                          stop_process)

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / 'config' / 'orthoglide.yaml'
DISTINCT = 1e-6         # N: the models' forces differ by more, everywhere
RATE = 1000.0           # setpoints per second
START_WAIT = 40.0       # s for the process to come up and answer
WAIT = 15.0             # s for one service answer: the machine is shared
TARGET, OMEGA = (0.15, -0.15, 0.12), 4.0    # stays in the cube

OLD = load_robot(PARAMS)
NEW = OLD.replace(m5=18.0, gravity=[0.0, 0.0, -9.0])
MODELS = {
    'old': OLD,
    'new': NEW,
    'm5_new_gravity_old': OLD.replace(m5=18.0),
    'm5_old_gravity_new': OLD.replace(gravity=[0.0, 0.0, -9.0]),
}
MIXED = ('m5_new_gravity_old', 'm5_old_gravity_new')
ATOMIC_TO = {'new': [Parameter('robot.m5', value=18.0),
                     Parameter('robot.gravity', value=[0.0, 0.0, -9.0])],
             'old': [Parameter('robot.m5', value=15.0),
                     Parameter('robot.gravity', value=[0.0, 0.0, -9.81])]}
INVALID = [
    [Parameter('robot.m5', value=-1.0)],
    [Parameter('robot.l3', value=0.0)],
    [Parameter('pairing_timeout', value=0.5)],     # > setpoint_timeout 0.1
    [Parameter('joint_names', value=['a', 'b'])],
    [Parameter('singularity_margin', value=2.0)],
    [Parameter('robot.gravity', value=[0.0, -9.81])],
]
WATCHED = ['robot.m5', 'robot.l3', 'robot.gravity', 'pairing_timeout',
           'setpoint_timeout', 'joint_names', 'singularity_margin']

pytestmark = [pytest.mark.ros, needs_scripts()]


def setpoint(k):
    """Position, velocity, acceleration of setpoint k (t = k ms)."""
    return paper_sample((k / RATE) % (2.0 * math.pi / OMEGA), TARGET, OMEGA)


def stamp_of(k):
    """Return the (sec, nanosec) stamp of setpoint k."""
    return (7000 + k // 1000, (k % 1000) * 1_000_000)


def close_all(actual, expected):
    """Say whether float sequences agree element by element to TOL."""
    return len(actual) == len(expected) and all(
        close(a, e) for a, e in zip(actual, expected))


class LoadRig:
    """The producer, recorder and parameter client, on one executor."""

    def __init__(self, context):
        self.node = Node('load_producer', context=context)
        self.publisher = self.node.create_publisher(
            MultiDOFJointTrajectory, 'setpoint/trajectory', PROBE_QOS)
        self.outputs = {name: [] for name in ('joint_states', 'forces',
                                              'power')}
        self.subscriptions = [
            self.node.create_subscription(
                kind, f'feedforward/{name}', self._recorder(name),
                PROBE_QOS, raw=True)
            for name, kind in (('joint_states', JointState),
                               ('forces', Float64MultiArray),
                               ('power', Float64MultiArray))]
        self.client = AsyncParameterClient(self.node, 'feedforward')
        self.executor = EventsExecutor(context=context)
        self.executor.add_node(self.node)
        self.sent_at = []       # monotonic send time of setpoint k
        self.history = []       # (model name, request time, answer time)
        self._message = MultiDOFJointTrajectory(
            joint_names=['platform'],
            points=[MultiDOFJointTrajectoryPoint(
                transforms=[Transform()], velocities=[Twist()],
                accelerations=[Twist()])])
        self._message.header.frame_id = 'base_link'
        self._message.points[0].transforms[0].rotation.w = 1.0
        self._due = None

    def _recorder(self, name):
        records = self.outputs[name]

        def record(data):
            records.append((time.monotonic(), data))
        return record

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()

    def _publish(self):
        k = len(self.sent_at)
        (x, y, z), (vx, vy, vz), (ax, ay, az) = setpoint(k)
        msg = self._message
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp_of(k)
        point = msg.points[0]
        t = point.transforms[0].translation
        v, a = point.velocities[0].linear, point.accelerations[0].linear
        t.x, t.y, t.z = x, y, z
        v.x, v.y, v.z = vx, vy, vz
        a.x, a.y, a.z = ax, ay, az
        self.publisher.publish(msg)
        self.sent_at.append(time.monotonic())

    def pump(self, duration=None, until=None, timeout=WAIT):
        """
        Stream at RATE and spin, for ``duration`` s or until ``until()``.

        Behind schedule it does not burst: one setpoint, then a spin.
        """
        self._due = paced(self.executor, RATE, self._publish, duration,
                          until, timeout, self._due)

    def drain(self, quiet=0.5):
        """Spin without publishing until no output came for ``quiet`` s."""
        last = -1
        while True:
            count = len(self.outputs['joint_states'])
            if count == last:
                return
            last = count
            deadline = time.monotonic() + quiet
            while time.monotonic() < deadline:
                self.executor.spin_once(timeout_sec=0.05)

    def call(self, make_future):
        """Send one request while streaming; return (result, sent, answer)."""
        sent = time.monotonic()
        future = make_future()
        self.pump(until=future.done)
        return future.result(), sent, time.monotonic()

    def change(self, make_future, models):
        """Make a valid change; the parameters pass through ``models``."""
        result, sent, answered = self.call(make_future)
        for name in models:
            self.history.append((name, sent, answered))
        return result


@pytest.fixture
def rig(ros_context):
    """Start the node process and the rig; stop and report afterwards."""
    proc = start_node_process(['--ros-args', '--params-file', str(PARAMS)])
    made = LoadRig(ros_context)
    try:
        yield made
    finally:
        made.close()
        code, stderr = stop_process(proc)
        print(f'node exit code {code}; stderr:\n{stderr[-3000:]}',
              file=sys.stderr)


def start(rig):
    """Stream until the node answers and its parameter services are up."""
    rig.history.append(('old', -math.inf, -math.inf))
    rig.pump(until=lambda: rig.outputs['joint_states']
             and rig.client.services_are_ready(), timeout=START_WAIT)
    rig.pump(0.5)


def refuse_invalid_changes(rig):
    """Send (a), the invalid changes: each refused with a reason, no effect."""
    client = rig.client
    before = rig.call(lambda: client.get_parameters(WATCHED))[0].values
    refusals = []
    for parameters in INVALID + [[Parameter('robot.m5', value=18.0),
                                  Parameter('robot.l3', value=0.0)]]:
        what = [p.name for p in parameters]
        if len(parameters) == 1:
            response = rig.call(lambda: client.set_parameters(parameters))[0]
            assert len(response.results) == 1
            result = response.results[0]
            assert not result.successful, what
            assert result.reason, what
            refusals.append(result.reason)
        result = rig.call(
            lambda: client.set_parameters_atomically(parameters))[0].result
        assert not result.successful, what
        assert result.reason, what
        refusals.append(result.reason)
        rig.pump(0.05)
    after = rig.call(lambda: client.get_parameters(WATCHED))[0].values
    assert after == before
    assert [after[0].double_value, list(after[2].double_array_value)] == [
        15.0, [0.0, 0.0, -9.81]]
    return refusals


def switch_atomically(rig, changes, spacing):
    """Switch m5 with gravity in one request, back and forth (b)."""
    for i in range(changes):
        target = 'new' if i % 2 == 0 else 'old'
        result = rig.change(lambda: rig.client.set_parameters_atomically(
            ATOMIC_TO[target]), [target]).result
        assert result.successful, result.reason
        rig.pump(spacing)


def switch_one_by_one(rig, spacing):
    """Switch the two through set_parameters, applied one by one (c)."""
    client = rig.client
    for target, through in (('new', 'm5_new_gravity_old'),
                            ('old', 'm5_old_gravity_new')):
        response = rig.change(
            lambda: client.set_parameters(ATOMIC_TO[target]),
            [through, target])
        assert [r.successful for r in response.results] == [True, True], [
            r.reason for r in response.results]
        rig.pump(spacing)
    # The second value refused: the first stays applied, on its own.
    response = rig.change(lambda: client.set_parameters([
        Parameter('robot.m5', value=18.0),
        Parameter('robot.gravity', value=[0.0, 0.0])]),
        ['m5_new_gravity_old'])
    assert [r.successful for r in response.results] == [True, False]
    assert 'robot.gravity' in response.results[1].reason
    rig.pump(spacing)
    result = rig.change(lambda: client.set_parameters_atomically(
        [Parameter('robot.m5', value=15.0)]), ['old']).result
    assert result.successful, result.reason
    rig.pump(spacing)


class Checker:
    """
    Identify each output's setpoint and model; check them against history.

    A joint state names its setpoint by its stamp. A forces or power array
    has no stamp: the node publishes one per setpoint taken, in order, so
    the next array's setpoint is the first later one for which a model's
    result matches it (an output the node's keep-last writer dropped for
    this busy reader leaves a gap, never a reordering).
    """

    def __init__(self, rig):
        self.rig = rig
        self.index = {stamp_of(k): k for k in range(len(rig.sent_at))}
        self.cache = {}

    def expected(self, k):
        """Return {model name: Solution} of setpoint k."""
        if k not in self.cache:
            p, v, a = setpoint(k)
            self.cache[k] = {name: mechanics.solve(robot, p, v, a)
                             for name, robot in MODELS.items()}
            forces = [s.force for s in self.cache[k].values()]
            assert min(max(abs(x - y) for x, y in zip(f, g))
                       for i, f in enumerate(forces)
                       for g in forces[i + 1:]) > DISTINCT
        return self.cache[k]

    def joint_states(self):
        """Return [(arrival, k, model name)] of the joint states."""
        found = []
        for arrival, data in self.rig.outputs['joint_states']:
            msg = deserialize_message(data, JointState)
            stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec)
            assert stamp in self.index, f'output of unknown stamp {stamp}'
            k = self.index[stamp]
            assert not found or k > found[-1][1], 'outputs out of order'
            got = (list(msg.position), list(msg.velocity), list(msg.effort))
            names = [name for name, s in self.expected(k).items()
                     if close_all(got[0], s.lambda_)
                     and close_all(got[1], s.lambdadot)
                     and close_all(got[2], s.force)]
            assert len(names) == 1, (
                f'setpoint {k}: output {got} matches {names or "no model"}')
            found.append((arrival, k, names[0]))
        return found

    def arrays(self, topic, field):
        """Return [(arrival, k, model name)] of the forces or powers."""
        found = []
        k = -1
        for arrival, data in self.rig.outputs[topic]:
            got = list(deserialize_message(data, Float64MultiArray).data)
            names = []
            while not names:
                k += 1
                assert k < len(self.rig.sent_at), (
                    f'{topic} {got} matches no setpoint after the last one')
                names = [name for name, s in self.expected(k).items()
                         if close_all(got, getattr(s, field))]
            assert len(names) == 1, (k, names)
            found.append((arrival, k, names[0]))
        return found

    def check_history(self, found):
        """
        Each model allowed by the times; only forwards through history.

        Returns the outputs per history step.
        """
        history = self.rig.history
        position = 0
        seen = Counter()
        for arrival, k, name in found:
            sent = self.rig.sent_at[k]
            # Changes answered before the setpoint was sent apply to it;
            # changes requested after the output arrived cannot.
            low = max(j for j, h in enumerate(history) if h[2] < sent)
            high = max(j for j, h in enumerate(history) if h[1] < arrival)
            allowed = [j for j in range(max(low, position), high + 1)
                       if history[j][0] == name]
            assert allowed, (
                f'setpoint {k} ({name}) at {arrival:.4f}: history position '
                f'{position}, allowed {low}..{high}: '
                f'{[h[0] for h in history[low:high + 1]]}')
            position = allowed[0]
            seen[position] += 1
        assert position == len(history) - 1, 'the last change never showed'
        return seen


def check_topic(rig, checker, found, first_change, one_by_one):
    """Check one output topic; return its figures."""
    seen = checker.check_history(found)
    # Before the first valid change: the original robot only. Up to the
    # first one-by-one change: never a mixed model.
    t_first = rig.history[first_change][1]
    t_one_by_one = rig.history[one_by_one][1]
    phases = {
        'refusals': Counter(n for a, _, n in found if a < t_first),
        'atomic': Counter(n for a, _, n in found
                          if t_first <= a < t_one_by_one),
        'one_by_one': Counter(n for a, _, n in found if a >= t_one_by_one),
    }
    assert set(phases['refusals']) == {'old'}, phases
    assert not any(phases['atomic'][m] for m in MIXED), phases
    runs = [name for i, (_, _, name) in enumerate(found)
            if i == 0 or found[i - 1][2] != name]
    return {
        'outputs': len(found),
        'per_history_step': [(name, seen[j]) for j, (name, _, _) in
                             enumerate(rig.history)],
        'model_switches_seen': len(runs) - 1,
        'per_model': Counter(n for _, _, n in found),
        'per_phase': phases,
    }


def run_script(rig, changes, spacing):
    """Run (a), (b), (c) under load; check and return the figures."""
    start(rig)
    refusals = refuse_invalid_changes(rig)
    first_change = len(rig.history)
    rig.pump(0.3)
    switch_atomically(rig, changes, spacing)
    one_by_one = len(rig.history)
    switch_one_by_one(rig, spacing)
    stream_end = time.monotonic()
    rig.drain()
    checker = Checker(rig)
    topics = {
        'joint_states': checker.joint_states(),
        'forces': checker.arrays('forces', 'force'),
        'power': checker.arrays('power', 'power'),
    }
    checks = {name: check_topic(rig, checker, found, first_change,
                                one_by_one)
              for name, found in topics.items()}
    span = rig.sent_at[-1] - rig.sent_at[0]
    figures = {
        'setpoints': len(rig.sent_at),
        'rate_hz': (len(rig.sent_at) - 1) / span,
        'streamed_s': stream_end - rig.sent_at[0],
        'setpoints_since_first_output':
            len(rig.sent_at) - topics['joint_states'][0][1],
        'refusals': len(refusals),
        'changes': len(rig.history) - 1,
        'answer_ms_max': 1e3 * max(b - a for _, a, b in rig.history[1:]),
        **checks['joint_states'],
        'forces': checks['forces']['per_model'],
        'power': checks['power']['per_model'],
    }
    print('parameters under load:', figures)
    print('refusal reasons:', *refusals, sep='\n  ')
    return figures


# serial: it asserts the producer's rate and the share of setpoints answered
# through the default keep-last 10, both the machine's figures too.
@pytest.mark.serial
@pytest.mark.parametrize('changes, spacing', [
    (6, 0.4),
    pytest.param(60, 0.5, marks=pytest.mark.soak, id='soak'),
])
def test_parameters_under_load(request, changes, spacing):
    """Refusals change nothing; valid changes are atomic; show the counts."""
    if changes > 6 and 'soak' not in (request.config.option.markexpr or ''):
        pytest.skip('long run: select it with -m soak')
    rig = request.getfixturevalue('rig')
    figures = run_script(rig, changes, spacing)
    assert figures['rate_hz'] > 0.5 * RATE, figures
    assert figures['outputs'] > 0.5 * figures[
        'setpoints_since_first_output'], figures
    per_phase = figures['per_phase']
    assert per_phase['refusals']['old'] > 0
    assert not any(per_phase['refusals'][m] for m in MODELS if m != 'old')
    assert per_phase['atomic']['new'] > 0 and per_phase['atomic']['old'] > 0
    assert not any(per_phase['atomic'][m] for m in MIXED)
    # The model left in force by the refused second value, seen on its own.
    assert per_phase['one_by_one']['m5_new_gravity_old'] > 0
    assert figures['model_switches_seen'] <= figures['changes']
