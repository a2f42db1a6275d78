"""
Flood tests of the feedforward node as a process: bursts it must survive.

A producer process publishes setpoints on ``setpoint/trajectory`` as fast
as it can, or at a steady 1 kHz, to the node started from its console
script; a recorder process keeps every output. With best-effort input
(overridden by ``qos_overrides``) the node must stay up and responsive,
keep its memory, and end on the newest setpoint; with reliable input and
an input history that covers the stalls of a busy machine
(``harness.LOSSLESS_DEPTH``, 1 s at 1 kHz: doc/feedforward.md's recipe for
"nothing lost") every setpoint must give exactly one output; a run in which
the producer, the run's highest priority, was itself late by more than that
history covers measured a stalled machine and is run again
(``harness.stalled_by``). The runs and
the bounds
are in ``orthoglide_testing.reliability`` (shared with
``scripts/reliability_report.py``); the soak versions last 10 s.
"""

import sys

import pytest

from node_checks import needs_scripts  # noqa: E402
from orthoglide_testing import reliability as harness  # noqa: E402

SHORT = 2.5         # s of flood / stream in the default run
FULL = 10.0         # s in the soak run (the target's)
RATE = 1000         # Hz: half of what the node sustains (bench_node.py)
# serial: a flood takes a core, and the bounds (100 ms of input history,
# diagnostics each second, answers within 2 s) failed beside a parallel
# neighbour (the ros set with -n 2, three runs, 2026-12-05); alone, none.
pytestmark = [pytest.mark.ros, pytest.mark.serial, needs_scripts()]


def check(result, **which):
    """Print the figures (shown on failure); assert the expectations."""
    print(harness.summary_lines(result), file=sys.stderr)
    found = harness.problems(result, **which)
    assert not found, found


@pytest.fixture(scope='module')
def short_flood():
    """Return one short best-effort flood's result (shared by two tests)."""
    return harness.flood(SHORT)


@pytest.fixture(scope='module')
def full_flood():
    """Return one 10 s best-effort flood's result (soak)."""
    return harness.flood(FULL)


def test_flood_best_effort(short_flood):
    """
    Flooded over best-effort input, the node survives, ends on the newest.

    Alive and exiting 0 on SIGINT, outputs in increasing stamp order with a
    bounded lag, the last output from the last setpoint sent (a few follow
    the flood at 100 Hz: best effort may drop the flood's own last one),
    every output finite and equal to mechanics.solve of its setpoint.
    """
    check(short_flood, skip=('backlog',))


def test_flood_best_effort_responsive_bounded(short_flood):
    """
    During the flood: responsive and bounded.

    /diagnostics about once a second, parameter gets answered within 2 s,
    RSS growth under 20 MB after warm-up and no steady growth.
    """
    check(short_flood, only='backlog')


@pytest.mark.soak
def test_flood_best_effort_soak(full_flood):
    """Run the best-effort flood for the target's 10 s."""
    check(full_flood, skip=('backlog',))


@pytest.mark.soak
def test_flood_best_effort_responsive_bounded_soak(full_flood):
    """Responsiveness and memory during the 10 s flood."""
    check(full_flood, only='backlog')


def test_reliable_every_setpoint_one_output():
    """At 1 kHz over reliable input: one output per setpoint, by stamp."""
    result = harness.reliable_stream(RATE, SHORT)
    check(result)
    assert result['sent'] >= RATE * SHORT * 0.9


@pytest.mark.soak
def test_reliable_every_setpoint_one_output_soak():
    """Run the reliable stream for the target's 10 s."""
    result = harness.reliable_stream(RATE, FULL)
    check(result)
    assert result['sent'] >= RATE * FULL * 0.9
