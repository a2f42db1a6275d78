"""
Restart tests of the feedforward node as a process: peers that restart.

- The node is SIGKILLed while a reliable producer streams at 500 Hz and is
  started again: every restart's first output comes within 2 s of its
  start (imports included), the outputs are right, and the producer was
  not held up while the node was dead. Every process uses
  ``config/fastdds_one_host.xml`` (see doc/deployment.md: with Fast DDS's
  defaults a restarted process takes over its killed predecessor's
  shared-memory port, and its peers reach it 1-3 s late), so the run is
  in a network namespace of its own (``netns.py``; skipped where none can
  be made).
- The producer is killed (SIGKILL) or stopped (SIGINT) mid-stream and a new
  one starts with later, then earlier stamps: the node, not restarted,
  serves it correctly without internal errors.
- SIGINT and SIGTERM while setpoints stream in: exit code 0, promptly, with
  nothing on standard error.

The runs and the bounds are in ``orthoglide_testing.reliability`` (shared with
``scripts/reliability_report.py``).
"""

import sys

import pytest

from node_checks import needs_scripts  # noqa: E402
from orthoglide_testing import live_graph  # noqa: E402
from orthoglide_testing import netns  # noqa: E402
from orthoglide_testing import reliability as harness  # noqa: E402

pytestmark = [pytest.mark.ros, needs_scripts()]
in_a_namespace = pytest.mark.skipif(bool(netns.unavailable()),
                                    reason=netns.unavailable() or 'ok')


def check(result):
    """Print the figures (shown on failure) and assert every expectation."""
    print(harness.summary_lines(result), file=sys.stderr)
    assert not harness.problems(result), harness.problems(result)


# serial: a restart's start-up (imports, at normal scheduling until the node
# takes its priority) shares the cores: 1.10, 2.16, 0.99 s beside a parallel
# neighbour and the pure set, where 2 s is the bar (a fresh clone,
# 2026-12-06); alone 1.0-1.1 s.
@pytest.mark.serial
@in_a_namespace
def test_node_killed_mid_stream_resumes():
    """SIGKILL mid-stream, restart, three times: each within 2 s, right."""
    check(live_graph.in_namespace('kill_restart', cycles=3))


@pytest.mark.soak
@in_a_namespace
def test_node_killed_mid_stream_resumes_soak():
    """Five kill/restart cycles."""
    check(live_graph.in_namespace('kill_restart', cycles=5))


def test_producer_restarts_later_and_earlier_stamps():
    """A new producer (SIGKILL, then SIGINT of the old) is served at once."""
    result = harness.producer_restart(running=0.5)
    check(result)
    assert result['outputs_per_producer'][1:] and all(
        result['outputs_per_producer']), result


@pytest.mark.soak
def test_producer_restarts_topics_input_soak():
    """The same on the pose/twist/accel input (pairing across producers)."""
    check(harness.producer_restart('topics'))


def test_sigint_sigterm_mid_stream_clean():
    """Ctrl-C or SIGTERM while streaming: exit 0 within 5 s, stderr clean."""
    result = harness.stop_mid_stream()
    check(result)
    assert result['stderr'] == [], result['stderr']
