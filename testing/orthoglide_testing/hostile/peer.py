"""
The hostile cases' actors: a peer in this process, the nodes as processes.

:class:`Peer` is an rclpy node spun by a thread of its own that records
topics and diagnostics and calls services; :class:`Nodes` starts the
nodes from their console scripts and stops every one of them.
"""

import threading
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter_client import AsyncParameterClient

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import (Transform, Twist)
from rcl_interfaces.srv import GetParameters
from trajectory_msgs.msg import (MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint)

from orthoglide_testing.checkout import params_file
from orthoglide_testing.load import (realtime_args, realtime_client)
from orthoglide_testing.messages import qos_profile
from orthoglide_testing.processes import (node_executable,
                                          start_node_process, stop_process)
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot

NODES = ('feedforward', 'simulator', 'tracking_controller',
         'setpoint_publisher')
START_TIMEOUT = 20.0    # s for nodes to appear and answer
LOG_LINE_LIMIT = 10000  # characters: the longest log line accepted
HOLD = mechanics.solve(Robot(), (0.0, 0.0, 0.0)).force   # N, at home


class HarnessError(RuntimeError):
    """A case could not run (a node did not start, a peer failed)."""


# A peer in this process ------------------------------------------------------
class Peer:
    """
    An rclpy node in this process, spun by a thread of its own.

    ``record(topic, kind)`` keeps ``(monotonic s, message)`` of a topic
    until ``forget(topic)``;
    ``diagnostics[name]`` the newest ``{key: value}`` and level per node.
    ``realtime``: this process at CLIENT_PRIORITY while it records (the
    timing cases). Use it as a context manager.
    """

    def __init__(self, name='hostile_peer', realtime=False):
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.records = {}
        self._subscriptions = {}
        self.diagnostics = {}
        self.lock = threading.Lock()
        self.node.create_subscription(DiagnosticArray, '/diagnostics',
                                      self._on_diagnostics,
                                      qos_profile('reliable', 100))
        self._stop = False
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()
        self._realtime = realtime_client(realtime)
        self._realtime.__enter__()

    def _spin(self):
        while not self._stop and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:   # shutting down
                if self._stop:
                    return
                raise

    def _on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                node = status.name.split(':')[0]
                self.diagnostics[node] = (
                    status.level[0] if isinstance(status.level, bytes)
                    else status.level, status.message,
                    {kv.key: kv.value for kv in status.values},
                    time.monotonic())

    def record(self, topic, kind, depth=1000):
        """Record every message of ``topic``: a list of (time, message)."""
        log = self.records.setdefault(topic, [])

        def on_message(msg):
            log.append((time.monotonic(), msg))
        self._subscriptions[topic] = self.node.create_subscription(
            kind, topic, on_message, qos_profile('reliable', depth))
        return log

    def forget(self, topic):
        """
        Stop recording ``topic`` (its log stays).

        For a topic whose rate would keep this process busy (a simulator's
        states at 10 kHz) once the case has what it needs of it.
        """
        self.node.destroy_subscription(self._subscriptions.pop(topic))

    def publisher(self, kind, topic, depth=10):
        """Return a reliable publisher of ``kind`` on ``topic``."""
        return self.node.create_publisher(kind, topic,
                                          qos_profile('reliable', depth))

    def status(self, node, after=None, timeout=5.0):
        """
        Return ``(level, message, values)`` of ``node``'s diagnostics.

        The first received after the monotonic time ``after`` (default:
        now), waiting up to ``timeout`` s; None if none came.
        """
        after = time.monotonic() if after is None else after
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self.lock:
                found = self.diagnostics.get(node)
            if found is not None and found[3] > after:
                return found[:3]
            time.sleep(0.05)
        return None

    def call(self, srv_type, name, request, timeout=10.0):
        """Call a service; return its response (None: no answer)."""
        client = self.node.create_client(srv_type, name)
        try:
            if not client.wait_for_service(timeout_sec=timeout):
                return None
            future = client.call_async(request)
            deadline = time.monotonic() + timeout
            while not future.done() and time.monotonic() < deadline:
                time.sleep(0.01)
            return future.result() if future.done() else None
        finally:
            self.node.destroy_client(client)

    def set_parameters(self, node, parameters, timeout=10.0):
        """Set ``{name: value}`` on ``node``; return the results."""
        client = AsyncParameterClient(self.node, node)
        if not client.wait_for_services(timeout_sec=timeout):
            return None
        from rclpy.parameter import Parameter
        future = client.set_parameters(
            [Parameter(k, value=v) for k, v in parameters.items()])
        deadline = time.monotonic() + timeout
        while not future.done() and time.monotonic() < deadline:
            time.sleep(0.01)
        return future.result().results if future.done() else None

    def wait(self, predicate, timeout):
        """Wait until ``predicate()`` holds; return whether it did."""
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                return predicate()
            time.sleep(0.02)
        return True

    def close(self):
        """Stop spinning, destroy the node, shut the context down."""
        self._realtime.__exit__(None, None, None)
        self._stop = True
        self._thread.join(5.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Nodes:
    """
    Node processes started from their console scripts; all stopped.

    ``realtime``: every node at NODE_PRIORITY (the timing cases).
    """

    def __init__(self, realtime=False):
        self.processes = {}
        self.results = {}
        self.realtime = realtime

    def start(self, name, *args, params=True):
        """Start ``name`` with ``args`` (after ``--ros-args``)."""
        extra = ['--params-file', str(params_file())] if params else []
        self.processes[name] = start_node_process(
            ['--ros-args', *extra, *realtime_args(self.realtime), *args],
            command=[node_executable(name)])
        return self.processes[name]

    def alive(self, name):
        """Whether the process still runs."""
        return self.processes[name].poll() is None

    def stop(self, name):
        """Stop one (SIGINT); keep and return (exit code, stderr)."""
        self.results[name] = stop_process(self.processes.pop(name))
        return self.results[name]

    def close(self):
        """Stop every process still running."""
        for name in list(self.processes):
            self.stop(name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def wait_running(peer, names, timeout=START_TIMEOUT):
    """Wait until every node answers get_parameters; raise if not."""
    for name in names:
        answer = peer.call(GetParameters, f'/{name}/get_parameters',
                           GetParameters.Request(names=['use_sim_time']),
                           timeout)
        if answer is None:
            raise HarnessError(f'{name} did not answer')


def handshake(peer, publish, arrived, timeout=START_TIMEOUT, every=0.05):
    """
    ``publish(k)`` every ``every`` s until ``arrived()``; return how many.

    A reliable writer matches its reader before the reader matches the
    writer, and a volatile reader drops what came before: the first
    message whose effect is seen proves the path. A HarnessError after
    ``timeout`` s.
    """
    deadline = time.monotonic() + timeout
    sent = 0
    while True:
        publish(sent)
        sent += 1
        if peer.wait(arrived, every):
            return sent
        if time.monotonic() > deadline:
            raise HarnessError('no message went through')


def diagnostic_counter(peer, node, key):
    """Return a counter of ``node``'s newest diagnostics (-1: none yet)."""
    with peer.lock:
        found = peer.diagnostics.get(node)
    return int(found[2].get(key, -1)) if found else -1


def log_lines(text):
    """Return the log lines of a stderr text (stdout part included)."""
    return [line for line in text.splitlines() if line.strip()]


def home_setpoint(frame, stamp=(5, 0), offset=(0, 0)):
    """Return a one-point MultiDOFJointTrajectory at home, at rest."""
    msg = MultiDOFJointTrajectory(points=[MultiDOFJointTrajectoryPoint(
        transforms=[Transform()], velocities=[Twist()],
        accelerations=[Twist()])])
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    point = msg.points[0]
    point.transforms[0].rotation.w = 1.0
    point.time_from_start.sec, point.time_from_start.nanosec = offset
    return msg
