"""
Tests of the ``orthoglide`` tool: calibration-poses, calibrate.

From the designed positions to a calibrated parameters file that the
tools read back; every refusal of bad input: exit code 2, one line naming
the file's line and column, nothing written.
"""

import csv
import os
import subprocess
import sys

import numpy as np
import pytest
import yaml

from cli_runs import assert_bad_input, PNG_MAGIC, run
from orthoglide_testing.robots_as_built import BUILT
from orthoglide_ros.formats import csvfile, params_file
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools import calibration

HEADER = 'lambda_a,lambda_b,lambda_c,x,y,z'
NOISE = 10e-6
MACHINE = Robot(**BUILT)


def read_poses(path):
    with open(path, newline='') as stream:
        return list(csv.DictReader(stream))


def write_measurements(path, lam, readings, header=HEADER):
    """Write rows (a NaN reading: an empty cell), columns of ``header``."""
    order = header.split(',')
    with open(path, 'w') as stream:
        stream.write(header + '\n')
        for row in np.column_stack((lam, readings)).tolist():
            cells = dict(zip(calibration.COLUMNS, row))
            stream.write(','.join('' if cells[c] != cells[c] else repr(
                cells[c]) for c in order) + '\n')
    return path


def measured(lam, seed=0, robot=MACHINE):
    readings = mechanics.forward_kinematics(robot, lam)
    return readings + np.random.default_rng(seed).normal(0.0, NOISE,
                                                         readings.shape)


@pytest.fixture(scope='module')
def twenty(tmp_path_factory):
    """Measurements of the built machine at 20 positions: (path, lam)."""
    rng = np.random.default_rng(5)
    positions = rng.uniform(-0.25, 0.25, (20, 3))
    lam = mechanics.solve_batch(Robot(), positions).lambda_
    path = tmp_path_factory.mktemp('calibration') / 'measurements.csv'
    return write_measurements(path, lam, measured(lam)), lam


@pytest.mark.slow     # 2.5-4 s: the design, the report's matplotlib, 2026-12-06
def test_the_poses_measured_calibrate_the_machine(capsys, tmp_path):
    poses_file = tmp_path / 'poses.csv'
    code, out, err = run(capsys, 'calibration-poses', '--count', 12,
                         '--output', poses_file)
    assert (code, err) == (0, '')
    assert 'condition number of the calibration\'s Jacobian (the 18 ' \
        'separable values, unit-norm columns):' in out
    rows = read_poses(poses_file)
    assert list(rows[0]) == HEADER.split(',') and len(rows) == 12
    lam = np.array([[float(r[f'lambda_{leg}']) for leg in 'abc']
                    for r in rows])
    nominal = np.array([[float(r[c]) for c in 'xyz'] for r in rows])
    assert np.allclose(mechanics.forward_kinematics(Robot(), lam), nominal,
                       atol=1e-12)
    # Measured: the columns in another order, as an instrument writes them.
    data = write_measurements(tmp_path / 'm.csv', lam, measured(lam),
                              'x,y,z,lambda_a,lambda_b,lambda_c')
    output, report = tmp_path / 'robot.yaml', tmp_path / 'report.png'
    code, out, err = run(capsys, 'calibrate', '--input', data, '--output',
                         output, '--report', report)
    assert (code, err) == (0, '')
    lines = out.splitlines()
    assert lines[0].startswith(f'Calibration from {data}: 12 measurements, '
                               '36 readings (x 12, y 12, z 12)')
    assert 'these readings separate 18 of the 30 values' in out
    assert '  attachment_a[x]       -joint_offset[a]' in lines
    assert any(line.startswith('axis_direction_b[z]') and line.endswith(
        'mrad') for line in lines)
    assert 'the noise it implies, sqrt(RSS / (n - k))' in out
    assert report.read_bytes().startswith(PNG_MAGIC)
    robot = params_file.load_robot(output)
    text = output.read_text()
    assert text.startswith(f'# Calibrated by `orthoglide calibrate` from '
                           f'{data} (nominal robot: the drawing\'s)\n')
    assert '#   axis_point_a[x]       joint_offset[a]' in text
    # What the file holds is what the machine does: a target commanded
    # through it is reached within the noise's reach.
    targets = np.random.default_rng(9).uniform(-0.25, 0.25, (200, 3))
    reached = mechanics.forward_kinematics(MACHINE, mechanics.solve_batch(
        robot, targets).lambda_)
    assert np.abs(reached - targets).max() < 60e-6
    # And every command reads it: batch solves with it.
    assert run(capsys, 'solve', '--params', output, '--position', 0.1,
               0.0, -0.1)[0] == 0


