"""
Absurd finite numbers given to ``identify`` and ``validate``: refused first.

``identify --payload 1e308`` and ``2e6`` (a payload the log cannot hold,
not a friction to blame), ``validate`` with a bad log (the log named, not
``None``), and a log whose forces are 1e300 (no RMS error of ``inf``):
each is exit 2 with one line naming the option, or the log's row and
column, and no warning reaches the user; every numeric option of both
commands, given a non-finite or an extreme value, either runs or is
refused in one line, without a traceback or a warning. The ranges are
those doc/identification.md states: an option that sets a robot
parameter takes that parameter's own limits (``robot.ROW``), a log's
values the LIMITS of :mod:`formats.logs`, its motion MOTION_LIMITS.
"""

import math
import subprocess
import sys
import warnings

from cli_runs import assert_bad_input, run
import numpy as np
from orthoglide_ros.cores.feedforward import PARAMETERS
from orthoglide_ros.formats import logs
from orthoglide_ros.model.robot import LENGTH_LIMITS, ROW
from orthoglide_ros.tools.identification import motion
import pytest
from synthetic_logs import synthetic_log, TRUE, write_csv

EXTREMES = ('nan', 'inf', '-inf', '1e308', '-1e308', '5e-324', '-5e-324')


@pytest.fixture(scope='module')
def log_file(tmp_path_factory):
    """Write a 12 s log of a robot unlike the paper's, without payload."""
    log = synthetic_log(TRUE, 0, 6.0, 1, duration=12.0)
    path = tmp_path_factory.mktemp('absurd') / 'log.csv'
    return write_csv(path, log), log


def tool(*argv):
    """Run ``orthoglide`` as a user does: (exit code, stdout, stderr)."""
    done = subprocess.run(
        [sys.executable, '-m', 'orthoglide_ros.tools.cli', *map(str, argv)],
        capture_output=True, text=True, timeout=300)
    return done.returncode, done.stdout, done.stderr


def assert_one_line_no_warning(code, out, err, *words):
    """Exit 2, one line naming ``words``; no warning, no traceback, no None."""
    assert 'Warning' not in err and 'Traceback' not in err, err
    assert 'None:' not in err, err
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    # argparse's refusals print the usage first, then one error line.
    assert lines[-1].startswith(('orthoglide: error: ',
                                 'orthoglide identify: error: ',
                                 'orthoglide validate: error: ')), err
    assert all(line.startswith(('usage:', ' ')) for line in lines[:-1]), err
    for word in words:
        assert word in lines[-1], err


@pytest.mark.parametrize('payload', ['1e308', '2e6', '-1'])
def test_identify_refuses_a_payload_beyond_the_robots_limits(log_file,
                                                             tmp_path,
                                                             payload):
    """As a user runs it: one line naming --payload and its limits."""
    path, _ = log_file
    out_file = tmp_path / 'out.yaml'
    code, out, err = tool('identify', '--input', path, '--output', out_file,
                          '--payload', payload)
    low, high = ROW['payload'].limits
    assert_one_line_no_warning(code, out, err, '--payload',
                               f'[{low:g}, {high:g}] kg')
    assert not out_file.exists()


def test_identify_refuses_a_payload_the_log_does_not_carry(capsys, log_file,
                                                           tmp_path):
    """
    Within the limits, but heavier than what the log was recorded with.

    The log carried nothing: 100 kg taken off its forces leaves a platform
    of about 19.35 - 100 kg (TRUE's own), which no robot has.
    """
    path, _ = log_file
    code, out, err = run(capsys, 'identify', '--input', path, '--output',
                         tmp_path / 'out.yaml', '--payload', 100)
    assert_bad_input(code, out, err, 'payload of 100 kg', 'm5 + 3 m4',
                     'do not carry')
    platform = float(err.split('comes out at ')[1].split(' kg')[0])
    assert platform == pytest.approx(TRUE.m5 + 3 * TRUE.m4 - 100.0, abs=0.5)
    assert not (tmp_path / 'out.yaml').exists()


def test_identify_takes_the_payload_the_log_was_recorded_with(capsys,
                                                              tmp_path):
    """The check above refuses nothing true: a log carrying 5 kg, told so."""
    log = synthetic_log(TRUE.replace(payload=5.0), 0, 6.0, 1, duration=12.0)
    path = write_csv(tmp_path / 'carried.csv', log)
    code, _, err = run(capsys, 'identify', '--input', path, '--output',
                       tmp_path / 'out.yaml', '--payload', 5)
    assert code == 0, err


def test_validate_names_the_option_not_none(log_file, tmp_path):
    path, _ = log_file
    code, out, err = tool('validate', '--input', path, '--payload', '2e6')
    assert_one_line_no_warning(code, out, err, '--payload')
    bad = tmp_path / 'bad.yaml'
    bad.write_text('feedforward:\n  ros__parameters:\n    robot:\n'
                   '      m1: -1.0\n')
    code, out, err = tool('validate', '--input', path, '--params', bad)
    assert_one_line_no_warning(code, out, err, f'{bad}: robot.m1')


