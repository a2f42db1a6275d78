"""
The closed loop over DDS: the feedforward does its job.

``setpoint_publisher`` -> ``feedforward`` -> ``tracking_controller`` ->
``simulator`` -> back, all processes on real Fast DDS (loopback, the session's
domain), run by ``orthoglide_testing.closed_loop`` at its default rates (loop
250 Hz, plant 500 Hz) on the paper's trajectory, eq. (6). The error is the
platform centre's, measured minus the trajectory at the measurement's stamp
(see the harness).

- Open loop (gains zero) is about the dynamics, not the timing: it is
  ``test_open_loop.py``, the same cores stepped on a simulated clock.
- PD + feedforward tracks at least 10x better (RMS) than PD alone with the
  exact plant (PD alone sags by about weight / kp = 256.5 N / 20000 N/m =
  12.8 mm), and better than PD alone with a plant whose platform is 20 %
  heavier than the model.
- A 5 kg payload picked up halfway through the pass: with the feedforward
  told at that instant (its ``robot.payload`` set at run time, as the
  simulator's is) the platform keeps to its path after it at least 5x
  better than with the feedforward not told. The measure is the distance
  from the path (eq. (6) is a straight line), not the tracking error: what
  is left of the error with the model told is timing, along the path
  (a latency, a descheduled process), and grows with the machine's load,
  while the unmodelled weight sags the platform across it too (figures:
  doc/measurements.md, "Closed loop"). It is measured from SETTLE after
  both the plant and the model acknowledged the payload: the two are set
  by two service calls, and the moments between them (25-40 ms here) are
  a model not yet told.
- A stalled process spoils a real-time pass now and then (the plant
  braked, skipped simulated time or applied one force for half the command
  timeout, or the controller held): such a pass is run again, five passes
  at most (``ClosedLoop.run_unspoiled``, the one home of that rule).
"""

import sys

import pytest

from node_checks import needs_scripts
from orthoglide_ros.model.trajectory import PAPER_TARGET

pytest.importorskip('rclpy')
harness = pytest.importorskip('orthoglide_testing.closed_loop')

# serial: a second real-time loop beside (a parallel neighbour's nodes at the
# same SCHED_FIFO priority) stalls this one; the pick-up's verdict failed on
# a fresh clone in the parallel phase (told 0.41 mm off the path where a
# pass alone measures 0.006-0.036 mm, CI 2026-12-06).
pytestmark = [pytest.mark.ros, pytest.mark.serial, needs_scripts(
    'simulator', 'feedforward', 'tracking_controller', 'setpoint_publisher')]
# s after the payload was acknowledged: the PD loop's transient, measured
# to fade within 0.1 s (0.03 mm off the path at once, 0.008 after 0.1 s).
SETTLE = 0.2


def report(run):
    """Print a run's figures (shown with -s and on failure)."""
    print(f'{run.label}: {run.samples} samples, position error RMS '
          f'{run.rms_mm:.4f} mm, max {run.max_mm:.4f} mm', file=sys.stderr)


def test_feedforward_ten_times_better_exact_plant(closed_loop):
    """PD + feedforward: at least 10x smaller RMS error than PD alone."""
    def loop_pass(feedforward):
        run = closed_loop.run_unspoiled('paper', feedforward=feedforward)
        report(run)
        return run

    def sags(run):
        """PD alone sags under the weight: weight / kp (see the docstring)."""
        return 10.0 <= run.rms_mm <= 16.0

    pd, ff = loop_pass(False), loop_pass(True)
    assert sags(pd)
    assert pd.rms_mm >= 10.0 * ff.rms_mm


def test_feedforward_better_mismatched_plant(closed_loop):
    """With a 20 % heavier platform the feedforward still helps."""
    pd = closed_loop.run_unspoiled('paper', feedforward=False,
                                   mass_factor=harness.MISMATCH)
    ff = closed_loop.run_unspoiled('paper', feedforward=True,
                                   mass_factor=harness.MISMATCH)
    report(pd)
    report(ff)
    assert ff.rms_mm < pd.rms_mm


def test_joint_trajectory_ten_times_better_like_the_stream(closed_loop):
    """
    The whole pass as one trajectory: the same 10x as the streamed mode.

    The Cartesian trajectory goes to the feedforward once; its
    JointTrajectory (effort = the model's forces) is followed by the
    tracking controller as joint_trajectory_controller would.
    """
    def loop_pass(feedforward):
        run = closed_loop.run_unspoiled('paper', feedforward=feedforward, mode='trajectory')
        report(run)
        return run

    pd, ff = loop_pass(False), loop_pass(True)
    assert pd.rms_mm >= 10.0 * ff.rms_mm


def test_a_payload_picked_up_the_feedforward_is_told_tracks_5x_better(
        closed_loop):
    at = 0.5 * harness.TRAJECTORIES['paper'].duration
    off_path, after = {}, {}
    for told in (False, True):
        run = closed_loop.run_unspoiled('paper', feedforward=True,
                                        pickup=(at, 5.0, told))
        report(run)
        off_path[told] = harness.off_path_mm(run, PAPER_TARGET,
                                             run.told_s + SETTLE)
        after[told] = harness.rms_mm(run, at)
    print(f'after the pick-up, off the path: told {off_path[True]:.4f} mm, '
          f'not told {off_path[False]:.4f} mm (tracking error {after[True]:.4f}'
          f' and {after[False]:.4f} mm)', file=sys.stderr)
    assert off_path[False] >= 5.0 * off_path[True]
