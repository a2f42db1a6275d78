#!/usr/bin/env python3
"""
Check whether each workaround of upstream behaviour is still needed.

One check per workaround's removal criterion, on plain rclpy (no code of
the package), each in a process of its own: it prints its figure and
``still needed`` or ``can go``. Run it after an rclpy, rmw or Fast DDS
upgrade; each workaround's docstring names its check. Measured figures:
``doc/measurements.md`` (upstream behaviour).

Usage: python benchmarks/upstream_checks.py [--only NAME[,NAME...]]
       [--seconds S]
"""

import argparse
from contextlib import ExitStack
import math
import os
import select
import struct
import subprocess
import sys
import threading
import time

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(150 + os.getpid() % 80))

CHECK_TIMEOUT = 120.0   # s for one check's process
MiB = 2**20


def _rclpy():
    import rclpy
    rclpy.init()
    return rclpy


def _executor(kind):
    if kind == 'events':
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    from rclpy.executors import SingleThreadedExecutor
    return SingleThreadedExecutor()


def _child(*args):
    """Start this script as a helper process (``--child``)."""
    return subprocess.Popen([sys.executable, __file__, '--child', *args],
                            stdout=subprocess.PIPE, text=True)


def _rss():
    with open('/proc/self/statm') as statm:
        return int(statm.read().split()[1]) * os.sysconf('SC_PAGE_SIZE')


def _read_on_wait_set(node, subscription, take):
    """Start a thread that hands each raw message to ``take(bytes)``."""
    from rclpy.impl.implementation_singleton import \
        rclpy_implementation as _impl
    handle = subscription.handle

    def read():
        with ExitStack() as stack:
            stack.enter_context(handle)
            stack.enter_context(node.context.handle)
            wait_set = _impl.WaitSet(1, 0, 0, 0, 0, 0, node.context.handle)
            while True:
                wait_set.clear_entities()
                wait_set.add_subscription(handle)
                wait_set.wait(int(0.1e9))
                while (taken := handle.take_message(
                        subscription.msg_type, True)) is not None:
                    take(taken[0])
    threading.Thread(target=read, daemon=True).start()


# Helpers run as processes of their own ----------------------------------
def publish(topic, rate, seconds):
    """Publish PoseStamped carrying their send time; ``rate`` 0: a flood."""
    from geometry_msgs.msg import PoseStamped
    from rclpy.node import Node
    _rclpy()
    node = Node('upstream_publisher')
    publisher = node.create_publisher(PoseStamped, topic, 10)
    while publisher.get_subscription_count() == 0:
        time.sleep(0.01)
    time.sleep(1.0)
    rate, seconds = float(rate), float(seconds)
    message, sent, start = PoseStamped(), 0, time.monotonic()
    while time.monotonic() - start < seconds:
        message.pose.position.x = time.time()
        publisher.publish(message)
        sent += 1
        if rate:
            time.sleep(max(0.0, start + sent / rate - time.monotonic()))
    print(sent, flush=True)
    time.sleep(60)


def request(count):
    """Send ``count`` Trigger requests to ``checked`` as fast as it can."""
    from rclpy.node import Node
    from std_srvs.srv import Trigger
    rclpy = _rclpy()
    node = Node('upstream_requester')
    client = node.create_client(Trigger, 'checked')
    client.wait_for_service(10.0)
    futures = [client.call_async(Trigger.Request())
               for _ in range(int(count))]
    end = time.monotonic() + 10.0
    while time.monotonic() < end and not all(f.done() for f in futures):
        rclpy.spin_once(node, timeout_sec=0.01)


