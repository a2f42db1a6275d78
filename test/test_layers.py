"""
The layers: the model, the formats, the cores and the tool without rclpy.

A fresh interpreter whose import system refuses rclpy (and every ROS
message package) imports every module of ``model``, ``formats``,
``cores`` and ``tools``, and runs ``orthoglide solve``, ``batch``,
``urdf``, ``draw`` and ``identify`` on a CSV log: where ROS is not
installed they work the same. Only ``ros`` may import rclpy.
"""

import os
import pkgutil
import subprocess
import sys

import pytest

import orthoglide_ros

HERE = os.path.dirname(os.path.abspath(__file__))
ROS_FREE = ('model', 'formats', 'cores', 'tools')
# An import hook refusing rclpy and the message packages, then the code.
REFUSE_ROS = '''
import sys
class RefuseRos:
    def find_spec(self, name, path=None, target=None):
        top = name.split('.')[0]
        if top in ('rclpy', 'rosidl_runtime_py') or top.endswith('_msgs') \\
                or top.endswith('_srvs') or top == 'rcl_interfaces':
            raise ImportError(f'{name} refused: ROS must not be imported')
sys.meta_path.insert(0, RefuseRos())
'''


def run_without_ros(code, *args, cwd=None):
    return subprocess.run(
        [sys.executable, '-c', REFUSE_ROS + code, *args], cwd=cwd,
        capture_output=True, text=True, timeout=300)


def ros_free_modules():
    root = os.path.dirname(orthoglide_ros.__file__)
    return [f'orthoglide_ros.{package}.{module.name}'
            for package in ROS_FREE
            for module in pkgutil.iter_modules([os.path.join(root, package)])]


def test_the_layers_are_the_folders():
    root = os.path.dirname(orthoglide_ros.__file__)
    folders = sorted(entry for entry in os.listdir(root)
                     if os.path.isdir(os.path.join(root, entry))
                     and not entry.startswith('__'))
    assert folders == sorted(ROS_FREE + ('ros',))
    modules = [m.name for m in pkgutil.iter_modules([root]) if not m.ispkg]
    assert modules == [], f'modules outside a layer: {modules}'


def test_model_formats_cores_and_tools_import_without_rclpy():
    modules = ros_free_modules()
    assert len(modules) > 15
    result = run_without_ros(
        'import importlib\n'
        f'for name in {modules!r}:\n'
        '    importlib.import_module(name)\n'
        'assert "rclpy" not in sys.modules\n')
    assert result.returncode == 0, result.stderr


def test_the_hook_refuses_rclpy():
    """The test above can fail: the glue does not import here."""
    result = run_without_ros('import orthoglide_ros.ros.feedforward_node')
    assert result.returncode != 0 and 'refused' in result.stderr


def test_the_tool_works_without_rclpy(tmp_path):
    from test_cli import identification_log
    source, _ = identification_log(tmp_path, duration=20.0)
    trajectory = tmp_path / 'in.csv'
    trajectory.write_text('t,x,y,z\n0,0,0,0\n0.1,0.01,0,0\n')
    for argv in (['solve', '--position', '0.05', '0.1', '-0.2'],
                 ['batch', '--input', str(trajectory)],
                 ['urdf', '--output', str(tmp_path / 'robot.urdf')],
                 ['draw', '--position', '0', '0', '0', '--output',
                  str(tmp_path / 'robot.png')],
                 ['identify', '--input', str(source), '--output',
                  str(tmp_path / 'robot.yaml')]):
        result = run_without_ros(
            'from orthoglide_ros.tools.cli import main\n'
            'code = main(sys.argv[1:])\n'
            'assert "rclpy" not in sys.modules\n'
            'sys.exit(code)\n', *argv, cwd=tmp_path)
        assert result.returncode == 0, (argv, result.stderr)
    assert (tmp_path / 'robot.yaml').exists()


def test_record_says_it_needs_ros_without_it(tmp_path):
    result = run_without_ros(
        'from orthoglide_ros.tools.cli import main\n'
        'sys.exit(main(sys.argv[1:]))\n', 'record', '--output',
        str(tmp_path / 'bag'), '--duration', '1')
    assert result.returncode == 2
    assert 'record needs ROS 2 (rclpy)' in result.stderr


pytestmark = pytest.mark.filterwarnings('ignore::DeprecationWarning')