def test_the_nominal_files_masses_and_friction_are_kept(capsys, tmp_path,
                                                        twenty):
    nominal = tmp_path / 'nominal.yaml'
    nominal.write_text(params_file.robot_file_text(Robot(
        m5=18.0, friction_coulomb=(5.0, 3.0, 4.0), armature=(1.0, 0.5,
                                                             0.2))))
    output = tmp_path / 'robot.yaml'
    code, out, _ = run(capsys, 'calibrate', '--input', twenty[0],
                       '--params', nominal, '--output', output)
    assert code == 0
    robot = params_file.load_robot(output)
    assert (robot.m5, robot.friction_coulomb, robot.armature) == (
        18.0, (5.0, 3.0, 4.0), (1.0, 0.5, 0.2))
    assert f'(nominal robot: {nominal})' in output.read_text()


def test_a_blunder_is_named_by_its_line(capsys, tmp_path, twenty):
    _, lam = twenty
    readings = measured(lam, 1)
    readings[6, 2] += 5e-3
    path = write_measurements(tmp_path / 'm.csv', lam, readings)
    code, out, _ = run(capsys, 'calibrate', '--input', path, '--output',
                       tmp_path / 'robot.yaml')
    assert code == 0
    assert 'left out: line 8 (a blunder: its z reading +5' in out
    assert '# left out: line 8' in (tmp_path / 'robot.yaml').read_text()


def test_a_gauge_design_leaves_the_readings_to_fill_in(capsys, tmp_path):
    poses_file = tmp_path / 'poses.csv'
    code, out, _ = run(capsys, 'calibration-poses', '--count', 40,
                       '--type', 'gauge', '--output', poses_file,
                       '--evaluations', 2000)
    assert code == 0 and '40 readings of one coordinate' in out
    assert 'note' not in out
    rows = read_poses(poses_file)
    assert list(rows[0]) == HEADER.split(',') + [
        'gauge', 'nominal_x', 'nominal_y', 'nominal_z']
    assert all(r['x'] == r['y'] == r['z'] == '' for r in rows)
    lam = np.array([[float(r[f'lambda_{leg}']) for leg in 'abc']
                    for r in rows])
    nominal = np.array([[float(r[f'nominal_{c}']) for c in 'xyz']
                        for r in rows])
    assert np.allclose(mechanics.forward_kinematics(Robot(), lam), nominal,
                       atol=1e-12)
    # Unfilled, the file is refused, not read as the drawing's positions.
    code, out, err = run(capsys, 'calibrate', '--input', poses_file,
                         '--output', tmp_path / 'robot.yaml')
    assert_bad_input(code, out, err, 'line 2, columns x, y, z: no '
                     'coordinate measured')
    # Each row's gauge cell filled in, the rest of the file as written.
    readings = measured(lam)
    with open(poses_file) as stream:
        lines = stream.read().splitlines()
    for k, r in enumerate(rows):
        cells = lines[k + 1].split(',')
        cells[3 + 'xyz'.index(r['gauge'])] = repr(float(
            readings[k, 'xyz'.index(r['gauge'])]))
        lines[k + 1] = ','.join(cells)
    poses_file.write_text('\n'.join(lines) + '\n')
    code, out, _ = run(capsys, 'calibrate', '--input', poses_file,
                       '--output', tmp_path / 'robot.yaml')
    assert code == 0
    assert '40 measurements, 40 readings (x ' in out
    assert 'separate 18 of the 30' in out


