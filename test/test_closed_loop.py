"""
The closed loop over DDS (issue 5): the feedforward does its job.

``setpoint_publisher`` -> ``feedforward`` -> ``tracking_controller`` ->
``simulator`` -> back, all processes on real Fast DDS (loopback, the
session's domain), run by ``closed_loop_harness`` at its default rates
(loop 250 Hz, plant 500 Hz) on the paper's trajectory, eq. (6). The error is
the platform centre's, measured minus the trajectory at the measurement's
stamp (see the harness).

- Open loop (gains zero, exact plant, the same initial state: home, at
  rest): the platform follows the trajectory on the feedforward alone. The
  plant is open-loop unstable (holding the weight on the vertical leg acts
  as a negative stiffness of ~300 N/m in x and y), so every error grows
  about 5x per 0.5 s: the commands are held for a loop period (4 ms), reach
  the plant ~1-2 ms late, and the plant's steps are late when the two cores
  are busy. Measured (exact plant, error norm at 0.5 / 1.0 / 1.5 / 2.0 s):
  0.1-0.6 / 0.5-1.5 / 2.7-8 / 10-46 mm on most passes; a pass in which a
  process was descheduled early reached 223 mm at 2 s (amplified ~e^5).
  The bound is therefore set on the first second, where the timing has
  been amplified least: ``OPEN_LOOP_BOUND``, 25 mm, above the first second
  of the passes measured with both cores saturated by two busy loops
  (4.6-15.6 mm) and below that of a plant whose platform is only 2 %
  heavier than the model (48-57 mm, idle or loaded): the open-loop test
  sees a 2 % model error
  (``test_open_loop_sees_a_two_percent_heavier_platform``). Without DDS,
  forces sampled at the midpoint of each 1 ms step follow to 1.4 um over
  the whole pass (test_simulation_energy).
- PD + feedforward tracks at least 10x better (RMS) than PD alone with the
  exact plant (PD alone sags by about weight / kp = 256.5 N / 20000 N/m =
  12.8 mm), and better than PD alone with a plant whose platform is 20 %
  heavier than the model.
- A descheduled process spoils a real-time pass now and then; the open-loop
  and 10x tests run a second pass when the first misses
  (:func:`second_pass_on_a_miss`).
"""

import sys

import numpy as np
import pytest

from node_harness import needs_scripts  # noqa: E402

from orthoglide_ros.model import trajectory  # noqa: E402

pytest.importorskip('rclpy')
harness = pytest.importorskip('closed_loop_harness')
from orthoglide_ros.cores.simulator import MAX_CATCH_UP  # noqa: E402

# Measured: see the module docstring and doc/measurements.md (closed loop).
OPEN_LOOP_BOUND = 0.025    # m, largest position error in the first second
OPEN_LOOP_SPAN = 1.0       # s: the first second of the pass
# Fewest measurements per second of a pass: the simulator publishes once a
# tick, after at most MAX_CATCH_UP steps when its ticks are late.
MIN_SAMPLE_RATE = harness.PLANT_RATE / MAX_CATCH_UP

pytestmark = [pytest.mark.ros, needs_scripts(
    'simulator', 'feedforward', 'tracking_controller', 'setpoint_publisher')]


def report(run):
    """Print a run's figures (shown with -s and on failure)."""
    print(f'{run.label}: {run.samples} samples, position error RMS '
          f'{run.rms_mm:.4f} mm, max {run.max_mm:.4f} mm', file=sys.stderr)


def second_pass_on_a_miss(run_pass, ok):
    """
    Return ``run_pass()``, or a second pass's result if the first is not ok.

    A process descheduled at the wrong moment spoils a real-time pass now
    and then (see the module docstring); a model error cannot be spoiled
    away by a second pass, so the test keeps its meaning.
    """
    result = run_pass()
    return result if ok(result) else run_pass()


def open_loop(closed_loop, mass_factor):
    """Run the paper's pass with gains zero; its largest error (m) early."""
    run = closed_loop.run('paper', feedforward=True, kp=(0.0,) * 3,
                          kd=(0.0,) * 3, mass_factor=mass_factor)
    report(run)
    early = run.times <= OPEN_LOOP_SPAN
    assert early.sum() >= OPEN_LOOP_SPAN * MIN_SAMPLE_RATE
    worst = float(np.linalg.norm(run.position_error[early], axis=1).max())
    print(f'  largest error in the first {OPEN_LOOP_SPAN:g} s: '
          f'{worst * 1e3:.3f} mm', file=sys.stderr)
    return run, worst


def test_open_loop_follows_the_trajectory(closed_loop):
    """Gains zero, exact plant: the feedforward alone moves the platform."""
    run, worst = second_pass_on_a_miss(
        lambda: open_loop(closed_loop, 1.0), lambda r: r[1] <= OPEN_LOOP_BOUND)
    assert run.samples >= trajectory.PAPER_DURATION * MIN_SAMPLE_RATE
    assert worst <= OPEN_LOOP_BOUND


def test_open_loop_sees_a_two_percent_heavier_platform(closed_loop):
    """
    The bound is tight: a plant 2 % off the model breaks it.

    (Such a plant falls away from the trajectory and may reach the
    simulator's workspace limit, which stops it, before the pass ends.)
    """
    _, worst = open_loop(closed_loop, 1.02)
    assert worst > OPEN_LOOP_BOUND


def test_feedforward_ten_times_better_exact_plant(closed_loop):
    """PD + feedforward: at least 10x smaller RMS error than PD alone."""
    def loop_pass(feedforward):
        run = closed_loop.run_unspoiled('paper', feedforward=feedforward)
        report(run)
        return run

    def sags(run):
        """PD alone sags under the weight: weight / kp (see the docstring)."""
        return 10.0 <= run.rms_mm <= 16.0

    pd = second_pass_on_a_miss(lambda: loop_pass(False), sags)
    assert sags(pd)
    ff = second_pass_on_a_miss(lambda: loop_pass(True),
                               lambda r: pd.rms_mm >= 10.0 * r.rms_mm)
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

    pd = second_pass_on_a_miss(lambda: loop_pass(False),
                               lambda r: r.rms_mm >= 10.0)
    ff = second_pass_on_a_miss(lambda: loop_pass(True),
                               lambda r: pd.rms_mm >= 10.0 * r.rms_mm)
    assert pd.rms_mm >= 10.0 * ff.rms_mm
