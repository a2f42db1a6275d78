"""Tests of the ``orthoglide`` tool: paper, solve, batch and the tool as a whole."""

import json
import math
import os
from pathlib import Path
import shutil
import subprocess
import sys

import numpy as np
import pytest

from orthoglide_ros.formats.params_file import ParametersFile
from orthoglide_ros.model import mechanics, trajectory
from cli_runs import assert_bad_input, HEADER, PNG_MAGIC, read_csv, run, write_trajectory
from orthoglide_ros.model.robot import Robot

ROOT = Path(__file__).resolve().parents[1]
QUANTITIES = ('lambda', 'lambdadot', 'lambdaddot', 'force', 'power')


def eq6(t):
    """Eq. (6), written out independently: position, velocity, accel."""
    w = math.pi / 3.0
    r = (0.05, 0.10, -0.20)
    return ([c * (1.0 - math.cos(w * t)) for c in r],
            [c * w * math.sin(w * t) for c in r],
            [c * w * w * math.cos(w * t) for c in r])


def expected_row(sol):
    """Map a single-sample Solution onto the CSV column names."""
    return {f'{q}_{leg}': value for q, values in zip(QUANTITIES, sol)
            for leg, value in zip('abc', values)}


def assert_close(row, expected, tol=1e-12):
    """Check the CSV row's numbers against ``expected`` (name -> value)."""
    for name, value in expected.items():
        assert float(row[name]) == pytest.approx(value, rel=tol, abs=tol), (
            name)


def paper_csv(capsys, tmp_path, samples=11):
    """Write and read the paper CSV with ``samples`` instants."""
    path = tmp_path / 'paper.csv'
    assert run(capsys, 'paper', '--samples', samples, '--csv', path)[0] == 0
    return read_csv(path.read_text())


# -- paper --------------------------------------------------------------------

def test_paper_csv_has_header_n_rows_and_times_over_0_to_2(capsys, tmp_path):
    header, rows = paper_csv(capsys, tmp_path, samples=11)
    assert header == HEADER
    assert len(rows) == 11
    times = [float(r['t']) for r in rows]
    assert times[0] == 0.0 and times[-1] == 2.0
    assert times == pytest.approx([0.2 * i for i in range(11)], abs=1e-15)


def test_paper_default_is_201_samples(capsys, tmp_path):
    path = tmp_path / 'paper.csv'
    assert run(capsys, 'paper', '--csv', path)[0] == 0
    assert len(path.read_text().splitlines()) == 1 + 201


def test_paper_csv_equals_solve_on_eq6(capsys, tmp_path):
    _, rows = paper_csv(capsys, tmp_path, samples=21)
    for i in (0, 1, 7, 10, 20):
        p, v, a = eq6(2.0 * i / 20)
        sol = mechanics.solve(Robot(), p, v, a)
        assert_close(rows[i], dict(zip('xyz', p)))
        assert_close(rows[i], expected_row(sol))


def test_paper_csv_dash_goes_to_stdout(capsys, tmp_path):
    code, out, err = run(capsys, 'paper', '--samples', 5, '--csv', '-')
    assert code == 0 and err == ''
    header, rows = read_csv(out)
    assert header == HEADER and len(rows) == 5


def test_paper_summary_reports_peaks_and_statics(capsys):
    code, out, _ = run(capsys, 'paper')
    assert code == 0
    for label in ('peak |lambda| (m)', 'peak |force| (N)',
                  'peak |power| (W)', 'statics force at t=0 (N)'):
        assert label in out
    statics = mechanics.solve(Robot(), (0.0, 0.0, 0.0)).force[2]
    assert f'{statics:.6g}' in out


def test_paper_plot_writes_png(capsys, tmp_path):
    pytest.importorskip('matplotlib')
    png, table = tmp_path / 'fig.png', tmp_path / 'paper.csv'
    code, out, err = run(capsys, 'paper', '--samples', 21, '--plot', png,
                         '--csv', table)
    assert (code, out, err) == (0, '', '')
    assert png.read_bytes()[:8] == PNG_MAGIC
    assert len(table.read_text().splitlines()) == 22
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ['fig.png', 'paper.csv']


