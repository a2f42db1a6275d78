"""
Isolation of the feedforward node: its graph apart from others on the host.

The node runs with discovery limited to this host and in the session's own
ROS domain (``test/conftest.py`` sets both for everything the tests start):
its process environment says so, a probe in the same domain gets its
outputs, and a probe one domain over neither sees it on the graph nor
reaches it with setpoints. The node runs in a namespace of its own, so that
another session in the neighbouring domain cannot be mistaken for it.
"""

import os
from pathlib import Path
import time

import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor

from node_checks import needs_scripts
from orthoglide_testing.probe import Probe, spin_for
from orthoglide_testing.processes import start_node_process, stop_process
from orthoglide_testing.processes import process_environment

PARAMS = Path(__file__).resolve().parents[1] / 'config' / 'orthoglide.yaml'
START_WAIT = 30.0   # s for the node to come up and answer
QUIET = 3.0         # s the probe in the other domain listens and sends

pytestmark = [pytest.mark.ros, needs_scripts()]


def _probe(domain, namespace):
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    probe = Probe(context, namespace=namespace)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(probe)
    return context, probe, executor


def test_localhost_own_domain_invisible_from_another():
    """LOCALHOST and the session's domain; nothing crosses to domain + 1."""
    domain = int(os.environ['ROS_DOMAIN_ID'])
    other = domain + 1 if domain < 232 else domain - 1
    namespace = f'/isolation_{os.getpid()}'
    proc = start_node_process(['--ros-args', '--params-file', str(PARAMS),
                               '-r', f'__ns:={namespace}'])
    made = []
    try:
        made.append(_probe(domain, namespace))
        _, near, near_executor = made[-1]
        near.handshake(near_executor, START_WAIT)    # it answers here
        # Read once it runs: right after exec the kernel may not have set
        # the new environment up yet.
        environment = process_environment(proc.pid)
        assert environment.get('ROS_AUTOMATIC_DISCOVERY_RANGE') == \
            'LOCALHOST'
        assert environment.get('ROS_DOMAIN_ID') == str(domain)
        assert ('feedforward', namespace) in \
            near.get_node_names_and_namespaces()
        made.append(_probe(other, namespace))
        _, far, far_executor = made[-1]
        deadline = time.monotonic() + QUIET
        sent = 0
        while time.monotonic() < deadline:
            sent += 1
            far.send_trajectory((1, sent), (0.0, 0.0, 0.0))
            spin_for(far_executor, 0.05)
        assert sent > 10
        assert far.joint_states == [] and far.forces == [] \
            and far.power == []
        assert all(p.get_subscription_count() == 0
                   for p in far.publishers_by_input.values())
        assert ('feedforward', namespace) not in \
            far.get_node_names_and_namespaces()
        assert proc.poll() is None
    finally:
        for context, probe, executor in made:
            executor.shutdown()
            probe.destroy_node()
            rclpy.try_shutdown(context=context)
        code, stderr = stop_process(proc)
    assert code == 0, stderr
