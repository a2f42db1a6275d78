"""
Real-time scheduling: the parameters' rules, and what the OS then holds.

The rules (no DDS): every loop node's table has ``thread_priority``,
``cpu_affinity`` and ``lock_memory``, read-only, off by default; a
priority outside [0, 99] or a CPU the machine lacks is refused naming
it. What holds is read here by the standard library
(``os.sched_getscheduler``, ``os.sched_getaffinity`` and ``VmLck``, per
thread), not by the package's own reader, in a child process that
applies the settings (this test process is never made real-time): every
thread, one started before and one after, at the policy; the refusal of
an OS without CAP_SYS_NICE and CAP_IPC_LOCK made real with ``setpriv``:
one warning per setting naming the limit and the fix, nothing changed.
"""

import importlib
import json
import os
import shutil
import subprocess
import sys

import pytest

from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.parameters import ParameterError

LOOP_NODES = ('feedforward', 'tracking_controller', 'simulator',
              'setpoint_publisher', 'mechanism_state_publisher')
CPUS = realtime.machine_cpus()
# A child that starts a thread, applies the settings of argv[1] (JSON),
# starts another, prints its warnings and the package's reading, then
# waits for stdin to close so that the test can read its threads.
CHILD = r'''
import json, sys, threading
from orthoglide_ros.cores import realtime
hold = threading.Event()
before = threading.Thread(target=hold.wait, daemon=True)
before.start()
warnings = realtime.apply(*json.loads(sys.argv[1]))
after = threading.Thread(target=hold.wait, daemon=True)
after.start()
print(json.dumps({'warnings': warnings,
                  'effect': realtime.in_effect()._asdict()}), flush=True)
sys.stdin.read()
'''
root = os.geteuid() == 0
needs_root = pytest.mark.skipif(not root, reason='SCHED_FIFO and mlockall '
                                'need root (or the limits) here')


def table(node):
    return importlib.import_module(f'orthoglide_ros.cores.{node}').PARAMETERS


@pytest.mark.parametrize('node', LOOP_NODES)
def test_every_loop_node_declares_the_three_read_only_and_off(node):
    specs = {s.name: s for s in table(node).specs}
    for name, default in (('thread_priority', 0), ('cpu_affinity', []),
                          ('lock_memory', False)):
        assert specs[name].default == default
        assert specs[name].read_only, f'{node}: {name} must be read-only'
    settings = table(node).parse({})
    assert (settings.thread_priority, settings.cpu_affinity,
            settings.lock_memory) == (0, (), False)


@pytest.mark.parametrize('values,name,words', [
    ({'thread_priority': 100}, 'thread_priority', '[0, 99]'),
    ({'thread_priority': -1}, 'thread_priority', '[0, 99]'),
    ({'thread_priority': 50.0}, 'thread_priority', 'integer'),
    ({'cpu_affinity': [max(CPUS) + 1]}, 'cpu_affinity', 'not a CPU'),
    ({'cpu_affinity': [-1]}, 'cpu_affinity', 'not a CPU'),
    ({'cpu_affinity': [1.0]}, 'cpu_affinity', 'integers'),
    ({'lock_memory': 1}, 'lock_memory', 'bool'),
])
def test_a_value_no_node_can_have_is_refused_naming_it(values, name, words):
    with pytest.raises(ParameterError) as refused:
        table('feedforward').parse(values)
    assert refused.value.name == name
    assert words in str(refused.value)


def test_the_cpus_are_kept_sorted_once_each():
    settings = table('simulator').parse(
        {'cpu_affinity': [CPUS[-1], CPUS[0], CPUS[-1]]})
    assert settings.cpu_affinity == tuple(sorted({CPUS[0], CPUS[-1]}))


@pytest.mark.parametrize('text,cpus,written', [
    ('0', (0,), '0'), ('0-3\n', (0, 1, 2, 3), '0-3'),
    ('0-1,4,6-7', (0, 1, 4, 6, 7), '0-1,4,6-7')])
def test_a_kernel_cpu_list_reads_and_writes_back(text, cpus, written):
    assert realtime._cpu_list(text) == cpus
    assert realtime.format_cpus(cpus) == written


def effect(**changes):
    values = dict(policy='SCHED_FIFO', priority=50, cpus=(1,), threads=12,
                  alike=12, locked_kb=200000, resident_kb=80000)
    values.update(changes)
    return realtime.Effect(**values)