def test_paper_too_few_samples_is_a_usage_error(capsys):
    assert run(capsys, 'paper', '--samples', 1)[0] == 2


def test_paper_unreachable_trajectory_names_time(capsys, tmp_path):
    params = tmp_path / 'short.yaml'
    params.write_text('/**:\n  ros__parameters:\n    robot:\n'
                      '      l3: 0.3\n')
    out = tmp_path / 'paper.csv'
    code, stdout, err = run(capsys, 'paper', '--params', params, '--csv', out)
    assert_bad_input(code, stdout, err, 't = ')
    assert not out.exists()


# -- solve --------------------------------------------------------------------

SAMPLE = ('--position', 0.01, 0.02, -0.03, '--velocity', 0.1, -0.2, 0.05,
          '--acceleration', 1.0, 0.5, -2.0)


def test_solve_json_keys_are_the_csv_columns_less_t(capsys):
    code, out, _ = run(capsys, 'solve', *SAMPLE, '--json')
    assert code == 0
    record = json.loads(out)
    assert list(record) == HEADER.split(',')[1:]
    sol = mechanics.solve(Robot(), (0.01, 0.02, -0.03), (0.1, -0.2, 0.05),
                          (1.0, 0.5, -2.0))
    expected = dict(x=0.01, y=0.02, z=-0.03, **expected_row(sol))
    assert record == expected       # full double precision survives


def test_solve_table_has_rows_with_units(capsys):
    code, out, _ = run(capsys, 'solve', *SAMPLE)
    assert code == 0
    for label in ('lambda (m)', 'lambdadot (m/s)', 'lambdaddot (m/s^2)',
                  'force (N)', 'power (W)', 'singularity distance'):
        assert label in out


@pytest.mark.parametrize('position', [('0.9', '0', '0'), ('nan', '0', '0')])
def test_solve_refused_position_exits_2(capsys, position):
    code, out, err = run(capsys, 'solve', '--position', *position)
    assert_bad_input(code, out, err, 'position')


# -- batch --------------------------------------------------------------------

def paper_trajectory(samples=21):
    """Columns and rows t,x,y,z,vx,...,az of eq. (6)."""
    rows = []
    for i in range(samples):
        t = 2.0 * i / (samples - 1)
        p, v, a = eq6(t)
        rows.append([t] + p + v + a)
    return 't,x,y,z,vx,vy,vz,ax,ay,az'.split(','), rows


def test_batch_round_trip_of_the_paper_csv(capsys, tmp_path):
    _, paper = paper_csv(capsys, tmp_path, samples=21)
    columns, rows = paper_trajectory(21)
    for row, ours in zip(rows, paper):      # t, x, y, z as the CSV has them
        row[:4] = [float(ours[c]) for c in 'txyz']
    source = write_trajectory(tmp_path / 'in.csv', columns, rows)
    out = tmp_path / 'out.csv'
    assert run(capsys, 'batch', '--input', source, '--output', out) == (
        0, '', '')
    header, result = read_csv(out.read_text())
    assert header == HEADER and len(result) == 21
    for got, want in zip(result, paper):
        assert got['t'] == want['t']
        assert_close(got, {k: float(v) for k, v in want.items()})


