"""
Every loop node started real-time runs every thread so, and says so.

Real processes on real DDS, started as ``ros2 run`` does with only the
real-time parameters added (no ``chrt``, no ``taskset``): once a node
answers on the graph, every thread of its process (Fast DDS's included)
is SCHED_FIFO at ``thread_priority`` on ``cpu_affinity``, with memory
locked (``VmLck``), read here by the standard library per thread. The
feedforward's diagnostics report what holds; with the OS refusing
(``setpriv`` drops CAP_SYS_NICE and CAP_IPC_LOCK: root's limits here are
rtprio 0 and memlock 8 MiB) it warns once per setting, naming the limit
and the fix, and serves setpoints at normal scheduling, its diagnostics
WARN; a value no node can have exits 2 with one line; the parameters are
read-only.
"""

import os
import re
import shutil
import time

import pytest
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient

from node_checks import needs_scripts
from orthoglide_testing.probe import probed, spin_until, wait_diagnostics
from orthoglide_testing.processes import (node_executable, run_to_exit,
                                          start_node_process, stop_process)
from orthoglide_ros.cores import realtime

pytestmark = [pytest.mark.ros, needs_scripts(
    'feedforward', 'tracking_controller', 'simulator', 'setpoint_publisher',
    'mechanism_state_publisher')]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIG = os.path.join(ROOT, 'config', 'orthoglide.yaml')
START_WAIT = 40.0
PRIORITY = 50
CPU = realtime.machine_cpus()[-1]
REAL_TIME = ['-p', f'thread_priority:={PRIORITY}',
             '-p', f'cpu_affinity:=[{CPU}]', '-p', 'lock_memory:=true']
# Extra arguments that keep a node running until it is stopped.
KEEP = {'setpoint_publisher': ['-p', 'loop:=true']}
DROP_CAPABILITIES = ('setpriv', '--bounding-set=-sys_nice,-ipc_lock')
needs_root = pytest.mark.skipif(
    os.geteuid() != 0, reason='SCHED_FIFO and mlockall need root here')


def threads_of(pid):
    """Return {tid: (policy, priority, CPUs)} of every thread of ``pid``."""
    held = {}
    for name in os.listdir(f'/proc/{pid}/task'):
        tid = int(name)
        try:
            held[tid] = (os.sched_getscheduler(tid),
                         os.sched_getparam(tid).sched_priority,
                         frozenset(os.sched_getaffinity(tid)))
        except ProcessLookupError:
            continue
    return held


def wait_for_log(proc, words, timeout=START_WAIT):
    """Wait until the process's standard error holds ``words``."""
    err = proc.output_files[1]
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        err.seek(0)
        if words in err.read().decode('utf-8', 'replace'):
            return
        time.sleep(0.05)
    raise AssertionError(f'no {words!r} in the log of {proc.args}')


def locked_kb(pid):
    with open(f'/proc/{pid}/status') as f:
        return next(int(line.split()[1]) for line in f
                    if line.startswith('VmLck:'))


@pytest.fixture
def graph(ros_context):
    with probed(ros_context, name='realtime_probe') as made:
        yield made


def answering(probe, executor, name):
    client = AsyncParameterClient(probe, name)
    assert spin_until(executor, client.services_are_ready, START_WAIT), (
        f'{name} did not answer on the graph')
    return client


@needs_root
@pytest.mark.parametrize('name', ['feedforward', 'tracking_controller',
                                  'simulator', 'setpoint_publisher',
                                  'mechanism_state_publisher'])
def test_every_thread_of_the_node_is_fifo_on_its_cpu_memory_locked(
        graph, name):
    probe, executor = graph
    proc = start_node_process(
        ['--ros-args', '--params-file', CONFIG, *REAL_TIME,
         *KEEP.get(name, [])], command=[node_executable(name)])
    try:
        client = answering(probe, executor, name)
        wait_for_log(proc, 'real time: ')
        held = threads_of(proc.pid)
        locked = locked_kb(proc.pid)
        future = client.set_parameters(
            [Parameter('thread_priority', value=10)])
        assert spin_until(executor, future.done, START_WAIT)
        assert not future.result().results[0].successful, (
            'thread_priority must be read-only')
    finally:
        code, stderr = stop_process(proc)
    assert code == 0, stderr
    assert len(held) >= 8, held     # Fast DDS's threads are among them
    wrong = {tid: v for tid, v in held.items()
             if v != (os.SCHED_FIFO, PRIORITY, frozenset({CPU}))}
    assert not wrong, f'{len(wrong)} of {len(held)} threads: {wrong}'
    assert locked > 0
    assert 'WARN' not in stderr, stderr
    assert f'real time: SCHED_FIFO {PRIORITY} on CPUs {CPU}' in stderr