@pytest.mark.parametrize('value, row', [(1e300, 500), (-1e300, 0),
                                        (1.5e9, 7)])
def test_a_log_with_absurd_forces_is_refused_naming_row_and_column(
        tmp_path, log_file, value, row):
    """Refused before any RMS error or share is computed from them."""
    _, log = log_file
    forces = log.forces.copy()
    forces[row, 1] = value
    path = write_csv(tmp_path / 'absurd.csv', log._replace(forces=forces))
    limit, unit = logs.LIMITS['force']
    for command in (['validate'], ['identify', '--output',
                                   tmp_path / 'out.yaml']):
        code, out, err = tool(*command, '--input', path)
        assert_one_line_no_warning(
            code, out, err, f'data row {row + 1} ', 'force_b',
            f'[{-limit:g}, {limit:g}] {unit}')


def test_every_force_at_1e300_is_refused_too(tmp_path, log_file):
    _, log = log_file
    path = write_csv(tmp_path / 'scaled.csv',
                     log._replace(forces=log.forces * 1e300 / 500.0))
    code, out, err = tool('validate', '--input', path)
    assert_one_line_no_warning(code, out, err, 'data row 1 ', 'force_')


def test_stamps_not_in_seconds_are_refused_naming_the_speed(tmp_path,
                                                            log_file):
    """Microseconds read as seconds: a platform faster than any robot's."""
    _, log = log_file
    path = write_csv(tmp_path / 'ns.csv', log._replace(times=log.times * 1e-6))
    name, limit, unit = motion.MOTION_LIMITS[0]
    code, out, err = tool('validate', '--input', path, '--cutoff', '1e8')
    assert_one_line_no_warning(code, out, err, f'{name} along',
                               f'{limit:g} {unit}', 'seconds')


def test_the_limits_are_those_the_package_states():
    """The log's force and speed bounds are the feedforward's largest."""
    spec = {s.name: s for s in PARAMETERS.specs}
    assert logs.LIMITS['force'][0] == \
        spec['joint_limits.slider_a.max_effort'].range[1]
    assert logs.LIMITS['lambdadot'][0] == spec['max_speed'].range[1]
    assert dict((n, v) for n, v, _ in motion.MOTION_LIMITS) == {
        'speed': spec['max_speed'].range[1],
        'acceleration': spec['max_acceleration'].range[1]}
    assert logs.LIMITS['lambda'][0] == 10 * LENGTH_LIMITS[1]


OPTIONS = {
    'identify': ('--start', '--end', '--cutoff', '--payload', '--force-lag',
                 '--stribeck-velocity', '--max-relative-std'),
    'validate': ('--start', '--end', '--cutoff', '--payload', '--force-lag'),
}


@pytest.mark.parametrize('command, option', [
    (c, o) for c, options in OPTIONS.items() for o in options])
def test_every_numeric_option_runs_or_refuses_in_one_line(
        capsys, tmp_path, log_file, command, option):
    """
    Each extreme value: exit 0, or exit 2 with one line; never a warning.

    In the test's process with every warning recorded, the tool's own
    handling of them included.
    """
    path, _ = log_file
    extra = ['--output', tmp_path / 'out.yaml'] if command == 'identify' \
        else []
    if option == '--stribeck-velocity':
        extra += ['--friction', 'coulomb+stribeck']
    for value in EXTREMES:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter('always')
            code, out, err = run(capsys, command, '--input', path, *extra,
                                 option, value)
        assert not caught, (option, value, [str(w.message) for w in caught])
        assert code in (0, 2), (option, value, err)
        if code == 2:
            lines = err.strip().splitlines()
            assert 'error: ' in lines[-1] and 'None:' not in err, err
            if not math.isfinite(float(value)):
                assert option in lines[-1], err
        else:
            assert 'nan' not in out.lower().replace('nan %', ''), out


def test_a_non_finite_validation_is_refused_not_printed(monkeypatch,
                                                        log_file):
    """
    The last guard: an error that is not finite is named, not printed.

    Unreachable from the command line (the ranges above keep every
    number finite), so forced here: the robot's forces made infinite on
    actuator B.
    """
    from orthoglide_ros.tools import identification
    _, log = log_file
    real = motion.Motion.model_forces

    def infinite(self, robot):
        forces = real(self, robot)
        forces[3, 1] = np.inf
        return forces
    monkeypatch.setattr(motion.Motion, 'model_forces', infinite)
    with pytest.raises(identification.LogError, match='actuator B'):
        identification.validate(TRUE, log, force_lag=0.0)