def test_batch_missing_velocity_and_acceleration_mean_zero(capsys, tmp_path):
    columns, rows = paper_trajectory(6)
    short = write_trajectory(tmp_path / 'short.csv', columns[:4],
                             [r[:4] for r in rows])
    zeros = write_trajectory(tmp_path / 'zeros.csv', columns,
                             [r[:4] + [0.0] * 6 for r in rows])
    _, out_short, err_short = run(capsys, 'batch', '--input', short)
    _, out_zeros, err_zeros = run(capsys, 'batch', '--input', zeros)
    assert out_short == out_zeros
    # Said once, on standard error; nothing said of a file that has them.
    assert err_short == (f'orthoglide: note: {short} has no velocity (vx, '
                         'vy, vz) and no acceleration (ax, ay, az) columns: '
                         'taken as zero\n')
    assert err_zeros == ''
    _, result = read_csv(out_short)
    sol = mechanics.solve(Robot(), rows[3][1:4])
    assert_close(result[3], expected_row(sol))


def test_batch_columns_match_by_name_in_any_order(capsys, tmp_path):
    columns, rows = paper_trajectory(6)
    order = [9, 0, 5, 3, 1, 7, 2, 4, 8, 6]
    shuffled = write_trajectory(
        tmp_path / 'shuffled.csv', ['note'] + [columns[i] for i in order],
        [[42.0] + [r[i] for i in order] for r in rows])
    plain = write_trajectory(tmp_path / 'plain.csv', columns, rows)
    code, out_shuffled, _ = run(capsys, 'batch', '--input', shuffled)
    assert code == 0
    assert out_shuffled == run(capsys, 'batch', '--input', plain)[1]


def test_batch_without_t_column_leaves_t_empty(capsys, tmp_path):
    source = write_trajectory(tmp_path / 'in.csv', ['x', 'y', 'z'],
                              [[0.0, 0.0, 0.0], [0.01, 0.0, 0.0]])
    code, out, _ = run(capsys, 'batch', '--input', source)
    assert code == 0
    _, rows = read_csv(out)
    assert [r['t'] for r in rows] == ['', '']
    assert float(rows[1]['x']) == 0.01


def test_batch_uses_params_file(capsys, tmp_path):
    source = write_trajectory(tmp_path / 'in.csv', ['x', 'y', 'z'],
                              [[0.0, 0.0, 0.0]])
    params = tmp_path / 'heavy.yaml'
    params.write_text((ROOT / 'config' / 'orthoglide.yaml').read_text()
                      .replace('m5: 15.0', 'm5: 20.0'))
    same = run(capsys, 'batch', '--input', source, '--params',
               ROOT / 'config' / 'orthoglide.yaml')[1]
    assert same == run(capsys, 'batch', '--input', source)[1]
    _, rows = read_csv(run(capsys, 'batch', '--input', source, '--params',
                           params)[1])
    force = mechanics.solve(Robot(m5=20.0), (0.0, 0.0, 0.0)).force
    assert_close(rows[0], {'force_c': force[2]})


BAD_TRAJECTORIES = {
    'missing_position_column': ('t,x,z\n0.0,0.0,0.0\n', ["'y'"]),
    'partial_velocity_group': ('x,y,z,vx\n0.0,0.0,0.0,1.0\n', ["'vy'"]),
    'non_numeric_cell': ('t,x,y,z\n0.0,0,0,0\n0.1,0,abc,0\n',
                         ['data row 2', "'y'", 'abc']),
    'nan_cell': ('x,y,z,ax,ay,az\n0,0,0,0,0,0\n0,0,0,0,0,0\n0,0,0,0,nan,0\n',
                 ['data row 3', "'ay'"]),
    'empty_cell': ('x,y,z\n0,0,0\n0,,0\n', ['data row 2', "'y'"]),
    'unreachable_point': ('t,x,y,z\n0,0,0,0\n1,0.01,0,0\n2,0.9,0,0\n',
                          ['data row 3', 'out of reach']),
    'empty_file': ('', ['header']),
}


