"""
The child processes of a reliability run: producer, recorder, attacker.

Run as ``python -m orthoglide_testing.reliability.roles ROLE ...``
(:class:`runs.Child` does): each talks in lines on its standard output
(``ready``, ``first``, ``gap``, ``idle``, ``done``) and takes commands on
its standard input (``go``, ``stop``); SIGINT or SIGTERM ends it.
"""

import argparse
import array
import os
import resource
import select
import signal
import struct
import sys
import time

import numpy as np

from orthoglide_testing.messages import INPUT_TOPICS, Producer, qos_profile
from orthoglide_testing.reliability.cases import attack_payloads
from orthoglide_testing.reliability.runs import (
    EPOCH_NS, FLOOD_STEP_NS, GAP_NS, IDLE_NS, LOG_COLUMNS, RECORD_LIMIT_NS,
    sample_at, START_TIMEOUT, TAIL_COUNT, TAIL_PERIOD, WARM_PERIOD)


def _stdin_lines(buffer):
    """Return the complete lines waiting on stdin (never blocks)."""
    lines = []
    while select.select([sys.stdin.fileno()], [], [], 0.0)[0]:
        chunk = os.read(sys.stdin.fileno(), 4096)
        if not chunk:
            lines.append('eof')
            break
        buffer.extend(chunk)
        while b'\n' in buffer:
            line, _, rest = bytes(buffer).partition(b'\n')
            buffer[:] = rest
            lines.append(line.decode().strip())
    return lines


def _say(*fields):
    sys.stdout.write(' '.join(str(f) for f in fields) + '\n')
    sys.stdout.flush()


def _stop_on_sigint():
    """Make SIGINT/SIGTERM set a flag; return the flag (a one-item list)."""
    stop = [False]

    def handler(signum, frame):
        stop[0] = True

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, handler)
    return stop


def produce(args):
    """
    Child process: warm up until ``go``, then stream setpoints; log them.

    Says ``ready`` once its publishers match the node, publishes warm-up
    setpoints (epoch ``--warm-epoch``) every 20 ms until ``go`` arrives on
    stdin, then setpoints from ``--epoch`` on: at ``--rate`` Hz (deadline
    schedule, as bench_node), or as fast as it can with rate 0 (then a
    steady tail, :func:`_tail`). Stops on
    ``stop``, SIGINT or after ``--duration`` s; waits up to 2 s for reliable
    readers to acknowledge; writes LOG_COLUMNS numbers per setpoint to
    ``--log``; says ``done count last``.
    """
    import rclpy
    from rclpy.duration import Duration
    from rclpy.signals import SignalHandlerOptions

    stop = _stop_on_sigint()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(f'reliability_producer_{os.getpid()}')
    producer = Producer(node, args.kind, args.qos)
    log = array.array('q')
    buffer = bytearray()
    count = 0
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while not producer.matched():
            if stop[0] or time.monotonic() > deadline:
                return 1
            time.sleep(0.01)
        _say('ready')
        warm = args.warm_epoch * EPOCH_NS
        go = False
        for k in range(round(START_TIMEOUT / WARM_PERIOD)):
            if stop[0]:
                break
            lines = _stdin_lines(buffer)
            if 'eof' in lines:      # the orchestrator is gone
                break
            if 'go' in lines:
                go = 'stop' not in lines    # both read at once: stop
                break
            stamp = warm + k * 1000
            producer.fill(stamp, sample_at(stamp))
            producer.publish()
            time.sleep(WARM_PERIOD)
        if go:
            count = _stream(producer, args, log, buffer, stop)
        for pub in producer.pubs:
            pub.wait_for_all_acked(Duration(seconds=2.0))
    finally:
        with open(args.log, 'wb') as f:
            log.tofile(f)
        node.destroy_node()
        rclpy.try_shutdown()
    last = log[-LOG_COLUMNS] if count else -1
    _say('done', count, last)
    return 0