def real_time_config(tmp_path):
    """Return a copy of the shipped file with its real-time block uncommented."""
    with open(CONFIG) as f:
        text = f.read()
    block = re.search(r'^# /\*\*:\n(#  .*\n)+', text, re.M)
    assert block, 'config/orthoglide.yaml has no commented real-time block'
    lines = block.group(0).splitlines(keepends=True)
    uncommented = ''.join(line[2:] for line in lines)
    assert 'thread_priority: 50' in uncommented
    path = tmp_path / 'real_time.yaml'
    path.write_text(text.replace(block.group(0), uncommented))
    return str(path)


@needs_root
@pytest.mark.skipif(CPU != 1, reason='the shipped real-time set names CPU 1')
def test_the_shipped_real_time_set_holds_and_the_diagnostics_say_so(
        graph, tmp_path):
    probe, executor = graph
    proc = start_node_process(['--ros-args', '--params-file',
                               real_time_config(tmp_path)])
    try:
        probe.handshake(executor)
        values = wait_diagnostics(
            executor, probe.diagnostics,
            lambda v: 'scheduling policy' in v, 10.0).status[0]
        shown = {kv.key: kv.value for kv in values.values}
        held = threads_of(proc.pid)
    finally:
        code, stderr = stop_process(proc)
    assert code == 0, stderr
    assert 'real time' not in values.message
    assert shown['scheduling policy'] == 'SCHED_FIFO'
    assert shown['thread priority'] == str(PRIORITY)
    assert shown['cpu affinity'] == str(CPU)
    alike, threads = shown['threads at that policy'].split(' of ')
    assert alike == threads and int(threads) >= len(held) - 2
    assert int(shown['memory locked (kB)']) > 0


@needs_root
@pytest.mark.skipif(shutil.which('setpriv') is None,
                    reason='setpriv (util-linux) is not installed')
def test_refused_by_the_os_it_warns_once_each_and_serves(graph):
    probe, executor = graph
    proc = start_node_process(['--ros-args', *REAL_TIME],
                              command=[*DROP_CAPABILITIES,
                                       node_executable('feedforward')])
    try:
        probe.handshake(executor)
        status = wait_diagnostics(
            executor, probe.diagnostics,
            lambda v: 'scheduling policy' in v, 10.0).status[0]
        held = threads_of(proc.pid)
    finally:
        code, stderr = stop_process(proc)
    assert code == 0, stderr
    warnings = [line for line in stderr.splitlines() if '[WARN]' in line]
    assert len(warnings) == 2, stderr
    assert any('RLIMIT_RTPRIO' in w and 'rtprio 99' in w
               and '--cap-add=sys_nice' in w for w in warnings), warnings
    assert any('RLIMIT_MEMLOCK' in w and 'memlock unlimited' in w
               and '--ulimit memlock=-1' in w for w in warnings), warnings
    assert 'Traceback' not in stderr
    assert {policy for policy, _, _ in held.values()} == {os.SCHED_OTHER}
    assert status.level == b'\x01'
    assert status.message.startswith('real time not in effect: SCHED_FIFO '
                                     f'{PRIORITY} asked, SCHED_OTHER 0')


@pytest.mark.parametrize('override,words', [
    ('thread_priority:=100', 'thread_priority'),
    (f'cpu_affinity:=[{max(realtime.machine_cpus()) + 1}]',
     'not a CPU of this machine'),
])
def test_a_value_no_node_can_have_exits_2_with_one_line(override, words):
    code, stderr = run_to_exit(['--ros-args', '-p', override],
                               [node_executable('feedforward')], START_WAIT)
    assert code == 2, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and '[FATAL]' in lines[0], stderr
    assert words in lines[0]