def test_an_instrument_frame_is_reported(capsys, tmp_path, twenty):
    _, lam = twenty
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    readings = measured(lam) @ turn.T + np.array([2.0, 1.0, -0.5])
    path = write_measurements(tmp_path / 'm.csv', lam, readings)
    output = tmp_path / 'robot.yaml'
    code, _, err = run(capsys, 'calibrate', '--input', path, '--output',
                       output)
    assert_bad_input(code, '', err, ', column ', '--frame instrument')
    code, out, _ = run(capsys, 'calibrate', '--input', path, '--output',
                       output, '--frame', 'instrument')
    assert code == 0
    assert 'instrument: reads m = R G + t, t = [' in out
    assert 'its origin at [' in out
    assert 'rotation vector [' in out and ', 90' in out
    assert 'separate 18 of the 36 values' in out


def bad_file(tmp_path, text):
    path = tmp_path / 'bad.csv'
    path.write_text(text)
    return path


GOOD = '0.0,0.0,0.0,0.0,0.0,0.0\n'


@pytest.mark.parametrize('text, words', [
    (HEADER + '\n0.0,0.0,nan,0.0,0.0,0.0\n', ("(line 2), column 'lambda_c'",
                                              "'nan'")),
    (HEADER + '\n' + GOOD + '0.01,0.0,0.0,inf,0.0,0.0\n',
     ("(line 3), column 'x'", "'inf'")),
    (HEADER + '\n0.0,0.0,0.0,0.0,zero,0.0\n', ("(line 2), column 'y'",
                                               "'zero'")),
    (HEADER + '\n0.0,0.0,,0.0,0.0,0.0\n', ("(line 2), column 'lambda_c'",
                                           "''")),
    ('lambda_a,lambda_b,x,y,z\n0.0,0.0,0.0,0.0,0.0\n', ("'lambda_c'",)),
    ('lambda_a,lambda_b,lambda_c,x,y\n0.0,0.0,0.0,0.0,0.0\n', ("'z'",)),
    (HEADER + '\n' + GOOD + '0.8,0.8,0.8,0.0,0.0,0.0\n',
     ("line 3, column 'lambda_", 'outside')),
    (HEADER + '\n' + GOOD + '0.0,0.7,0.8,0.0,0.0,0.0\n',
     ("line 3, column 'lambda_c'", 'nearer a singularity than the margin')),
    (HEADER + '\n0.0,0.0,0.0,,,\n', ('line 2, columns x, y, z',
                                     'no coordinate measured')),
    (HEADER + '\n' + GOOD + '0.01,0.0,0.0,-1e308,0.0,0.0\n',
     ("line 3, column 'x'", '-1e+308 m is 1e+308 m from')),
    (HEADER + '\n' + GOOD + '0.01,0.0,0.0,0.0,0.0,1e308\n',
     ("line 3, column 'z'", 'beyond the 100 mm')),
    (HEADER + '\n' + GOOD + '0.01,0.0,0.0,0.0,1e200,0.0\n',
     ("line 3, column 'y'", 'beyond the 100 mm')),
    (HEADER + '\n' + GOOD + '1e308,0.0,0.0,0.0,0.0,0.0\n',
     ("line 3, column 'lambda_a'", 'outside')),
    (HEADER + '\n' + GOOD + '0.0,-1e308,0.0,0.0,0.0,0.0\n',
     ("line 3, column 'lambda_b'", 'outside')),
    (HEADER + '\n', ('no measurement',)),
    (HEADER + '\n' + GOOD + '0.01,0.0,0.0,0.0,0.0\n',
     ('data row 2 (line 3): 5 cells where the header has 6',)),
    (HEADER + '\n0.01,0.0,0.0,0.0,0.0,0.0,0.0\n',
     ('data row 1 (line 2): 7 cells where the header has 6',)),
    ('', ('empty file',)),
])
def test_bad_measurements_are_refused_naming_line_and_column(
        capsys, tmp_path, text, words):
    output = tmp_path / 'robot.yaml'
    code, out, err = run(capsys, 'calibrate', '--input',
                         bad_file(tmp_path, text), '--output', output,
                         '--report', tmp_path / 'r.png')
    assert_bad_input(code, out, err, *words)
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bad.csv']