@pytest.mark.parametrize('name', sorted(BAD_TRAJECTORIES))
@pytest.mark.parametrize('existing', [False, True])
def test_batch_bad_input_exits_2_and_writes_nothing(capsys, tmp_path, name,
                                                    existing):
    text, words = BAD_TRAJECTORIES[name]
    source = tmp_path / 'in.csv'
    source.write_text(text)
    out = tmp_path / 'out.csv'
    if existing:
        out.write_text('old\n')
    code, stdout, err = run(capsys, 'batch', '--input', source, '--output',
                            out)
    assert_bad_input(code, stdout, err, *words)
    assert out.read_text() == 'old\n' if existing else not out.exists()
    assert sorted(os.listdir(tmp_path)) == sorted(
        ['in.csv'] + (['out.csv'] if existing else []))


def test_batch_missing_input_file_exits_2(capsys, tmp_path):
    code, out, err = run(capsys, 'batch', '--input', tmp_path / 'nope.csv')
    assert_bad_input(code, out, err, 'nope.csv')


BAD_PARAMS = {
    'unknown': ('      l7: 0.1\n', 'robot.l7'),
    'integer': ('      l3: 1\n', 'robot.l3'),
    'string': ('      m5: heavy\n', 'robot.m5'),
    'negative': ('      m1: -0.35\n', 'robot.m1'),
    'mixed_gravity': ('      gravity: [0, 0.0, -9.81]\n', 'robot.gravity'),
}


@pytest.mark.parametrize('name', sorted(BAD_PARAMS))
@pytest.mark.parametrize('command', ['paper', 'solve', 'batch'])
def test_bad_parameter_exits_2_naming_it(capsys, tmp_path, name, command):
    entry, parameter = BAD_PARAMS[name]
    params = tmp_path / 'params.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n    robot:\n'
                      + entry)
    source = write_trajectory(tmp_path / 'in.csv', ['x', 'y', 'z'],
                              [[0.0, 0.0, 0.0]])
    out = tmp_path / 'out.csv'
    argv = {'paper': ['paper', '--csv', out],
            'solve': ['solve', '--position', 0, 0, 0, '--json'],
            'batch': ['batch', '--input', source, '--output', out]}[command]
    code, stdout, err = run(capsys, *argv, '--params', params)
    assert_bad_input(code, stdout, err, parameter, 'params.yaml')
    assert not out.exists()


def test_unreadable_params_file_exits_2(capsys, tmp_path):
    code, out, err = run(capsys, 'solve', '--position', 0, 0, 0, '--params',
                         tmp_path / 'missing.yaml')
    assert_bad_input(code, out, err, 'missing.yaml')


def test_friction_of_the_params_file_reaches_solve_batch_and_paper(
        capsys, tmp_path):
    """robot.friction_* read by --params: in every force and power."""
    params = tmp_path / 'friction.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n    robot:\n'
                      '      friction_viscous: [30.0, 40.0, 50.0]\n'
                      '      friction_coulomb: [5.0, 3.0, 4.0]\n'
                      '      friction_velocity: 0.002\n'
                      '      friction_coulomb_negative: [5.0, 3.0, 4.0]\n'
                      '      friction_stribeck: [0.0, 0.0, 0.0]\n')
    robot = Robot(friction_viscous=(30.0, 40.0, 50.0),
                  friction_coulomb=(5.0, 3.0, 4.0), friction_velocity=0.002)
    p, v, a = eq6(0.7)
    code, out, _ = run(capsys, 'solve', '--position', *p, '--velocity', *v,
                       '--acceleration', *a, '--json', '--params', params)
    assert code == 0
    assert_close(json.loads(out), expected_row(mechanics.solve(robot, p, v,
                                                               a)))
    rigid = mechanics.solve(Robot(), p, v, a)
    assert json.loads(out)['force_a'] - rigid.force[0] == pytest.approx(
        30.0 * rigid.lambdadot[0] + 5.0 * math.tanh(rigid.lambdadot[0]
                                                    / 0.002), rel=1e-9)
    columns, rows = paper_trajectory(5)
    source = write_trajectory(tmp_path / 'in.csv', columns, rows)
    for argv in (['batch', '--input', source], ['paper', '--samples', 5,
                                                '--csv', '-']):
        code, out, _ = run(capsys, *argv, '--params', params)
        assert code == 0
        _, result = read_csv(out)
        for row in result:
            t = float(row['t'])
            assert_close(row, expected_row(mechanics.solve(robot, *eq6(t))),
                         tol=1e-9)