def sink_cpu(kind, seconds):
    """Receive a 1 kHz stream; print the CPU per message (us)."""
    from geometry_msgs.msg import PoseStamped
    from rclpy.node import Node
    _rclpy()
    node, got = Node('upstream_sink'), [0]
    if kind == 'waitset':
        subscription = node.create_subscription(
            PoseStamped, 'cpu', lambda m: None, 10, raw=True)

        def take(data):
            struct.unpack_from('<iI', data, 4)      # the stamp
            got[0] += 1
        _read_on_wait_set(node, subscription, take)

        def spin():
            time.sleep(0.05)
    else:
        node.create_subscription(PoseStamped, 'cpu', lambda m: got.__setitem__(
            0, got[0] + 1), 10)
        executor = _executor(kind)
        executor.add_node(node)

        def spin():
            executor.spin_once(timeout_sec=0.05)
    publisher = _child('publish', 'cpu', '1000', seconds)
    start, end = None, time.monotonic() + float(seconds) + 10.0
    while time.monotonic() < end:
        if start is None and got[0]:
            start, first = time.process_time(), got[0]
        spin()
        if start is not None and got[0] > first + 900 * float(seconds):
            break
    cpu = time.process_time() - (start or 0.0)
    publisher.kill()
    print(cpu / max(1, got[0] - first) * 1e6, flush=True)
    os._exit(0)


def mask_latency(case, seconds):
    """Read a 200 Hz stream on a wait-set thread; print p99 (ms) and lost."""
    from geometry_msgs.msg import PoseStamped
    from rclpy.node import Node
    from rclpy.serialization import deserialize_message
    _rclpy()

    class Hiding(Node):
        hidden = set()

        @property
        def subscriptions(self):
            return [s for s in super().subscriptions if s not in self.hidden]

        @property
        def waitables(self):
            return [w for w in super().waitables if w not in self.hidden]

    node = Hiding('upstream_mask')
    subscription = node.create_subscription(PoseStamped, 'mask',
                                            lambda m: None, 10, raw=True)
    node.hidden.add(subscription)
    if case == 'hidden':
        node.hidden.update(subscription.event_handlers)
    latencies = []

    def take(data):
        sent = deserialize_message(data, PoseStamped)
        latencies.append(time.time() - sent.pose.position.x)
    _read_on_wait_set(node, subscription, take)
    executor = _executor('single')
    executor.add_node(node)
    publisher = _child('publish', 'mask', '200', seconds)
    end = time.monotonic() + float(seconds) + 20.0
    while time.monotonic() < end and not select.select(
            [publisher.stdout], [], [], 0)[0]:     # streaming
        executor.spin_once(timeout_sec=0.2)
    sent, end = int(publisher.stdout.readline() or 0), time.monotonic() + 0.5
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.1)
    publisher.kill()
    ordered = sorted(latencies)
    print(ordered[int(0.99 * (len(ordered) - 1))] * 1e3,
          sent - len(latencies), flush=True)
    os._exit(0)


def spin_events():
    """Spin an EventsExecutor with spin() for 2 s; print the timer's runs."""
    from rclpy.node import Node
    _rclpy()
    node, runs = Node('upstream_spin'), [0]
    node.create_timer(0.1, lambda: runs.__setitem__(0, runs[0] + 1))
    executor = _executor('events')
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    time.sleep(2.0)
    print(runs[0], flush=True)
    os._exit(0)


def end_of_main():
    """Make a node, shut it down; print the time at the end of main()."""
    from rclpy.node import Node
    from std_msgs.msg import String
    rclpy = _rclpy()
    node = Node('upstream_teardown')
    node.create_publisher(String, 'x', 10)
    node.create_subscription(String, 'x', lambda m: None, 10)
    time.sleep(0.5)
    node.destroy_node()
    rclpy.shutdown()
    print(time.time(), flush=True)


