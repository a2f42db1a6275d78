"""
Identification over DDS: a better feedforward for an unknown plant.

The loop of ``orthoglide_testing.closed_loop`` with a plant the feedforward
does not know (``UNKNOWN_PLANT``: a 25 % heavier platform, heavier bars,
friction on every slider): three periods of the excitation through PD + the
nominal feedforward, then ``identification.identify`` on the plant's measured
joint states (the harness's recorder; a segment per stretch the plant stepped
without skipping time, ``log_of``), the effort taken as applied half a plant
step before its state (``force_lag``), the plant's friction law (viscous +
Coulomb: the law's choice is tested on synthetic logs). Checked:

- the identified base parameters lie within the tolerances of the
  plant's (3 %, the lightest group 10 %, friction 25 %; measured within
  1 %). Not within a number of their standard deviations: those assume
  white residuals, and a loop over DDS leaves correlated ones (measured:
  errors of 0.07-0.16 % at 4.3-4.5 of the computed deviations);
- on the paper's trajectory, PD + the identified feedforward tracks
  better (RMS) than PD + the nominal one, in medians of interleaved
  passes (``orthoglide_testing.closed_loop.median_runs``; a pass a stall
  spoiled is run again once). The criterion, within 1.5 times the error of
  PD + the exact feedforward, is checked where a pass is deterministic
  (``test_identification.py``) and printed here: over DDS a pass's error
  is set by the timing as much as by the model (0.08-0.20 mm with either
  model on an idle machine, 0.13-1.1 mm beside another test run), so the
  ratio to the exact model measured the load (it failed under load with
  0.185 against 0.083 mm), while the nominal model's error stays 4-15
  times larger on either machine;
- the identified robot written as a parameters file starts the
  ``feedforward`` node (``--params-file``) with its values.

The full demo (a longer excitation recorded by ``orthoglide record``, the
CLI's ``identify``, two validation motions, four cases) is
``scripts/identification_demo.sh``.
"""

import sys
import time

import pytest

from identification_checks import assert_within_tolerances
from node_checks import needs_scripts
from orthoglide_testing.processes import start_node_process, stop_process

from orthoglide_ros.formats import params_file
from orthoglide_ros.tools import identification
from orthoglide_ros.model.robot import Robot

rclpy = pytest.importorskip('rclpy')
harness = pytest.importorskip('orthoglide_testing.closed_loop')
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.parameter_client import AsyncParameterClient  # noqa: E402
from rcl_interfaces.msg import ParameterType  # noqa: E402

# serial: a real-time closed loop for minutes, judged by its passes' timing
# (the rule of test_closed_loop), and the largest load on a neighbour.
pytestmark = [pytest.mark.ros, pytest.mark.serial, needs_scripts(
    'simulator', 'feedforward', 'tracking_controller', 'setpoint_publisher')]

SEED, PERIOD, PASSES = 0, 6.0, 3
CRITERION = 1.5     # the target, against the exact feedforward (printed)
REPEATS = 3         # passes of each compared case; the median counts
EXCITATIONS = 3     # excitation runs recorded at most (see identified())


@pytest.fixture(scope='module')
def identified(closed_loop):
    """
    Excite the unknown plant, identify it: (Identification, last run).

    As a user would: when a log does not excite every base parameter
    enough (a loaded machine drops or delays states, and gaps split the
    log), another excitation is recorded and both are identified together,
    EXCITATIONS at most.
    """
    logs = []
    for attempt in range(1, EXCITATIONS + 1):
        run = closed_loop.run_unspoiled(
            harness.excitation_motion(SEED, PERIOD), feedforward=True,
            plant=harness.UNKNOWN_PLANT, model=Robot(), passes=PASSES)
        logs.append(identification.crop(harness.log_of(run),
                                        harness.SETTLE))
        try:
            result = identification.identify(
                Robot(), harness.joined(logs), force_lag=harness.force_lag(),
                friction=identification.PLAIN)
            break
        except identification.IdentificationError as error:
            print(f'excitation {attempt}: {error}', file=sys.stderr)
            if attempt == EXCITATIONS:
                raise
    print(f'excitation: {len(logs)} log(s), {run.samples} states in the '
          f'last, {len(result.samples.times)} used', file=sys.stderr)
    return result, run


def test_identified_base_parameters_are_the_plants(identified):
    result, _ = identified
    truth = result.base.matrix @ identification.standard_parameters(
        harness.UNKNOWN_PLANT)
    for name, value, true, std in zip(result.base.names, result.values,
                                      truth, result.std):
        print(f'{name}: {value:.4f} (plant {true:.4f}, std {std:.3g})',
              file=sys.stderr)
    assert_within_tolerances(result.base, result.values, truth,
                             result.robot, harness.UNKNOWN_PLANT)


def test_identified_feedforward_tracks_like_the_exact_one(closed_loop,
                                                          identified):
    result, _ = identified

    def report(text):
        print(text, file=sys.stderr)
    compared = {'identified': (True, result.robot),
                'exact': (True, harness.UNKNOWN_PLANT),
                'nominal': (True, Robot())}
    runs, _ = harness.median_runs(
        closed_loop, 'paper', compared, harness.UNKNOWN_PLANT, REPEATS,
        report)
    ratio = runs['identified'].rms_mm / runs['exact'].rms_mm
    report(f'identified / exact: {ratio:.2f} (target: {CRITERION:g}, '
           'checked without DDS)')
    assert runs['identified'].rms_mm < runs['nominal'].rms_mm


def test_identified_parameters_file_starts_the_feedforward(closed_loop,
                                                           identified,
                                                           tmp_path):
    result, _ = identified
    path = tmp_path / 'identified.yaml'
    # Its own namespace, beside the loop's feedforward: the section's key
    # is the node's full name (the tools write '/**', every node's).
    path.write_text(params_file.robot_file_text(
        result.robot, node='/identified/feedforward'))
    proc = start_node_process(['--ros-args', '--params-file', str(path),
                               '-r', '__ns:=/identified'])
    context = closed_loop.context
    node = rclpy.create_node('identified_check', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        client = AsyncParameterClient(node, '/identified/feedforward')
        deadline = time.monotonic() + 20.0
        while not client.services_are_ready():
            assert proc.poll() is None, stop_process(proc)
            assert time.monotonic() < deadline
            executor.spin_once(timeout_sec=0.05)
        names = [f'robot.{n}' for n in Robot.parameter_names()]
        future = client.get_parameters(names)
        while not future.done():
            assert time.monotonic() < deadline
            executor.spin_once(timeout_sec=0.05)
        values = {n: v for n, v in zip(
            Robot.parameter_names(), future.result().values)}
        robot = Robot(**{
            n: (list(v.double_array_value)
                if v.type == ParameterType.PARAMETER_DOUBLE_ARRAY
                else v.double_value) for n, v in values.items()})
        assert robot == result.robot
    finally:
        executor.shutdown()
        node.destroy_node()
        code, err = stop_process(proc)
    assert code == 0, err