def _stream(producer, args, log, buffer, stop):
    """Publish the stream of :func:`produce`; return the setpoints sent."""
    clock, sleep = time.monotonic_ns, time.sleep
    base = args.epoch * EPOCH_NS
    step = FLOOD_STEP_NS if args.rate == 0 else round(1e9 / args.rate)
    limit = round(args.duration * 1e9)
    # Voluntary context switches of this thread: a publish call that
    # waited (blocked) rather than lost the CPU makes some. Only at a rate:
    # a flood publishes as fast as it can.
    switches = ((lambda: resource.getrusage(
        resource.RUSAGE_THREAD).ru_nvcsw) if args.rate else (lambda: 0))
    start = clock()
    i = 0
    while not stop[0]:
        deadline = start + i * step
        if args.rate:
            wait = deadline - clock()
            if wait > 0:
                sleep(wait / 1e9)
        stamp = base + i * step
        producer.fill(stamp, sample_at(stamp))
        waited = switches()
        before = clock()
        producer.publish()
        after = clock()
        log.extend((stamp, before, after - before,
                    before - deadline if args.rate else 0,
                    switches() - waited))
        i += 1
        if i % 64 == 0 or args.rate:
            if after - start >= limit or {'stop', 'eof'} & set(
                    _stdin_lines(buffer)):
                break
    if not args.rate:
        i = _tail(producer, base + i * step, log)
    return i


def _tail(producer, stamp, log):
    """
    End a flood with TAIL_COUNT setpoints TAIL_PERIOD s apart; return them.

    Best effort drops what a full transport cannot take, the flood's last
    setpoint included now and then on a busy machine: the newest setpoint
    the node must end on is sent once the flood has drained.
    """
    for k in range(TAIL_COUNT):
        time.sleep(TAIL_PERIOD)
        producer.fill(stamp, sample_at(stamp))
        before = time.monotonic_ns()
        producer.publish()
        log.extend((stamp, before, time.monotonic_ns() - before, 0, 0))
        stamp += FLOOD_STEP_NS
    return len(log) // LOG_COLUMNS


def record(args):
    """
    Child process: record every ``feedforward/joint_states`` it receives.

    Raw subscription (reliable, keep-last 1000), EventsExecutor. Says
    ``matched``; ``first t stamp`` for the first output of a new stamp
    epoch, ``gap t stamp`` for an output after 100 ms without any and
    ``idle t stamp`` (stamp of the last output) after 300 ms without any; t
    is CLOCK_MONOTONIC in ns. On SIGINT writes an (N, 11) array to
    ``--out``: stamp (ns), receive time (ns), position, velocity and effort
    (NaN where an array does not hold three values).
    """
    import rclpy
    from rclpy.experimental import EventsExecutor
    from rclpy.serialization import deserialize_message
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState

    stop = _stop_on_sigint()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(f'reliability_recorder_{os.getpid()}')
    received = []
    state = {'last': None, 'stamp': None, 'idle': True, 'matched': False}
    epochs = set()
    clock = time.monotonic_ns

    def on_joints(data):
        now = clock()
        received.append((now, data))
        sec, nanosec = struct.unpack_from('<iI' if data[1] else '>iI',
                                          data, 4)
        stamp = sec * 10**9 + nanosec
        epoch = stamp // EPOCH_NS
        if epoch not in epochs:
            epochs.add(epoch)
            _say('first', now, stamp)
        elif state['last'] is not None and now - state['last'] >= GAP_NS:
            _say('gap', now, stamp)
        state.update(last=now, stamp=stamp, idle=False)

    sub = node.create_subscription(
        JointState, 'feedforward/joint_states', on_joints,
        qos_profile('reliable', 1000), raw=True)

    buffer = bytearray()
    started = clock()

    def watch():
        # Stop when the orchestrator is gone (stdin closed) or after an
        # hour, whatever happens.
        if 'eof' in _stdin_lines(buffer) or \
                clock() - started > RECORD_LIMIT_NS:
            stop[0] = True
        if not state['matched'] and sub.get_publisher_count() > 0:
            state['matched'] = True
            _say('matched')
        now = clock()
        if not state['idle'] and now - state['last'] >= IDLE_NS:
            state['idle'] = True
            _say('idle', now, state['stamp'])

    node.create_timer(0.05, watch)
    executor = EventsExecutor()
    executor.add_node(node)
    try:
        while not stop[0]:
            executor.spin_once(timeout_sec=0.05)
    finally:
        rows = np.full((len(received), 11), np.nan)
        for row, (now, data) in zip(rows, received):
            msg = deserialize_message(data, JointState)
            row[0] = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
            row[1] = now
            for k, values in enumerate((msg.position, msg.velocity,
                                        msg.effort)):
                if len(values) == 3:
                    row[2 + 3 * k:5 + 3 * k] = values
        np.save(args.out, rows)
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def attack(args):
    """
    Child process: publish the attack messages raw, round robin.

    Says ``ready`` once matched; on ``go`` publishes one message every
    1/--rate s until ``stop`` or --duration; says ``done count``.
    """
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from trajectory_msgs.msg import MultiDOFJointTrajectory

    stop = _stop_on_sigint()
    payloads = attack_payloads()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(f'hostile_attacker_{os.getpid()}')
    pub = node.create_publisher(MultiDOFJointTrajectory,
                                'setpoint/trajectory',
                                qos_profile('reliable', 1))
    buffer = bytearray()
    count = 0
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while pub.get_subscription_count() == 0:
            if stop[0] or time.monotonic() > deadline:
                return 1
            time.sleep(0.01)
        _say('ready')
        while not stop[0]:
            lines = _stdin_lines(buffer)
            if 'go' in lines or 'eof' in lines:
                break
            time.sleep(0.01)
        start = time.monotonic()
        while not stop[0] and time.monotonic() - start < args.duration:
            if {'stop', 'eof'} & set(_stdin_lines(buffer)):
                break
            pub.publish(payloads[count % len(payloads)][1])
            count += 1
            time.sleep(1.0 / args.rate)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    _say('done', count)
    return 0