# The checks: each returns (still needed, its figure) ---------------------
def executor_queue(seconds):
    """Check for a bounded executor within 1.3x a wait-set thread's CPU."""
    from geometry_msgs.msg import PoseStamped
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    _rclpy()
    node, ticks = Node('upstream_flood_sink'), []

    def busy(message):      # a callback of 0.2 ms
        end = time.perf_counter() + 0.0002
        while time.perf_counter() < end:
            pass
    node.create_subscription(PoseStamped, 'flood', busy, QoSProfile(
        depth=10, reliability=ReliabilityPolicy.RELIABLE))
    node.create_timer(0.1, lambda: ticks.append(time.monotonic()))
    executor = _executor('events')
    executor.add_node(node)
    flood = _child('publish', 'flood', '0', seconds)
    before, growth = _rss(), 0.0
    end = time.monotonic() + float(seconds) + 15.0
    while not select.select([flood.stdout], [], [], 0)[0]:  # flooding
        executor.spin_once(timeout_sec=0.05)
        growth = max(growth, (_rss() - before) / MiB)
        if time.monotonic() > end:
            break
    sent, ended = int(flood.stdout.readline() or 0), time.monotonic()
    flood.kill()
    while not ticks or ticks[-1] < ended:   # what was queued, then a tick
        executor.spin_once(timeout_sec=0.1)
        if time.monotonic() > ended + 30.0:
            break
    ticks = [t for t in ticks if t > ended - float(seconds)]
    gap = max((b - a for a, b in zip(ticks, ticks[1:])), default=math.inf)
    cpu = {}
    for kind in ('single', 'waitset'):
        helper = _child('sink_cpu', kind, seconds)
        cpu[kind] = float(helper.communicate(timeout=CHECK_TIMEOUT)[0])
    ratio = cpu['single'] / cpu['waitset']
    bounded = growth < 10.0 and gap < 1.0
    return not bounded and ratio > 1.3, (
        f'EventsExecutor under a {seconds} s flood ({sent} sent, depth 10): '
        f'RSS +{growth:.1f} MiB, a 10 Hz timer\'s largest gap {gap:.1f} s; '
        f'SingleThreadedExecutor {cpu["single"]:.0f} us '
        f'per message, {ratio:.2f}x a wait-set thread\'s '
        f'{cpu["waitset"]:.0f} us')


def events_mask(seconds):
    """Check whether an executor holding a reader's events delays its data."""
    figures = {}
    for case in ('visible', 'hidden'):
        helper = _child('mask_latency', case, seconds)
        figures[case] = [float(x) for x in helper.communicate(
            timeout=CHECK_TIMEOUT)[0].split()]
    (p99, lost), (p99_hidden, lost_hidden) = (figures['visible'],
                                              figures['hidden'])
    return p99 > 3.0 * p99_hidden + 5.0 or lost > lost_hidden, (
        f'200 Hz into a wait-set thread, a SingleThreadedExecutor on the '
        f'node: p99 {p99:.1f} ms, {lost:.0f} lost with the events in the '
        f'executor, {p99_hidden:.1f} ms, {lost_hidden:.0f} lost without')


def timer_behind_services(seconds):
    """Check whether a timer waits behind a flood of service requests."""
    from rclpy.node import Node
    from std_srvs.srv import Trigger
    _rclpy()
    node, runs = Node('upstream_server'), []

    def serve(request, response):      # 0.5 ms of work
        end = time.perf_counter() + 0.0005
        while time.perf_counter() < end:
            pass
        response.success = True
        return response
    node.create_service(Trigger, 'checked', serve)
    node.create_timer(0.01, lambda: runs.append(time.monotonic()))
    executor = _executor('events')
    executor.add_node(node)
    requester = _child('request', '3000')
    end = time.monotonic() + float(seconds) + 4.0
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)
    requester.kill()
    gap = max(b - a for a, b in zip(runs, runs[1:])) * 1e3
    return gap > 30.0, (f'100 Hz timer, 3000 requests: largest gap '
                        f'{gap:.0f} ms (3 periods: 30 ms)')


