"""
Tests of the feedforward node as a process, started from its console script.

``feedforward --ros-args --params-file config/orthoglide.yaml``, as a user
runs it; the test talks to it over DDS (on localhost, in the session's
domain: see conftest) and stops it with SIGINT, as Ctrl-C does.
"""

import contextlib
from pathlib import Path
import sys
import time

import pytest

from orthoglide_ros.model import mechanics
from orthoglide_ros.formats.params_file import load_robot
from orthoglide_ros.model.trajectory import paper_sample, paper_times

from node_checks import assert_vector, needs_scripts  # noqa: E402
from orthoglide_testing.messages import header_stamp  # noqa: E402
from orthoglide_testing.probe import probed, spin_until  # noqa: E402
from orthoglide_testing.processes import (start_node_process,  # noqa: E402
                                          stop_process, wait_exit)

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / 'config' / 'orthoglide.yaml'
WAIT = 15.0         # s for one answer: generous, the machine is shared
START_WAIT = 40.0   # s for the process to come up and answer
PROMPT = 5.0        # s from SIGINT to exit

pytestmark = [pytest.mark.ros, needs_scripts()]


@pytest.fixture
def probe_graph(ros_context):
    """Return make(**probe_kwargs) -> (probe, executor); cleaned up after."""
    with contextlib.ExitStack() as made:
        yield lambda **kwargs: made.enter_context(
            probed(ros_context, **kwargs))


def wait_count(executor, probe, count, timeout=WAIT):
    """Spin until ``count`` joint states, forces and powers have arrived."""
    assert spin_until(executor, lambda: min(
        len(probe.joint_states), len(probe.forces), len(probe.power))
        >= count, timeout), f'expected {count} outputs'


def report(code, stderr):
    """Print the node's exit code and stderr (shown if the test fails)."""
    print(f'node exit code {code}; stderr:\n{stderr}', file=sys.stderr)


def assert_clean_exit(code, stderr, elapsed):
    """Exit code 0 within PROMPT s of SIGINT, and no Python traceback."""
    assert code == 0, f'exit code {code} after SIGINT; stderr:\n{stderr}'
    assert elapsed < PROMPT, f'took {elapsed:.1f} s to exit after SIGINT'
    assert 'Traceback' not in stderr, stderr


def test_paper_trajectory_over_dds_then_sigint(probe_graph):
    """Eq. (6) on the trajectory input: outputs = mechanics.solve; Ctrl-C."""
    robot = load_robot(PARAMS)
    probe, executor = probe_graph()
    proc = start_node_process(['--ros-args', '--params-file', str(PARAMS)])
    try:
        probe.handshake(executor, START_WAIT)
        for k, t in enumerate(float(t) for t in paper_times(50)):
            p, v, a = paper_sample(t)
            offset = divmod(round(t * 1e9), 10**9)
            probe.send_trajectory((2000, 0), p, v, a, frame='base_link',
                                  time_from_start=offset)
            wait_count(executor, probe, k + 1)
            expected = mechanics.solve(robot, p, v, a)
            joints = probe.joint_states[k]
            assert header_stamp(joints) == (2000 + offset[0], offset[1])
            assert list(joints.name) == ['slider_a', 'slider_b', 'slider_c']
            assert_vector(joints.position, expected.lambda_, 'lambda')
            assert_vector(joints.velocity, expected.lambdadot, 'lambdadot')
            assert_vector(joints.effort, expected.force, 'force')
            assert list(probe.forces[k].data) == list(joints.effort)
            assert_vector(probe.power[k].data, expected.power, 'power')
        assert proc.poll() is None, 'the node exited by itself'
    finally:
        start = time.monotonic()
        code, stderr = stop_process(proc)
        elapsed = time.monotonic() - start
        report(code, stderr)
    assert_clean_exit(code, stderr, elapsed)


@pytest.mark.parametrize('old, new, word, exit_code', [
    ('m5: 15.0', 'm5: -1.0', 'robot.m5', 2),            # our validation
    ('l3: 0.85', 'l3: 1', 'robot.l3', None),            # rclpy's typing
    ('    robot:', '    pairing_timeout: 0.5\n    robot:', 'pairing_timeout',
     2),
    # rcl's parser refuses a mixed array before any node exists; its
    # message names the file (and line), not the parameter.
    ('gravity: [0.0, 0.0, -9.81]', 'gravity: [0, 0, -9.81]', 'bad.yaml',
     None),
], ids=['m5_negative', 'l3_integer', 'pairing_above_setpoint_timeout',
        'gravity_mixed_array'])
def test_invalid_params_file_refused(tmp_path, old, new, word, exit_code):
    """The process exits non-zero, says why, without a traceback."""
    text = PARAMS.read_text()
    assert old in text
    bad = tmp_path / 'bad.yaml'
    bad.write_text(text.replace(old, new, 1))
    proc = start_node_process(['--ros-args', '--params-file', str(bad)])
    try:
        code = wait_exit(proc, START_WAIT)
    finally:
        code, stderr = stop_process(proc)
    assert code is not None and code != 0, stderr
    if exit_code is not None:
        assert code == exit_code, stderr
    assert 0 < code < 128, f'killed by a signal? {code}'
    assert word in stderr, stderr
    assert 'Traceback' not in stderr, stderr


def test_remapped_forces_topic(probe_graph):
    """-r feedforward/forces:=/effort_controller/commands publishes there."""
    robot = load_robot(PARAMS)
    probe, executor = probe_graph(forces_topic='/effort_controller/commands')
    proc = start_node_process([
        '--ros-args', '--params-file', str(PARAMS),
        '-r', 'feedforward/forces:=/effort_controller/commands'])
    try:
        probe.handshake(executor, START_WAIT)
        p, v, a = paper_sample(1.0)
        probe.send_trajectory((3000, 0), p, v, a)
        wait_count(executor, probe, 1)
        expected = mechanics.solve(robot, p, v, a)
        assert_vector(probe.forces[0].data, expected.force, 'force')
        assert list(probe.forces[0].data) == list(
            probe.joint_states[0].effort)
        publishers = {
            topic: [i.node_name for i in
                    probe.get_publishers_info_by_topic(topic)]
            for topic in ('/effort_controller/commands',
                          '/feedforward/forces')}
        assert publishers == {'/effort_controller/commands': ['feedforward'],
                              '/feedforward/forces': []}
    finally:
        report(*stop_process(proc))
