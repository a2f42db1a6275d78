"""
``orthoglide record`` over DDS: joint states into a bag identify reads.

A JointState publisher in the test's process, ``orthoglide record`` as a
process (the installed console script): every message published reaches
the bag (reliable QoS, acknowledged before the stop), with its bytes
unchanged, in MCAP (the default, on the default topic ``/joint_states``)
or sqlite3, and ``identification.read_bag`` reads the positions and
efforts back in the joint order asked for. A stop drains into the bag what
the recorder had received but not handled yet, and what comes between its
subscription and its activation is recorded too. The recorder stops at the
end of ``--duration`` or on SIGINT before it, exit code 0 either way;
without a publisher it gives up after ``--wait`` with exit code 2.
Messages longer than its limit are dropped, and said: the last line
counts what went into the bag and what was dropped, as the bag's own
metadata does (read by rosbags), and the exit code is LOSSY (3).
"""

import contextlib
import threading
import time

import numpy as np
import pytest

from node_checks import needs_scripts
from orthoglide_testing.processes import (node_executable,
                                          start_node_process, stop_process)

from orthoglide_ros.tools import identification

rclpy = pytest.importorskip('rclpy')
from rclpy.duration import Duration  # noqa: E402
from rclpy.qos import HistoryPolicy, QoSProfile, \
    ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import Image, JointState  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402

pytestmark = [pytest.mark.ros, needs_scripts('orthoglide')]

MESSAGES = 150
QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=MESSAGES,
                 reliability=ReliabilityPolicy.RELIABLE)
MATCH_TIMEOUT = 20.0    # s for the recorder to start and subscribe


def record(args):
    return start_node_process(['record', *args],
                              command=[node_executable('orthoglide')])


def wait_subscribed(publisher, proc):
    """
    Wait until the recorder's reader matches ``publisher``.

    ``proc``: the recorder's process (None: in this process). The
    recorder makes its reader only once it sees this publisher, so its
    reader matches this writer as it is made: once this writer sees the
    reader, both sides are matched.
    """
    deadline = time.monotonic() + MATCH_TIMEOUT
    while publisher.get_subscription_count() < 1:
        assert proc is None or proc.poll() is None, stop_process(proc)
        assert time.monotonic() < deadline, 'the recorder never subscribed'
        time.sleep(0.05)


def joint_state(k):
    """Return state ``k``: stamped 1000 s + 10 ms k, values from k."""
    msg = JointState(name=['slider_c', 'slider_a', 'slider_b'],
                     position=[0.003 * k, 0.001 * k, 0.002 * k],
                     velocity=[0.0, 0.0, 0.0],
                     effort=[250.0 + k, 1.0 + k, -2.0 - k])
    msg.header.stamp.sec = 1000 + k // 100
    msg.header.stamp.nanosec = (k % 100) * 10_000_000
    return msg


def publish_states(node, publisher, proc):
    """
    Publish MESSAGES joint states once the recorder listens; return them.

    ``proc``: the recorder's process (None: in this process).
    """
    wait_subscribed(publisher, proc)
    sent = []
    for k in range(MESSAGES):
        sent.append(joint_state(k))
        publisher.publish(sent[-1])
        time.sleep(0.005)
    assert publisher.wait_for_all_acked(Duration(seconds=5.0))
    return sent


def check_bag(path, k=np.arange(MESSAGES)):
    """Check that the bag holds the states ``k``, as published."""
    log = identification.read_bag(path)
    assert np.allclose(log.times, 0.01 * (k - k[0]), rtol=0.0, atol=1e-12)
    assert log.origin == 1000 * 10**9 + k[0] * 10**7
    assert np.array_equal(log.lambdas, np.column_stack(
        (0.001 * k, 0.002 * k, 0.003 * k)))
    assert np.array_equal(log.forces, np.column_stack(
        (1.0 + k, -2.0 - k, 250.0 + k)))


def record_a_source(ros_context, tmp_path, arguments, finish, suffix):
    """Record the joint states published; check the bag's ``suffix`` file."""
    node = rclpy.create_node('joint_state_source', context=ros_context)
    try:
        publisher = node.create_publisher(JointState, 'joint_states', QOS)
        proc = record(['--output', str(tmp_path / 'bag'), *arguments])
        try:
            publish_states(node, publisher, proc)
            finish(proc)
        finally:
            code, err = stop_process(proc)
        assert code == 0, err
        assert list((tmp_path / 'bag').glob(f'*{suffix}'))
        check_bag(tmp_path / 'bag')
    finally:
        node.destroy_node()