def test_a_position_far_beyond_any_geometric_error_is_refused(
        capsys, tmp_path, twenty):
    _, lam = twenty
    readings = measured(lam)
    readings[4] *= 1000.0       # millimetres where metres are meant
    path = write_measurements(tmp_path / 'm.csv', lam, readings)
    code, out, err = run(capsys, 'calibrate', '--input', path, '--output',
                         tmp_path / 'robot.yaml')
    assert_bad_input(code, out, err, 'line 6, column', 'beyond the 100 mm',
                     'units m')
    assert not (tmp_path / 'robot.yaml').exists()


def test_too_few_measurements_are_refused(capsys, tmp_path, twenty):
    _, lam = twenty
    path = write_measurements(tmp_path / 'm.csv', lam[:2], measured(lam[:2]))
    code, out, err = run(capsys, 'calibrate', '--input', path, '--output',
                         tmp_path / 'robot.yaml')
    assert_bad_input(code, out, err, '6 readings: too few to identify')
    assert not (tmp_path / 'robot.yaml').exists()


def test_few_measurements_identify_what_they_can_and_say_so(capsys,
                                                            tmp_path,
                                                            twenty):
    _, lam = twenty
    path = write_measurements(tmp_path / 'm.csv', lam[:6], measured(lam[:6]))
    code, out, _ = run(capsys, 'calibrate', '--input', path, '--output',
                       tmp_path / 'robot.yaml')
    assert code == 0
    assert 'note: 18 readings: 12 of the 18 values these positions ' \
        'separate identified' in out
    assert 'not separated: too few readings' in out


@pytest.mark.parametrize('argv, words', [
    (['--bogus'], ('unrecognized arguments: --bogus',)),
    (['--frame', 'tracker'], ("--frame: invalid choice: 'tracker'",)),
])
def test_an_unknown_option_is_refused_in_one_line(capsys, tmp_path, twenty,
                                                  argv, words):
    output = tmp_path / 'robot.yaml'
    code, out, err = run(capsys, 'calibrate', '--input', twenty[0],
                         '--output', output, *argv)
    assert_bad_input(code, out, err, *words)
    assert not output.exists()


@pytest.mark.parametrize('argv, words', [
    (['--count', '7'], ('--count 7: below 8, the fewest whose readings '
                        'identify the 18 separable values with 6 readings '
                        'to spare',)),
    (['--count', '23', '--type', 'gauge'], ('--count 23: below 24',)),
    (['--count', '1001'], ('--count 1001: above 1000',)),
    (['--count', '12', '--evaluations', '10000001'],
     ('--evaluations: must be an integer in [1, 1e+07], got',)),
    (['--count', '12', '--type', 'laser'], ("invalid choice: 'laser'",)),
])
def test_calibration_poses_refuses_bad_arguments(capsys, tmp_path, argv,
                                                 words):
    output = tmp_path / 'poses.csv'
    code, out, err = run(capsys, 'calibration-poses', '--output', output,
                         *argv)
    assert_bad_input(code, out, err, *words)
    assert not output.exists()


