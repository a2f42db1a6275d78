"""
The file ``orthoglide calibrate`` writes, read as is by the other nodes.

Not the feedforward's section alone: started with ``--params-file`` of
calibrate's output, the ``mechanism_state_publisher`` and the
``simulator`` (two nodes that model the robot, as ``ros2 run`` starts
them) answer a ``get_parameters`` call over DDS with the calibrated
``robot.*`` rows, the ones the file holds, not the drawing's.
"""

import numpy as np
import pytest
from rcl_interfaces.msg import ParameterType
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter_client import AsyncParameterClient

from node_checks import needs_scripts
from orthoglide_testing.probe import spin_until
from orthoglide_testing.processes import (node_executable,
                                          start_node_process, stop_process)
from orthoglide_testing.robots_as_built import BUILT
from orthoglide_ros.formats import params_file
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools import cli

pytestmark = [pytest.mark.ros,
              needs_scripts('mechanism_state_publisher', 'simulator')]

START_WAIT = 40.0   # s for a process to come up and answer


@pytest.fixture(scope='module')
def calibrated(tmp_path_factory):
    """Write what calibrate makes of a built machine's 20 positions."""
    folder = tmp_path_factory.mktemp('calibrated')
    positions = np.random.default_rng(5).uniform(-0.25, 0.25, (20, 3))
    lam = mechanics.solve_batch(Robot(), positions).lambda_
    readings = mechanics.forward_kinematics(Robot(**BUILT), lam)
    measurements = folder / 'measurements.csv'
    measurements.write_text('lambda_a,lambda_b,lambda_c,x,y,z\n' + ''.join(
        ','.join(map(repr, row)) + '\n'
        for row in np.column_stack((lam, readings)).tolist()))
    output = folder / 'robot.yaml'
    assert cli.main(['calibrate', '--input', str(measurements),
                     '--output', str(output)]) == 0
    return output


@pytest.mark.parametrize('name', ['mechanism_state_publisher', 'simulator'])
def test_a_node_started_with_the_calibrated_file_has_its_legs(
        ros_context, calibrated, name):
    robot = params_file.load_robot(calibrated)
    assert not robot.as_drawn
    probe = Node(f'calibrated_probe_{name}', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(probe)
    proc = start_node_process(['--ros-args', '--params-file',
                               str(calibrated)],
                              command=[node_executable(name)])
    try:
        client = AsyncParameterClient(probe, name)
        assert spin_until(executor, client.services_are_ready, START_WAIT), \
            f'{name} did not answer: {stop_process(proc)}'
        names = Robot.parameter_names()
        future = client.get_parameters([f'robot.{n}' for n in names])
        assert spin_until(executor, future.done, START_WAIT)
        values = {n: list(v.double_array_value)
                  if v.type == ParameterType.PARAMETER_DOUBLE_ARRAY
                  else v.double_value
                  for n, v in zip(names, future.result().values)}
        assert Robot(**values) == robot
        assert proc.poll() is None, stop_process(proc)
    finally:
        stop_process(proc)
        executor.shutdown()
        probe.destroy_node()