def test_record_writes_every_joint_state_into_an_mcap_bag(ros_context,
                                                          tmp_path):
    # Stopped by SIGINT long before its duration, as soon as its reader
    # has acknowledged the last message: a complete bag all the same (what
    # its input thread had not handled yet is drained into it).
    record_a_source(ros_context, tmp_path, ['--duration', '600'],
                    lambda proc: None, '.mcap')


@contextlib.contextmanager
def recording_here(ros_context, tmp_path):
    """Yield a joint state source, its publisher and a Recorder of ours."""
    from orthoglide_ros.ros.recorder_node import Recorder
    node = rclpy.create_node('joint_state_source', context=ros_context)
    recorder = None
    try:
        publisher = node.create_publisher(JointState, 'joint_states', QOS)
        recorder = Recorder(str(tmp_path / 'bag'), ['joint_states'],
                            context=ros_context)
        yield node, publisher, recorder
    finally:
        if recorder is not None:
            recorder.destroy_node()
        node.destroy_node()


def test_a_stop_drains_what_the_recorder_had_not_handled(
        ros_context, tmp_path):
    """
    The messages received but not handled at the stop go into the bag.

    The recorder in this process, its lock held while the states are
    published: its input thread takes the first and waits to handle it,
    the rest wait in its reader's history (acknowledged). The stop comes
    before the lock is free: what the thread holds and what the history
    holds are drained into the bag, not dropped.
    """
    with recording_here(ros_context, tmp_path) as (node, publisher,
                                                   recorder):
        stopping = threading.Thread(target=recorder.on_stop, args=(True,))
        with recorder.lock:
            publish_states(node, publisher, None)
            stopping.start()
            time.sleep(0.2)     # the stop asked (a flag) before the lock is free
        stopping.join(timeout=MATCH_TIMEOUT)
        assert not stopping.is_alive()
        check_bag(tmp_path / 'bag')


def test_record_stops_by_itself_into_a_sqlite3_bag(ros_context, tmp_path):
    record_a_source(ros_context, tmp_path,
                    ['--storage', 'sqlite3', '--duration', '4', '--topic',
                     '/joint_states'],
                    lambda proc: proc.wait(timeout=MATCH_TIMEOUT), '.db3')


def test_record_without_a_publisher_exits_2(tmp_path):
    proc = record(['--output', str(tmp_path / 'bag'), '--topic',
                   'nobody_publishes_this', '--wait', '1', '--duration',
                   '10'])
    try:
        proc.wait(timeout=MATCH_TIMEOUT)
    finally:
        code, err = stop_process(proc)
    assert code == 2
    # The tool's one-line error, not a node's FATAL log line.
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('orthoglide: error: '), err
    assert 'nobody_publishes_this' in err
    assert not (tmp_path / 'bag').exists()


def test_what_comes_before_the_activation_is_recorded(ros_context,
                                                      tmp_path):
    """
    Messages received between configure and activate go into the bag.

    The recorder subscribes at configure; a message that came before it
    was active was counted and not written (under two busy loops the
    suite's MCAP test found 149 of 150: the first one). Here its
    activation takes 0.3 s, while the states are published: all 150 are
    in the bag, and none is counted as dropped.
    """
    from orthoglide_ros.ros.recorder_node import Recorder

    class SlowToActivate(Recorder):
        def on_activate(self, state):
            time.sleep(0.3)
            return super().on_activate(state)

    node = rclpy.create_node('joint_state_source', context=ros_context)
    made = []
    maker = threading.Thread(target=lambda: made.append(SlowToActivate(
        str(tmp_path / 'bag'), ['joint_states'], context=ros_context)))
    try:
        publisher = node.create_publisher(JointState, 'joint_states', QOS)
        maker.start()
        publish_states(node, publisher, None)
        maker.join(timeout=MATCH_TIMEOUT)
        assert made, 'the recorder did not start'
        made[0].on_stop(True)
        check_bag(tmp_path / 'bag')
        assert not made[0].lossy
    finally:
        maker.join(timeout=MATCH_TIMEOUT)
        for recorder in made:
            recorder.destroy_node()
        node.destroy_node()