def test_a_file_beyond_the_measurement_limit_is_refused(capsys, tmp_path,
                                                        twenty, monkeypatch):
    """The rule of MAX_MEASUREMENTS (10,000), shown on a limit of 15."""
    from orthoglide_ros.tools.calibration import measurements
    monkeypatch.setattr(measurements, 'MAX_MEASUREMENTS', 15)
    code, out, err = run(capsys, 'calibrate', '--input', twenty[0],
                         '--output', tmp_path / 'robot.yaml')
    assert_bad_input(code, out, err, 'more than 15 data rows')
    assert csvfile.MAX_ROWS > 15


def refused_nominal(capsys, tmp_path, twenty, command, rows):
    """Run ``command`` with a --params robot of ``rows``: its error line."""
    params = tmp_path / 'nominal.yaml'
    params.write_text('/**:\n  ros__parameters:\n    robot:\n' + ''.join(
        f'      {name}: {value}\n' for name, value in rows.items()))
    output = tmp_path / 'out.file'
    argv = (['--input', twenty[0]] if command == 'calibrate'
            else ['--count', '12'])
    code, out, err = run(capsys, command, *argv, '--params', params,
                         '--output', output)
    assert_bad_input(code, out, err, f'{params}: robot.')
    assert not output.exists()
    return err


@pytest.mark.parametrize('command', ['calibrate', 'calibration-poses'])
def test_a_nominal_robot_whose_legs_do_not_assemble_is_refused(
        capsys, tmp_path, twenty, command):
    # A small robot (bars of 0.1 m) whose leg A is shorter than its reach.
    err = refused_nominal(capsys, tmp_path, twenty, command, {
        'l3': '0.1', 'bar_length': '[0.05, 0.1, 0.1]',
        'axis_point_a': '[0.0, 0.08, 0.0]'})
    assert "robot.bar_length: leg A's bars (0.05 m) are shorter than its " \
        'reach' in err


@pytest.mark.parametrize('command', ['calibrate', 'calibration-poses'])
def test_a_nominal_robot_with_parallel_axes_is_refused(capsys, tmp_path,
                                                       twenty, command):
    err = refused_nominal(capsys, tmp_path, twenty, command, {
        'axis_direction_b': '[0.9962, 0.0872, 0.0]'})
    assert 'robot.axis_direction_b: parallel to robot.axis_direction_a' in err


def test_poses_on_standard_output_are_the_csv_alone(capsys):
    code, out, err = run(capsys, 'calibration-poses', '--count', 8,
                         '--output', '-', '--evaluations', 500)
    assert code == 0
    rows = list(csv.reader(out.splitlines()))
    assert rows[0] == HEADER.split(',') and len(rows) == 9
    assert all(len(row) == 6 for row in rows)
    assert 'condition number' in err and 'written' not in out + err
    assert 'note: 8 positions leave 6 readings to spare: too few to find a ' \
        'blunder reliably; 12 or more do' in err


def test_a_calibration_on_standard_output_is_the_yaml_alone(capsys, twenty):
    code, out, err = run(capsys, 'calibrate', '--input', twenty[0],
                         '--output', '-')
    assert code == 0
    document = yaml.safe_load(out)
    assert not params_file.robot_from_parameters(
        params_file.ParametersFile('-', document).section()).as_drawn
    assert err.startswith('Calibration from ') and 'written' not in err


