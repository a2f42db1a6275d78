"""
``colcon build`` of the package, and its installed node talking over DDS.

Builds the repository into a temporary directory (build, install and log
there, the source tree untouched) and runs what ``ros2 run orthoglide_ros
feedforward`` runs: ``install/orthoglide_ros/lib/orthoglide_ros/feedforward``
with the install tree's site-packages first on PYTHONPATH, so the code under
test is the installed copy.
"""

import os
from pathlib import Path
import subprocess
import sys

import pytest
from rclpy.executors import SingleThreadedExecutor

from orthoglide_ros.model import mechanics
from orthoglide_ros.formats.params_file import load_robot
from orthoglide_ros.model.trajectory import paper_sample

from node_checks import close  # noqa: E402
from orthoglide_testing.messages import header_stamp  # noqa: E402
from orthoglide_testing.probe import Probe, spin_until  # noqa: E402
from orthoglide_testing.processes import (node_executable,  # noqa: E402
                                          start_node_process, stop_process)

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = 'orthoglide_ros'
COLCON = node_executable('colcon')
BUILD_TIMEOUT = 300.0
WAIT = 40.0

pytestmark = [pytest.mark.ros, pytest.mark.skipif(
    not os.path.exists(COLCON),
    reason='colcon is not installed next to python')]


@pytest.fixture(scope='module')
def install(tmp_path_factory):
    """Run colcon build once; return the package's install prefix."""
    tmp = tmp_path_factory.mktemp('colcon')
    before = {p.name for p in ROOT.iterdir()}
    result = subprocess.run(
        [COLCON, 'build', '--base-paths', str(ROOT),
         '--build-base', str(tmp / 'build'),
         '--install-base', str(tmp / 'install')],
        cwd=tmp, env=os.environ, stdin=subprocess.DEVNULL,
        capture_output=True, text=True, timeout=BUILD_TIMEOUT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert f'Finished <<< {PACKAGE}' in result.stdout, result.stdout
    assert (tmp / 'log').is_dir()
    created = {p.name for p in ROOT.iterdir()} - before
    assert not created & {'build', 'install', 'log'}, created
    return tmp / 'install' / PACKAGE


def install_env(prefix):
    """Return os.environ with the install tree's site-packages first."""
    site = prefix / 'lib' / (f'python{sys.version_info.major}.'
                             f'{sys.version_info.minor}') / 'site-packages'
    assert site.is_dir(), site
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(
        [str(site)] + [p for p in [env.get('PYTHONPATH')] if p])
    env['AMENT_PREFIX_PATH'] = os.pathsep.join(
        [str(prefix)] + [p for p in [env.get('AMENT_PREFIX_PATH')] if p])
    return env, site


def test_install_layout(install):
    """Executables, config, URDF, package.xml and the ament index are installed."""
    for relative in ('lib/orthoglide_ros/feedforward',
                     'lib/orthoglide_ros/orthoglide',
                     'lib/orthoglide_ros/tracking_controller',
                     'lib/orthoglide_ros/simulator',
                     'lib/orthoglide_ros/mechanism_state_publisher',
                     'lib/orthoglide_ros/planner'):
        path = install / relative
        assert path.is_file() and os.access(path, os.X_OK), relative
    for name in ('orthoglide.yaml', 'fastdds_one_host.xml',
                 'orthoglide.rviz'):
        assert (install / 'share' / PACKAGE / 'config' / name
                ).read_text() == (ROOT / 'config' / name).read_text()
    # The URDF that robot_state_publisher reads as robot_description.
    assert (install / 'share' / PACKAGE / 'urdf' / 'orthoglide.urdf'
            ).read_text() == (ROOT / 'urdf' / 'orthoglide.urdf').read_text()
    assert (install / 'share' / PACKAGE / 'package.xml').is_file()
    assert (install / 'share' / 'ament_index' / 'resource_index'
            / 'packages' / PACKAGE).is_file()


def test_install_holds_the_package_and_no_test_support(install):
    """Every module of orthoglide_ros/ is installed, no other Python file."""
    _, site = install_env(install)
    installed = {str(p.relative_to(site)) for p in site.rglob('*.py')}
    product = {str(p.relative_to(ROOT))
               for p in (ROOT / 'orthoglide_ros').rglob('*.py')}
    assert installed == product, installed ^ product
    support = [str(p.relative_to(install)) for p in install.rglob('*')
               if any(name in p.name for name in
                      ('orthoglide_testing', 'harness', 'conftest'))
               or p.name in ('test', 'scripts', 'benchmarks', 'testing')]
    assert support == []


def test_installed_code_is_used_and_cli_runs(install):
    """
    PYTHONPATH makes the install tree win; ``orthoglide --help`` runs.

    Run from the install prefix, as ``ros2 run`` may be run from anywhere
    (from the repository, ``python -c`` would import the source tree).
    """
    env, site = install_env(install)
    found = subprocess.run(
        [sys.executable, '-c',
         'import orthoglide_ros; print(orthoglide_ros.__file__)'],
        env=env, cwd=install, capture_output=True, text=True, timeout=60)
    assert found.returncode == 0, found.stderr
    assert found.stdout.strip().startswith(str(site)), found.stdout
    cli = subprocess.run(
        [str(install / 'lib' / PACKAGE / 'orthoglide'), '--help'],
        env=env, cwd=install, capture_output=True, text=True, timeout=60)
    assert cli.returncode == 0, cli.stderr
    assert cli.stdout.startswith('usage: orthoglide'), cli.stdout
    assert 'Traceback' not in cli.stderr


def test_installed_node_over_dds(install, ros_context):
    """One setpoint -> one joint state = mechanics.solve; SIGINT -> 0."""
    env, _ = install_env(install)
    params = install / 'share' / PACKAGE / 'config' / 'orthoglide.yaml'
    robot = load_robot(params)
    probe = Probe(ros_context, name='colcon_probe')
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(probe)
    proc = start_node_process(['--ros-args', '--params-file', str(params)],
                              env=env, cwd=install,
                              command=[str(install / 'lib' / PACKAGE /
                                           'feedforward')])
    try:
        probe.handshake(executor, WAIT)
        p, v, a = paper_sample(1.25)
        probe.send_trajectory((4000, 0), p, v, a)
        assert spin_until(executor, lambda: probe.joint_states
                          and probe.forces and probe.power, WAIT)
        spin_until(executor, lambda: False, 0.2)
        assert len(probe.joint_states) == 1
        joints = probe.joint_states[0]
        expected = mechanics.solve(robot, p, v, a)
        assert header_stamp(joints) == (4000, 0)
        for got, want in ((joints.position, expected.lambda_),
                          (joints.velocity, expected.lambdadot),
                          (joints.effort, expected.force),
                          (probe.power[0].data, expected.power)):
            assert len(got) == 3
            assert all(close(g, w) for g, w in zip(got, want)), (got, want)
    finally:
        code, stderr = stop_process(proc)
        executor.shutdown()
        probe.destroy_node()
    assert code == 0, f'exit code {code}; stderr:\n{stderr}'
    assert 'Traceback' not in stderr, stderr