@pytest.mark.parametrize('asked,held,words', [
    ((50, (1,), True), effect(), None),
    ((0, (), False), effect(policy='SCHED_OTHER', priority=0, cpus=(0, 1),
                            locked_kb=0), None),
    ((50, (), False), effect(policy='SCHED_OTHER', priority=0),
     'SCHED_FIFO 50 asked, SCHED_OTHER 0 in effect'),
    ((50, (), False), effect(alike=11), '1 of 12 threads not at that'),
    ((0, (1,), False), effect(cpus=(0, 1)), 'CPUs 1 asked, 0-1 in effect'),
    ((0, (), True), effect(locked_kb=0), 'no memory locked'),
])
def test_what_was_asked_and_does_not_hold_is_named(asked, held, words):
    missing = realtime.shortfall(*asked, held)
    if words is None:
        assert missing is None
    else:
        assert missing.startswith('real time not in effect: ')
        assert words in missing


def run_child(settings, wrap=()):
    """Run CHILD with ``settings``; return (its report, its threads)."""
    proc = subprocess.Popen(
        [*wrap, sys.executable, '-c', CHILD, json.dumps(settings)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        report = json.loads(proc.stdout.readline())
        threads = {}
        for name in os.listdir(f'/proc/{proc.pid}/task'):
            tid = int(name)
            threads[tid] = (os.sched_getscheduler(tid),
                            os.sched_getparam(tid).sched_priority,
                            frozenset(os.sched_getaffinity(tid)))
        with open(f'/proc/{proc.pid}/status') as f:
            locked = next(int(line.split()[1]) for line in f
                          if line.startswith('VmLck:'))
    finally:
        proc.stdin.close()
        proc.wait(10)
    return report, threads, locked


@needs_root
def test_every_thread_made_before_and_after_runs_at_the_policy():
    cpu = CPUS[-1]
    report, threads, locked = run_child([50, [cpu], True])
    assert report['warnings'] == []
    assert len(threads) >= 3     # main, before, after
    assert set(threads.values()) == {(os.SCHED_FIFO, 50, frozenset({cpu}))}, threads
    assert locked > 0
    held = report['effect']
    assert (held['policy'], held['priority'], held['cpus'],
            held['alike']) == ('SCHED_FIFO', 50, [cpu], held['threads'])
    assert held['threads'] == len(threads)
    assert held['locked_kb'] > 0


def test_off_changes_nothing():
    report, threads, locked = run_child([0, [], False])
    assert report['warnings'] == []
    assert {policy for policy, _, _ in threads.values()} == {
        os.sched_getscheduler(0)}
    assert {cpus for _, _, cpus in threads.values()} == {
        frozenset(os.sched_getaffinity(0))}
    assert locked == 0


@needs_root
@pytest.mark.skipif(shutil.which('setpriv') is None,
                    reason='setpriv (util-linux) is not installed')
def test_an_os_that_refuses_gets_one_warning_each_and_no_change():
    # As a user without CAP_SYS_NICE and CAP_IPC_LOCK: root's limits here
    # are rtprio 0 and memlock 8 MiB.
    report, threads, locked = run_child(
        [50, [], True], wrap=('setpriv', '--bounding-set=-sys_nice,-ipc_lock'))
    warnings = report['warnings']
    assert len(warnings) == 2, warnings
    memory, priority = warnings
    for line, words in (
            (memory, ('lock_memory refused', 'RLIMIT_MEMLOCK',
                      'memlock unlimited', 'limits.conf',
                      '--ulimit memlock=-1', 'LimitMEMLOCK')),
            (priority, ('thread_priority 50 refused', 'RLIMIT_RTPRIO',
                        'CAP_SYS_NICE', 'rtprio 99', 'limits.conf',
                        '--cap-add=sys_nice --ulimit rtprio=99',
                        'LimitRTPRIO', 'running at normal scheduling'))):
        assert '\n' not in line
        for word in words:
            assert word in line, f'{word!r} not in {line!r}'
    assert {policy for policy, _, _ in threads.values()} == {os.SCHED_OTHER}
    assert locked == 0
    assert report['effect']['policy'] == 'SCHED_OTHER'


def test_unset_values_read_as_the_defaults():
    # rclpy declares the empty cpu_affinity by its type alone: unset, None.
    assert realtime.settings_of({'thread_priority': 0, 'cpu_affinity': None,
                                 'lock_memory': None}) == (0, (), False)
    assert realtime.settings_of({}) == (0, (), False)