def bystand(args):
    """
    Child process: ``--participants`` participants that read one topic.

    Each (an rclpy context of its own, as a process of several nodes has
    with several contexts) subscribes to ``--topic`` (reliable, keep-last
    10; by default the node's ``feedforward/joint_states``: the node sends
    it every output) ``--subscribe-after`` s after it saw the node
    ``feedforward`` in the graph (said: ``joined``), as ``ros2 topic echo``
    or a display added in RViz does. Says ``matched`` once every
    subscription matched a publisher, spins until ``stop``, stdin closes
    or SIGINT, and says ``done count``.
    """
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState

    stop = _stop_on_sigint()
    nodes, executors = [], []
    for k in range(args.participants):
        context = Context()
        rclpy.init(context=context,
                   signal_handler_options=SignalHandlerOptions.NO)
        nodes.append(rclpy.create_node(f'bystander_{os.getpid()}_{k}',
                                       context=context))
        executors.append(SingleThreadedExecutor(context=context))
        executors[-1].add_node(nodes[-1])
    count = [0]

    def on_joints(data):
        count[0] += 1
    buffer = bytearray()
    subs, joined, matched = [], None, False
    try:
        while not stop[0] and not {'stop', 'eof'} & set(
                _stdin_lines(buffer)):
            for executor in executors:
                executor.spin_once(timeout_sec=0.005)
            if joined is None and 'feedforward' in nodes[0].get_node_names():
                joined = time.monotonic()
                _say('joined')
            if not subs and joined is not None and \
                    time.monotonic() - joined >= args.subscribe_after:
                subs = [node.create_subscription(
                    JointState, args.topic, on_joints,
                    qos_profile('reliable', 10), raw=True) for node in nodes]
            if subs and not matched and all(
                    sub.get_publisher_count() for sub in subs):
                matched = True
                _say('matched')
    finally:
        for executor, node in zip(executors, nodes):
            context = node.context
            executor.shutdown()
            node.destroy_node()
            rclpy.try_shutdown(context=context)
    _say('done', count[0])
    return 0


def main(argv=None):
    """Entry point of the child processes: produce, record, attack..."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('role', choices=('produce', 'record', 'attack',
                                         'bystand'))
    parser.add_argument('--kind', default='trajectory',
                        choices=tuple(INPUT_TOPICS))
    parser.add_argument('--qos', default='reliable')
    parser.add_argument('--rate', type=float, default=0.0)
    parser.add_argument('--epoch', type=int, default=100)
    parser.add_argument('--warm-epoch', type=int, default=1)
    parser.add_argument('--duration', type=float, default=3600.0)
    parser.add_argument('--log')
    parser.add_argument('--out')
    parser.add_argument('--topic', default='feedforward/joint_states')
    parser.add_argument('--subscribe-after', type=float, default=0.0)
    parser.add_argument('--participants', type=int, default=1)
    args = parser.parse_args(argv)
    return {'produce': produce, 'record': record, 'attack': attack,
            'bystand': bystand}[args.role](args)


if __name__ == '__main__':
    sys.exit(main())