def test_the_commands_pipe_into_each_other():
    """``calibration-poses --output - | calibrate --input - --output -``."""
    tool = os.path.join(os.path.dirname(sys.executable), 'orthoglide')
    design = subprocess.Popen(
        [tool, 'calibration-poses', '--count', '8', '--evaluations', '500',
         '--output', '-'], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    fit = subprocess.run([tool, 'calibrate', '--input', '-', '--output', '-'],
                         stdin=design.stdout, capture_output=True,
                         timeout=60)
    design.stdout.close()
    assert design.wait(60) == 0, design.stderr.read()
    assert 'condition number' in design.stderr.read().decode()
    design.stderr.close()
    assert fit.returncode == 0, fit.stderr
    # The designed positions are the nominal robot's exactly: calibrated,
    # the drawing again, within the rounding of the file's digits.
    robot = params_file.robot_from_parameters(params_file.ParametersFile(
        '-', yaml.safe_load(fit.stdout)).section())
    assert np.allclose(np.array(robot.bar_length), Robot().l3, atol=1e-9)
    assert fit.stderr.decode().startswith('Calibration from <stdin>: 8 ')


@pytest.mark.parametrize('value', ['-1e308', '1e308'])
def test_a_reading_near_the_largest_double_is_refused_in_any_frame(
        capsys, tmp_path, twenty, value):
    _, lam = twenty
    path = write_measurements(tmp_path / 'm.csv', lam, measured(lam))
    lines = path.read_text().splitlines()
    cells = lines[5].split(',')
    cells[4] = value
    lines[5] = ','.join(cells)
    path.write_text('\n'.join(lines) + '\n')
    for frame in ('robot', 'instrument'):
        code, out, err = run(capsys, 'calibrate', '--input', path,
                             '--output', tmp_path / 'robot.yaml', '--frame',
                             frame)
        assert_bad_input(code, out, err, "line 6, column 'y'",
                         f'{float(value):.6g} m is ', 'beyond the 100 mm')
    assert not (tmp_path / 'robot.yaml').exists()


def test_a_robot_that_reaches_too_little_is_refused_by_its_file(capsys,
                                                                tmp_path):
    params = tmp_path / 'short.yaml'
    params.write_text('/**:\n  ros__parameters:\n    robot:\n'
                      '      l3: 0.05\n')
    output = tmp_path / 'poses.csv'
    code, out, err = run(capsys, 'calibration-poses', '--count', 12,
                         '--params', params, '--output', output)
    assert_bad_input(code, out, err, f'error: {params}: the robot reaches '
                     'too little of the workspace cube')
    assert not output.exists()


def test_a_fit_that_leaves_more_than_any_instruments_noise_is_refused(
        capsys, tmp_path):
    """A 5 mm blunder among 8 positions, absorbed: 0.47 mm per reading."""
    from orthoglide_testing.robots_as_built import random_built
    from orthoglide_ros.tools.calibration import poses
    machine = Robot(**random_built(np.random.default_rng(0)))
    lam = mechanics.solve_batch(Robot(), poses._workspace(
        Robot(), np.random.default_rng(60), 8)).lambda_
    readings = measured(lam, robot=machine)
    readings[3, 1] += 5e-3
    path = write_measurements(tmp_path / 'm.csv', lam, readings)
    code, out, err = run(capsys, 'calibrate', '--input', path, '--output',
                         tmp_path / 'robot.yaml')
    assert_bad_input(code, out, err, 'um of noise per reading',
                     'beyond any instrument a calibration uses (100 um)',
                     'with 6 readings to spare a blunder may hide: measure '
                     '12 more coordinates (4 more positions in x, y and z)')
    assert not (tmp_path / 'robot.yaml').exists()


def test_a_row_repeated_exactly_counts_twice_and_is_said(capsys, tmp_path,
                                                         twenty):
    """A quantised gauge and encoders may read a position again alike."""
    lines = twenty[0].read_text().splitlines()
    path = tmp_path / 'm.csv'
    path.write_text('\n'.join(lines[:5] + [lines[3]] + lines[5:]) + '\n')
    code, out, err = run(capsys, 'calibrate', '--input', path, '--output',
                         tmp_path / 'robot.yaml')
    assert (code, err) == (0, '')
    assert '21 measurements, 63 readings' in out
    note = ('note: line 6 repeats line 4 exactly: counted as two '
            'measurements (a quantised instrument reads a position again '
            'alike; a row pasted twice would count twice too)')
    assert note in out.splitlines()
    assert f'# {note}' in (tmp_path / 'robot.yaml').read_text()