def test_a_deactivated_recorder_counts_what_it_did_not_record(
        ros_context, tmp_path):
    """
    What comes while a lifecycle client has deactivated it is dropped, said.

    The recorder in this process, deactivated after the first 50 states
    were handled and activated again after the next 50: the bag holds the
    first and the last 50, the 50 between are counted as dropped
    (``inactive``) in the last line, and the recording is lossy.
    """
    with recording_here(ros_context, tmp_path) as (_, publisher, recorder):
        wait_subscribed(publisher, None)
        for part, change in ((range(0, 50), recorder.trigger_deactivate),
                             (range(50, 100), recorder.trigger_activate),
                             (range(100, 150), None)):
            for k in part:
                publisher.publish(joint_state(k))
                time.sleep(0.002)
            deadline = time.monotonic() + MATCH_TIMEOUT
            while recorder.core.received['/joint_states'] < part.stop:
                assert time.monotonic() < deadline, recorder.core.received
                time.sleep(0.01)
            if change is not None:
                change()
        recorder.on_stop(True)
        assert recorder.lossy
        assert recorder.core.summary('bag') == (
            'recorded 100 message(s) into bag (/joint_states: 100); dropped '
            '50 (/joint_states inactive: 50, received while the recorder was '
            'not active)')
        check_bag(tmp_path / 'bag', np.r_[0:50, 100:150])


BIG = 5_000_000     # bytes of image data: above the 4 MiB limit


def test_record_counts_and_says_what_it_dropped(ros_context, tmp_path):
    """
    Ten 5 MB images among twenty: ten in the bag, ten said dropped.

    The last line counts both (by topic and reason, with the limit), the
    diagnostics agree, the bag's metadata (rosbags' reader, not the
    recorder) holds the ten small ones with their bytes, and the exit code
    is LOSSY (3), not 0.
    """
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import get_typestore, Stores
    node = rclpy.create_node('image_source', context=ros_context)
    status = []
    node.create_subscription(DiagnosticArray, '/diagnostics', lambda m: [
        status.append(s) for s in m.status
        if s.name.startswith('orthoglide_record')], 10)
    executor = rclpy.executors.SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    proc = None
    try:
        publisher = node.create_publisher(Image, 'camera/image', QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=20,
            reliability=ReliabilityPolicy.RELIABLE))
        proc = record(['--output', str(tmp_path / 'bag'), '--topic',
                       '/camera/image', '--duration', '600'])
        deadline = time.monotonic() + MATCH_TIMEOUT
        while publisher.get_subscription_count() < 1:
            assert proc.poll() is None, stop_process(proc)
            assert time.monotonic() < deadline, 'never subscribed'
            time.sleep(0.05)
        small = []
        for k in range(20):
            size = BIG if k % 2 else 64
            image = Image(height=1, width=size, encoding='mono8',
                          step=size, data=bytes([k]) * size)
            image.header.frame_id = f'image {k}'
            publisher.publish(image)
            if not k % 2:
                small.append(image)
        assert publisher.wait_for_all_acked(Duration(seconds=30.0))
        # The diagnostics after the last message: the counts so far.
        deadline = time.monotonic() + MATCH_TIMEOUT
        values = {}
        while values.get('messages written') != '10' or \
                values.get('messages dropped') != '10':
            assert time.monotonic() < deadline, values
            executor.spin_once(timeout_sec=0.1)
            if status:
                values = {kv.key: kv.value for kv in status[-1].values}
        assert values['rejected /camera/image oversize'] == '10', values
        code, err = stop_process(proc)
    finally:
        if proc is not None:
            stop_process(proc)
        executor.shutdown()
        node.destroy_node()
    assert code == 3, err
    last = err.strip().splitlines()[-1]
    assert last.startswith('[WARN]'), err
    assert ('recorded 10 message(s) into ' + str(tmp_path / 'bag')
            + ' (/camera/image: 10); dropped 10 (/camera/image oversize: '
            '10, larger than 4 MiB)') in last, err
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(tmp_path / 'bag') as bag:
        assert bag.message_count == 10
        [connection] = bag.connections
        assert connection.topic == '/camera/image'
        assert connection.msgcount == 10
        read = [store.deserialize_cdr(raw, connection.msgtype)
                for _, _, raw in bag.messages()]
    assert [m.header.frame_id for m in read] == \
        [m.header.frame_id for m in small]
    assert all(bytes(m.data) == bytes(s.data) for m, s in zip(read, small))