def parameter_type(seconds):
    """Check whether rclpy raises on a parameter value of type 99."""
    from rcl_interfaces.msg import Parameter, ParameterValue
    from rcl_interfaces.srv import SetParameters
    from rclpy.node import Node
    rclpy = _rclpy()
    server, client_node = Node('upstream_params'), Node('upstream_client')
    server.declare_parameter('gain', 1.0)
    executor, raised = _executor('single'), []
    executor.add_node(server)
    client = client_node.create_client(SetParameters,
                                       '/upstream_params/set_parameters')
    client.wait_for_service(5.0)
    future = client.call_async(SetParameters.Request(parameters=[Parameter(
        name='gain', value=ParameterValue(type=99, double_value=2.0))]))
    end = time.monotonic() + 3.0
    while not future.done() and time.monotonic() < end:
        try:
            executor.spin_once(timeout_sec=0.05)
        except Exception as error:  # what the workaround is for
            raised.append(repr(error)[:80])
        rclpy.spin_once(client_node, timeout_sec=0.01)
    return bool(raised) or not future.done(), (
        f'raised {raised[0]}' if raised else
        f'answered: {future.result().results[0].reason}' if future.done()
        else 'no answer')


def reply_stall(seconds):
    """Check whether a reply to an unmatched reader blocks its sender."""
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from std_srvs.srv import Trigger
    rclpy = _rclpy()
    server, client_node = Node('upstream_replies'), Node('upstream_client')
    sends = []

    def answer(request, response):
        response.success = True
        return response
    service = server.create_service(Trigger, 'checked', answer)
    send = service.send_response

    def timed(response, header):
        start = time.perf_counter()
        send(response, header)
        sends.append(time.perf_counter() - start)
    service.send_response = timed
    executor = _executor('single')
    executor.add_node(server)
    client = client_node.create_client(Trigger, 'checked', qos_profile=(
        QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL)))
    client.wait_for_service(5.0)
    for _ in range(3):
        client.call_async(Trigger.Request())
    end = time.monotonic() + 3.0
    while len(sends) < 3 and time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)
        rclpy.spin_once(client_node, timeout_sec=0.01)
    longest = max(sends, default=0.0) * 1e3
    return longest >= 50.0, (f'a reply to an unmatched reader: '
                             f'send_response {longest:.0f} ms')


def writer_guid(seconds):
    """Check whether rclpy exposes the writer GUID of a request's header."""
    from rclpy.impl.implementation_singleton import \
        rclpy_implementation as _impl
    fields = [f for f in dir(_impl.rmw_request_id_t) if not f.startswith('_')]
    return 'writer_guid' not in fields, f'rmw_request_id_t fields: {fields}'


def lifecycle_by_id(seconds):
    """Check whether rclpy raises on a transition id the state lacks."""
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState
    from rclpy.lifecycle import LifecycleNode
    from rclpy.node import Node
    rclpy = _rclpy()
    server, client_node = LifecycleNode('upstream_lc'), Node('upstream_cl')
    executor = _executor('single')
    executor.add_node(server)
    client = client_node.create_client(ChangeState, '/upstream_lc/change_state')
    client.wait_for_service(5.0)
    outcomes = []
    for asked in (Transition(label='deactivate'),
                  Transition(id=Transition.TRANSITION_DEACTIVATE)):
        future = client.call_async(ChangeState.Request(transition=asked))
        raised, end = None, time.monotonic() + 3.0
        while not future.done() and time.monotonic() < end:
            try:
                executor.spin_once(timeout_sec=0.05)
            except Exception as error:  # what the workaround is for
                raised = type(error).__name__
            rclpy.spin_once(client_node, timeout_sec=0.01)
        outcomes.append(f'raised {raised}' if raised else
                        f'success {future.result().success}'
                        if future.done() else 'no answer')
    return not outcomes[1].startswith('success'), (
        f'deactivate when unconfigured: by label {outcomes[0]}, by id '
        f'{outcomes[1]}')


def events_spin(seconds):
    """Check whether the EventsExecutor's spin() runs a timer."""
    runs = int(_child('spin_events').communicate(timeout=30)[0])
    return runs < 10, f'10 Hz timer under spin() for 2 s: {runs} runs'


