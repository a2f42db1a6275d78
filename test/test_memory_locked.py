"""
``lock_memory`` locks a bounded memory, and the loop's pages stay locked.

The feedforward runs as a process from its console script with ``-p
lock_memory:=true``, on real DDS, and serves setpoints at 1 kHz from this
process; read from ``/proc`` while it serves (figures independent of the
machine's load): at most 250 MB under the lock (``VmLck``, every locked
mapping whole, as RLIMIT_MEMLOCK counts it: about 950 MB without the
bounds of ``cores/memory.py``), every page it holds in RAM locked (``Locked`` of
``smaps_rollup`` against its ``Pss``), and, once warm, no major page fault
and fewer minor faults than one per ten setpoints: the loop does not wait
for pages. The process is stopped (SIGINT) whatever happens.
"""

import pytest

from node_checks import needs_scripts
from orthoglide_testing.probe import paced, probed
from orthoglide_testing.processes import (memory_kb, page_faults,
                                          start_node_process, stop_process)
from orthoglide_ros.model.trajectory import paper_sample

pytestmark = [pytest.mark.ros, needs_scripts()]

LOCKED_LIMIT_KB = 250_000   # 250 MB: the feedforward's VmLck
RATE = 1000.0               # Hz: setpoints sent
WARM = 1.0                  # s of setpoints before the faults are counted
WINDOW = 3.0                # s of setpoints whose faults are counted
START_WAIT = 40.0           # s for the process to come up and answer


@pytest.fixture
def probe_graph(ros_context):
    with probed(ros_context, name='memory_probe') as graph:
        yield graph


def stream(probe, executor, seconds, first):
    """Send the paper's trajectory at RATE for ``seconds``; return the count."""
    sent = [first]

    def publish():
        sent[0] += 1
        position, velocity, acceleration = paper_sample(sent[0] / RATE)
        probe.send_trajectory((2, sent[0] * 1000), position, velocity,
                              acceleration)
    paced(executor, RATE, publish, duration=seconds)
    return sent[0]


# serial: the share of setpoints answered and the faults per setpoint sent
# depend on the rate the paced producer keeps.
@pytest.mark.serial
def test_the_feedforward_locks_at_most_250_mb_and_its_loop_takes_no_fault(
        probe_graph):
    probe, executor = probe_graph
    proc = start_node_process(['--ros-args', '-p', 'lock_memory:=true'])
    try:
        probe.handshake(executor, timeout=START_WAIT)
        warm = stream(probe, executor, WARM, 0)
        before = page_faults(proc.pid)
        sent = stream(probe, executor, WINDOW, warm) - warm
        after = page_faults(proc.pid)
        held = memory_kb(proc.pid)
        answered = len(probe.joint_states)
    finally:
        code, stderr = stop_process(proc)
    assert code == 0, stderr
    assert 'WARN' not in stderr, stderr
    assert answered > 0.5 * (sent + warm), f'{answered} of {sent + warm}'
    assert 0 < held['locked'] <= LOCKED_LIMIT_KB, held
    # Every page in RAM is locked but the kernel's own (vdso, a few kB).
    assert held['locked_resident'] >= held['proportional'] - 64, held
    minor, major = (a - b for a, b in zip(after, before))
    assert major == 0, f'{major} major faults in {sent} setpoints'
    assert minor < sent / 10, f'{minor} minor faults in {sent} setpoints'
