"""
Every node as ``ros2 run`` starts it: it starts, answers, exits 0 on Ctrl-C.

One rule for the six console scripts: started with the shipped
parameters file (and an override, as a user would), the node answers a
``get_parameters`` call over DDS with the value its parameters file and
its core's table give, keeps running, and SIGINT ends it with exit code
0 within PROMPT seconds and no traceback.
"""

import os

import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter_client import AsyncParameterClient

from node_checks import assert_clean_exit
from orthoglide_testing.probe import spin_until
from orthoglide_testing.processes import (node_executable,
                                          start_node_process, timed_stop)

pytestmark = pytest.mark.ros

CONFIG = os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), 'config', 'orthoglide.yaml')
START_WAIT = 40.0   # s for a process to come up and answer
PROMPT = 5.0        # s from SIGINT to exit
# name: (override, the parameter asked for, its value)
NODES = {
    'feedforward': ('rate_hz:=250.0', 'rate_hz', 250.0),
    'tracking_controller': ('measurement_timeout:=30.0',
                            'measurement_timeout', 30.0),
    'simulator': ('rate_hz:=100.0', 'rate_hz', 100.0),
    'setpoint_publisher': ('loop:=true', 'loop', True),
    'mechanism_state_publisher': ('singularity_margin:=0.3',
                                  'singularity_margin', 0.3),
    'planner': ('rate_hz:=500.0', 'rate_hz', 500.0),
}


@pytest.mark.parametrize('name', sorted(NODES))
def test_starts_answers_and_exits_0_on_sigint(ros_context, name):
    override, parameter, value = NODES[name]
    if not os.path.exists(node_executable(name)):
        pytest.skip(f'the console script {name} is not installed')
    probe = Node(f'process_probe_{name}', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(probe)
    proc = start_node_process(['--ros-args', '--params-file', CONFIG, '-p',
                               override], command=[node_executable(name)])
    try:
        client = AsyncParameterClient(probe, name)
        assert spin_until(executor, client.services_are_ready, START_WAIT), \
            f'{name} did not answer on the graph'
        future = client.get_parameters([parameter])
        assert spin_until(executor, future.done, START_WAIT)
        answer = future.result().values[0]
        assert (answer.bool_value if isinstance(value, bool)
                else answer.double_value) == value
        assert proc.poll() is None, f'{name} exited by itself'
    finally:
        stopped = timed_stop(proc)
        executor.shutdown()
        probe.destroy_node()
    assert_clean_exit(*stopped, PROMPT)