# -- the tool as a whole ------------------------------------------------------

@pytest.mark.parametrize('command,units', [
    ('paper', ['(m', '(W', ' s']), ('solve', ['m/s^2', '(N', '(W']),
    ('batch', ['m/s^2', '(m)', '(s)']),
    ('excitation', ['m/s^2', '(s)', 'm/s']),
    ('identify', ['(kg)', '(N s/m)', '(Hz;']), ('record', ['(s;'])])
def test_help_gives_units(capsys, command, units):
    code, out, _ = run(capsys, command, '--help')
    assert code == 0
    for unit in units:
        assert unit in out


def test_cli_imports_neither_rclpy_nor_matplotlib():
    # Nor scipy and rosbags, which only identification's steps need.
    code = ('import sys; from orthoglide_ros.tools import cli; '
            'assert cli.main(["paper"]) == 0; '
            'bad = {"rclpy", "matplotlib", "scipy", "rosbags"} '
            '& set(sys.modules); '
            'assert not bad, bad')
    done = subprocess.run([sys.executable, '-c', code], cwd=ROOT,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def console_script():
    """Path of the installed ``orthoglide`` script, or None."""
    venv = ROOT / '.venv' / 'bin' / 'orthoglide'
    return shutil.which('orthoglide') or (str(venv) if venv.exists()
                                          else None)


def test_console_script_runs_batch_and_reports_errors(tmp_path):
    script = console_script()
    if script is None:
        pytest.skip('the orthoglide console script is not installed')
    columns, rows = paper_trajectory(5)
    source = write_trajectory(tmp_path / 'in.csv', columns, rows)
    done = subprocess.run([script, 'batch', '--input', source],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    header, result = read_csv(done.stdout)
    assert header == HEADER and len(result) == 5
    sol = mechanics.solve(Robot(), rows[2][1:4], rows[2][4:7], rows[2][7:])
    assert_close(result[2], expected_row(sol))
    source.write_text('x,y\n0,0\n')
    done = subprocess.run([script, 'batch', '--input', source],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.startswith('orthoglide: error: ')


@pytest.mark.parametrize('argv', [
    ['solve', '--position', '0', '0', '0'],             # one print
    ['paper', '--samples', '20000', '--csv', '-'],      # chunks of bytes
])
def test_output_whose_reader_is_gone_ends_quietly(argv):
    """``orthoglide ... | head -1``: status 141 as SIGPIPE's, no traceback."""
    script = console_script()
    if script is None:
        pytest.skip('the orthoglide console script is not installed')
    read, write = os.pipe()
    os.close(read)      # the reader gone before the first write
    try:
        done = subprocess.run([script, *argv], stdout=write,
                              stderr=subprocess.PIPE, timeout=60)
    finally:
        os.close(write)
    assert (done.returncode, done.stderr) == (141, b'')
    shell = subprocess.run(f'{script} {" ".join(argv)} | head -1; exit '
                           '"${PIPESTATUS[0]}"', shell=True,
                           executable='/bin/bash', capture_output=True,
                           timeout=60)
    assert shell.stderr == b'' and len(shell.stdout.splitlines()) == 1
    assert shell.returncode in (0, 141)


# batch --format joint_trajectory ---------------------------------------------
def joint_trajectory_of(document):
    """Fill a trajectory_msgs/JointTrajectory from its YAML mapping."""
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    msg = JointTrajectory(joint_names=document['joint_names'])
    stamp = document['header']['stamp']
    msg.header.stamp.sec, msg.header.stamp.nanosec = (stamp['sec'],
                                                      stamp['nanosec'])
    msg.header.frame_id = document['header']['frame_id']
    for point in document['points']:
        made = JointTrajectoryPoint(
            positions=point['positions'], velocities=point['velocities'],
            accelerations=point['accelerations'], effort=point['effort'])
        made.time_from_start.sec = point['time_from_start']['sec']
        made.time_from_start.nanosec = point['time_from_start']['nanosec']
        msg.points.append(made)
    return msg


def test_batch_writes_a_joint_trajectory_ros_reads(tmp_path, capsys):
    """Every point equals solve_batch; the YAML fills a JointTrajectory."""
    pytest.importorskip('rclpy')
    import yaml
    times = trajectory.paper_times(21)
    p, v, a = trajectory.paper_batch(times)
    source = tmp_path / 'in.csv'
    rows = ['t,x,y,z,vx,vy,vz,ax,ay,az'] + [
        ','.join(repr(float(x)) for x in (t, *p[k], *v[k], *a[k]))
        for k, t in enumerate(times)]
    source.write_text('\n'.join(rows) + '\n')
    params = tmp_path / 'params.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n'
                      '    joint_names: [ja, jb, jc]\n')
    out = tmp_path / 'out.yaml'
    code, _, err = run(capsys, 'batch', '--input', source, '--format',
                       'joint_trajectory', '--params', params,
                       '--output', out)
    assert code == 0, err
    msg = joint_trajectory_of(yaml.safe_load(out.read_text()))
    s = mechanics.solve_batch(Robot(), p, v, a)
    assert list(msg.joint_names) == ['ja', 'jb', 'jc']
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)
    assert len(msg.points) == 21
    for k, point in enumerate(msg.points):
        assert list(point.positions) == list(s.lambda_[k])
        assert list(point.velocities) == list(s.lambdadot[k])
        assert list(point.accelerations) == list(s.lambdaddot[k])
        assert list(point.effort) == list(s.force[k])
        ns = point.time_from_start.sec * 10**9 + \
            point.time_from_start.nanosec
        assert ns == round(times[k] * 1e9)


# Every command that takes --params, run on a small valid input: each
# reads the file once, whatever it takes from it (robot, joint_names, the
# planner's joint_limits). WORDS: inputs written by params_once_inputs.
PARAMS_COMMANDS = {
    'paper': ['--samples', '3'],
    'solve': ['--position', '0', '0', '0', '--json'],
    'batch': ['--format', 'joint_trajectory', '--input', 'TRAJECTORY',
              '--output', 'OUT'],
    'plan': ['--format', 'joint_trajectory', '--input', 'PROGRAM',
             '--output', 'OUT'],
    'excitation': ['--duration', '2', '--rate', '50', '--output', 'OUT'],
    'identify': ['--input', 'LOG', '--output', 'OUT'],
    'validate': ['--input', 'LOG'],
    'calibration-poses': ['--count', '12', '--evaluations', '1',
                          '--output', 'OUT'],
    'calibrate': ['--input', 'MEASUREMENTS', '--output', 'OUT'],
    'urdf': ['--output', 'OUT'],
    'mjcf': ['--output', 'OUT'],
    'draw': ['--position', '0', '0', '0', '--size', '100', '100', '--output',
             'OUT.png'],
    'animate': ['--frames', '2', '--size', '100', '100', '--output',
                'OUT.gif'],
    # render: MuJoCo's OpenGL context stays out of the test's process
    # (test_mjcf runs it as a process); it takes the robot main read.
}


def params_once_inputs(tmp_path):
    """Write the inputs PARAMS_COMMANDS names; return ``{word: path}``."""
    from orthoglide_ros.model.mechanics import (forward_kinematics,
                                                solve_batch)
    from cli_runs import identification_log
    program = tmp_path / 'part.nc'
    program.write_text('G21 G90 F6000\nG1 X20\nM2\n')
    positions = np.random.default_rng(3).uniform(-0.2, 0.2, (12, 3))
    lam = solve_batch(Robot(), positions).lambda_
    measurements = tmp_path / 'measurements.csv'
    measurements.write_text('lambda_a,lambda_b,lambda_c,x,y,z\n' + ''.join(
        ','.join(map(repr, row)) + '\n' for row in np.column_stack(
            (lam, forward_kinematics(Robot(), lam))).tolist()))
    return {'TRAJECTORY': write_trajectory(tmp_path / 'in.csv',
                                           ('t', 'x', 'y', 'z'),
                                           [(0.0, 0.0, 0.0, 0.0)]),
            'PROGRAM': program,
            'LOG': identification_log(tmp_path, duration=6.0)[0],
            'MEASUREMENTS': measurements,
            'OUT': tmp_path / 'out', 'OUT.png': tmp_path / 'out.png',
            'OUT.gif': tmp_path / 'out.gif'}


def test_every_command_with_params_is_checked_for_one_reading():
    from orthoglide_ros.tools import cli
    commands = {c.name for module in (
        cli.solving, cli.planning, cli.identifying, cli.calibrating,
        cli.models, cli.pictures) for c in module.SUBCOMMANDS if c.robot}
    assert commands - set(PARAMS_COMMANDS) == {'render'}
    assert set(PARAMS_COMMANDS) <= commands


def test_command_modules_share_helpers_through_common_alone():
    """A command module imports from cli.common, never from another's."""
    import ast
    folder = ROOT / 'orthoglide_ros' / 'tools' / 'cli'
    for path in sorted(folder.glob('*.py')):
        if path.name in ('__init__.py', '__main__.py', 'common.py'):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and \
                    node.module.startswith('orthoglide_ros.tools.cli'):
                assert node.module == 'orthoglide_ros.tools.cli.common', \
                    f'{path.name} imports {node.module}'


@pytest.mark.parametrize('command', sorted(PARAMS_COMMANDS))
def test_params_is_read_once_per_command(tmp_path, capsys, monkeypatch,
                                         command):
    """The robot, the joint names, the limits: one reading of --params."""
    reads = []
    read = ParametersFile.read.__func__

    def counted(cls, path):
        reads.append(path)
        return read(cls, path)
    monkeypatch.setattr(ParametersFile, 'read', classmethod(counted))
    params = tmp_path / 'params.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n'
                      '    joint_names: [ja, jb, jc]\n'
                      '    robot: {m5: 16.0}\n'
                      'planner:\n  ros__parameters:\n'
                      '    joint_limits:\n'
                      '      ja: {has_effort_limits: true, '
                      'max_effort: 400.0}\n')
    files = params_once_inputs(tmp_path)
    code, _, err = run(capsys, command, *[
        files.get(word, word) for word in PARAMS_COMMANDS[command]],
        '--params', params)
    assert code == 0, err
    assert reads == [str(params)]
    if command in ('batch', 'plan'):
        assert 'joint_names: ["ja", "jb", "jc"]' in files['OUT'].read_text()


@pytest.mark.parametrize('rows, words', [
    (['x,y,z', '0,0,0'], ["'t'"]),
    (['t,x,y,z', '0.5,0,0,0', '0.5,0,0,0'], ['data row 2', 'increase']),
    (['t,x,y,z', '-0.1,0,0,0'], ['data row 1', '[0, 2**31)']),
    (['t,x,y,z', '0,0,0,0', '3e9,0,0,0'], ['data row 2', '[0, 2**31)']),
    # Apart by less than half a nanosecond: the same time_from_start.
    (['t,x,y,z', '0,0,0,0', '1e-10,0,0,0'], ['data row 2', 'nanosecond']),
    (['t,x,y,z'], ['no data row']),
])
def test_batch_joint_trajectory_needs_increasing_times(tmp_path, capsys,
                                                       rows, words):
    source = tmp_path / 'in.csv'
    source.write_text('\n'.join(rows) + '\n')
    code, out, err = run(capsys, 'batch', '--input', source, '--format',
                         'joint_trajectory')
    assert_bad_input(code, out, err, *words)