def logger_severity(seconds):
    """Check whether one call site may log two severities."""
    from rclpy.logging import LoggingSeverity
    from rclpy.node import Node
    _rclpy()
    logger = Node('upstream_logger').get_logger()
    try:
        for level in (LoggingSeverity.INFO, LoggingSeverity.WARN):
            logger.log('upstream check', level)
    except ValueError as error:
        return True, f'raised: {error}'
    return False, 'two severities from one call site'


def qos_profile(seconds):
    """Check whether rclpy writes QoS overrides into the profile given."""
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from rclpy.qos import QoSProfile
    from rclpy.qos_overriding_options import QoSOverridingOptions
    from std_msgs.msg import String
    _rclpy()
    node = Node('upstream_qos', parameter_overrides=[
        Parameter('qos_overrides./a.publisher.depth', value=3)])
    shared = QoSProfile(depth=10)
    node.create_publisher(String, 'a', shared, qos_overriding_options=(
        QoSOverridingOptions.with_default_policies()))
    return shared.depth != 10, (f'override depth 3 on /a: the shared '
                                f'profile\'s depth is now {shared.depth}')


def empty_array_default(seconds):
    """Check whether a DOUBLE_ARRAY descriptor types a ``[]`` default."""
    from rcl_interfaces.msg import ParameterDescriptor, ParameterType
    from rclpy.node import Node
    _rclpy()
    node = Node('upstream_array')
    node.declare_parameter('values', [], ParameterDescriptor(
        type=ParameterType.PARAMETER_DOUBLE_ARRAY))
    kind = node.get_parameter('values').type_
    return kind.name != 'DOUBLE_ARRAY', f'[] declared as double[]: {kind.name}'


def teardown(seconds):
    """Measure the time from the end of main() to the process's exit."""
    spans = []
    for _ in range(3):
        helper = _child('end_of_main')
        ended = float(helper.stdout.readline())
        helper.wait()
        spans.append((time.time() - ended) * 1e3)
    spans.sort()
    return spans[1] >= 5.0, f'end of main() to exit: {spans[1]:.0f} ms median'


CHECKS = (executor_queue, events_mask, timer_behind_services, parameter_type,
          reply_stall, writer_guid, lifecycle_by_id, events_spin,
          logger_severity, qos_profile, empty_array_default, teardown)
HELPERS = (publish, request, sink_cpu, mask_latency, spin_events, end_of_main)


def main():
    """Run the checks asked for, each in a process; print the verdicts."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--only', default='',
                        help='comma-separated check names (default: all)')
    parser.add_argument('--seconds', default='4',
                        help='length of the streams and floods (s)')
    parser.add_argument('--child', nargs='+', help=argparse.SUPPRESS)
    parser.add_argument('--check', help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        {h.__name__: h for h in HELPERS}[args.child[0]](*args.child[1:])
        return 0
    if args.check:
        needed, figure = {c.__name__: c for c in CHECKS}[args.check](
            args.seconds)
        print(f'{"still needed" if needed else "can go"}: {figure}',
              flush=True)
        os._exit(0)
    names = [n for n in args.only.split(',') if n] or [
        c.__name__ for c in CHECKS]
    print(f'upstream checks, ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}:')
    for name in names:
        try:
            done = subprocess.run(
                [sys.executable, __file__, '--check', name, '--seconds',
                 args.seconds], capture_output=True, text=True,
                timeout=CHECK_TIMEOUT)
            lines = done.stdout.strip().splitlines() or [
                f'no verdict (exit {done.returncode}): '
                f'{done.stderr.strip()[-200:]}']
            verdict = lines[-1]
        except subprocess.TimeoutExpired:
            verdict = f'no verdict: timed out after {CHECK_TIMEOUT:g} s'
        print(f'  {name:22s} {verdict}', flush=True)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
