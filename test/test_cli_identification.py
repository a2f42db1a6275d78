"""Tests of the ``orthoglide`` tool: excitation, identify, validate, record."""

import json
import math
import re

import numpy as np
import pytest

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools import cli
from cli_runs import (assert_bad_input, HEADER, identification_log, PNG_MAGIC,
                      read_csv, run)


TRAJECTORY_HEADER = 't,x,y,z,vx,vy,vz,ax,ay,az'


def test_excitation_writes_the_batch_input_columns(capsys, tmp_path):
    path = tmp_path / 'excitation.csv'
    code, out, err = run(capsys, 'excitation', '--duration', 3, '--output',
                         path, '--seed', 2, '--rate', 200)
    assert (code, err) == (0, '')
    assert 'seed 2, period 3 s, 5 harmonics (0.333333 to 1.66667 Hz)' in out
    for label in ('peak |position| (m)', 'peak |velocity| (m/s)',
                  'peak |acceleration| (m/s^2)', 'singularity distance',
                  'm5 + 3 m4', 'condition number of the base regressor'):
        assert label in out
    header, rows = read_csv(path.read_text())
    assert header == TRAJECTORY_HEADER and len(rows) == 600
    motion = trajectory.excitation(2, 3.0)
    for i in (0, 77, 599):
        t = float(rows[i]['t'])
        assert t == pytest.approx(i / 200.0, abs=1e-12)
        p, v, a = trajectory.excitation_sample(motion, t)
        assert [float(rows[i][c]) for c in TRAJECTORY_HEADER.split(',')[1:]
                ] == pytest.approx([*p, *v, *a], rel=1e-12, abs=1e-15)
    # The file is a batch input: orthoglide batch solves it.
    solved = tmp_path / 'solved.csv'
    assert run(capsys, 'batch', '--input', path, '--output', solved)[0] == 0
    assert read_csv(solved.read_text())[0] == HEADER


def test_excitation_condition_number_is_the_libraries(capsys, tmp_path):
    from orthoglide_ros.tools import identification
    code, out, _ = run(capsys, 'excitation', '--duration', 4, '--output',
                       tmp_path / 'e.csv')
    assert code == 0
    motion = trajectory.excitation(0, 4.0)
    times = np.arange(0.0, 4.0, 0.01)
    condition = identification.condition_number(
        Robot(), *trajectory.excitation_batch(motion, times))
    assert f'condition number of the base regressor: {condition:.4g}' in out


@pytest.mark.parametrize('argv', [
    ['--seeds', '0'], ['--seed', '-1'], ['--duration', '0'],
    ['--duration', 'nan'], ['--rate', '-5']])
def test_excitation_refuses_bad_arguments(capsys, tmp_path, argv):
    out_file = tmp_path / 'e.csv'
    full = {'--duration': '5', '--output': str(out_file)}
    full.update(dict(zip(argv[::2], argv[1::2])))
    code, out, err = run(capsys, 'excitation',
                         *[x for kv in full.items() for x in kv])
    assert code == 2 and out == '' and argv[0] in err
    assert not out_file.exists()


@pytest.mark.parametrize('missing', ['--duration', '--output'])
def test_excitation_needs_duration_and_output(capsys, tmp_path, missing):
    full = {'--duration': '5', '--output': str(tmp_path / 'e.csv')}
    del full[missing]
    code, _, err = run(capsys, 'excitation',
                       *[x for kv in full.items() for x in kv])
    assert code == 2 and missing in err


def test_excitation_writes_the_best_of_several_seeds(capsys, tmp_path):
    path = tmp_path / 'best.csv'
    code, out, _ = run(capsys, 'excitation', '--duration', 5, '--seed', 10,
                       '--seeds', 3, '--output', path, '--rate', 100)
    assert code == 0
    lines = [line for line in out.splitlines()
             if line.strip().startswith('seed 1')]
    assert [line.split()[1] for line in lines] == ['10', '11', '12']
    conditions = [float(line.split()[2]) for line in lines]
    best = 10 + int(np.argmin(conditions))
    assert sum('(best: written)' in line for line in lines) == 1
    assert f'Excitation: seed {best}, period 5 s' in out
    _, rows = read_csv(path.read_text())
    p, _, _ = trajectory.excitation_sample(trajectory.excitation(best, 5.0),
                                           float(rows[123]['t']))
    assert float(rows[123]['x']) == pytest.approx(p[0], rel=1e-12)


@pytest.mark.slow     # 1.6-3.6 s of CPU, one process, 2026-12-06
def test_identify_writes_a_parameters_file_the_tools_read(capsys, tmp_path):
    from orthoglide_ros.formats import params_file
    from orthoglide_ros.tools import identification
    source, log = identification_log(tmp_path)
    out = tmp_path / 'identified.yaml'
    code, stdout, err = run(capsys, 'identify', '--input', source,
                            '--output', out)
    assert (code, err) == (0, '')
    expected = identification.identify(Robot(), log)
    robot = params_file.load_robot(out)
    assert robot == expected.robot
    values = params_file.load_parameters(out)
    assert all(type(v) is float or all(type(c) is float for c in v)
               for v in values.values())
    assert len(values) == len(Robot.parameter_names())
    # Under /**: every node's section, not the feedforward's alone.
    assert params_file.load_parameters(out, 'mechanism_state_publisher') \
        == values
    assert f'written: {out}' in stdout
    code, solved, _ = run(capsys, 'solve', '--position', 0, 0, 0, '--json',
                          '--params', out)
    assert code == 0
    assert json.loads(solved)['force_c'] == pytest.approx(
        mechanics.solve(robot, (0.0, 0.0, 0.0)).force[2], rel=1e-12)


def test_identify_reports_fit_quality_and_base_parameters(capsys, tmp_path):
    """Each base parameter, meaning, estimate, rel. std; condition; RMS; samples, span."""
    from orthoglide_ros.tools import identification
    source, log = identification_log(tmp_path)
    code, out, _ = run(capsys, 'identify', '--input', source, '--output',
                       tmp_path / 'out.yaml', '--start', 1.0)
    assert code == 0
    expected = identification.identify(Robot(), identification.crop(log, 1.0))
    lines = out.splitlines()
    for name, meaning, value, relative in zip(
            expected.base.names, expected.base.meanings, expected.values,
            expected.relative_std):
        (line,) = [x for x in lines if x.startswith(name + ' (')]
        assert line.endswith(meaning)
        assert f'{value:.6g}' in line and f'{relative:.3g}' in line
    assert (f'condition number of the base regressor: '
            f'{expected.condition:.4g}') in out
    assert 'RMS residual per actuator (N): ' + ', '.join(
        f'{leg} {r:.4g}' for leg, r in zip('ABC', expected.residual_rms)
    ) in out
    used = expected.samples.times
    assert (f'20000 samples over [0, 19.999] s (19.999 s); 19000 in the '
            f'window [1, 19.999] s (18.999 s); {len(used)} used over '
            f'[{used[0]:.6g}, {used[-1]:.6g}] s') in out


def test_identify_draws_the_report(capsys, tmp_path):
    source, _ = identification_log(tmp_path, duration=8.0)
    report = tmp_path / 'report.png'
    code, out, err = run(capsys, 'identify', '--input', source, '--output',
                         tmp_path / 'out.yaml', '--report', report)
    assert (code, err) == (0, '')
    assert report.read_bytes().startswith(PNG_MAGIC)
    assert f'written: {report}' in out


def test_identify_validates_on_another_log(capsys, tmp_path):
    source, _ = identification_log(tmp_path)
    other, _ = identification_log(tmp_path, 'other.csv', seed=4,
                                  duration=6.0)
    code, out, _ = run(capsys, 'identify', '--input', source, '--validate',
                       other, '--output', tmp_path / 'out.yaml')
    assert code == 0
    nominal = [float(v) for v in next(
        line for line in out.splitlines() if 'nominal robot' in line)
        .split()[-3:]]
    identified = [float(v) for v in next(
        line for line in out.splitlines() if 'identified robot' in line)
        .split()[-3:]]
    assert all(10.0 * i < n for i, n in zip(identified, nominal))


@pytest.fixture(scope='module')
def from_csv(tmp_path_factory):
    """Return the robot identify finds from a 6 s CSV log (no lag)."""
    from orthoglide_ros.formats import params_file
    tmp_path = tmp_path_factory.mktemp('from_csv')
    source, _ = identification_log(tmp_path, duration=6.0)
    assert cli.main(['identify', '--input', str(source), '--output',
                     str(tmp_path / 'out.yaml'), '--force-lag', '0']) == 0
    return params_file.load_robot(tmp_path / 'out.yaml')


@pytest.mark.parametrize('storage,form,topic', [
    ('mcap', 'directory', None), ('mcap', 'file', 'joint_states'),
    ('sqlite3', 'directory', '/joint_states'), ('sqlite3', 'file', None)])
def test_identify_reads_bags_of_both_storages(capsys, tmp_path, from_csv,
                                              storage, form, topic):
    """A bag directory or its storage file: the robot of the same CSV log."""
    from orthoglide_ros.formats import params_file
    from orthoglide_ros.tools import identification
    from synthetic_logs import storage_file, synthetic_log, TRUE, write_bag
    write_bag(tmp_path / 'bag', synthetic_log(TRUE, 0, 5.0, 11,
                                              duration=6.0), storage)
    path = tmp_path / 'bag' if form == 'directory' else storage_file(
        tmp_path / 'bag')
    out = tmp_path / 'from_bag.yaml'
    code, _, err = run(capsys, 'identify', '--input', path, '--output', out,
                       '--force-lag', 0,
                       *(['--topic', topic] if topic else []))
    assert (code, err) == (0, '')
    # The bag's stamps are the CSV's times to the nanosecond (a lag
    # estimated would move by their rounding).
    assert np.allclose(*(identification.standard_parameters(robot)
                         for robot in (params_file.load_robot(out),
                                       from_csv)), rtol=1e-9, atol=0.0)


def bad_logs(tmp_path):
    """Write every kind of log identify must refuse; return name -> path."""
    from synthetic_logs import (one_actuator_log, spoiled, synthetic_log,
                                TRUE, write_bag, write_csv)
    log = synthetic_log(TRUE, 0, 5.0, 12, duration=8.0)
    header = 't,lambda_a,lambda_b,lambda_c,force_a,force_b,force_c'
    rest = mechanics.solve(TRUE, (0.0, 0.0, 0.0))
    rng = np.random.default_rng(3)
    times = np.arange(0.0, 8.0, 1e-3)
    at_rest = log._replace(
        times=times, lambdas=np.tile(rest.lambda_, (len(times), 1)),
        forces=rest.force + rng.normal(0.0, 0.5, (len(times), 3)))
    paths = {
        'missing_file': tmp_path / 'nope.csv',
        'missing_column': tmp_path / 'column.csv',
        'nan': write_csv(tmp_path / 'nan.csv',
                         spoiled(log, 'forces', 99, 1, math.nan)),
        'inf': write_csv(tmp_path / 'inf.csv',
                         spoiled(log, 'lambdas', 5, 2, math.inf)),
        'time': write_csv(tmp_path / 'time.csv',
                          spoiled(log, 'times', 40, 0, log.times[39])),
        'few': write_csv(tmp_path / 'few.csv', log._replace(
            times=log.times[:2500], lambdas=log.lambdas[:2500],
            forces=log.forces[:2500])),
        'rest': write_csv(tmp_path / 'rest.csv', at_rest),
        'one_actuator': write_csv(tmp_path / 'one.csv', one_actuator_log()),
        'bag': tmp_path / 'bag',
    }
    paths['missing_column'].write_text(header.replace(',force_b', '')
                                       + '\n0,0,0,0,0,0\n')
    write_bag(paths['bag'], log, 'mcap')
    return paths


BAD_IDENTIFY = {
    'missing_file': ([], ['nope.csv']),
    'missing_column': ([], ["no 'force_b' column"]),
    'nan': ([], ['data row 100 (line 101)', "'force_b'"]),
    'inf': ([], ['data row 6 (line 7)', "'lambda_c'"]),
    'time': ([], ['data row 41 (line 42): time 0.039 s is not after']),
    'few': ([], ['42 usable samples, at least 90']),
    'rest': ([], ['shows no motion', 'viscous_a ', 'viscous_c ',
                  'orthoglide excitation']),
    'missing_topic': (['--topic', 'nothing'], ['no topic /nothing',
                                               '/joint_states']),
    'cutoff_above_nyquist': (['--cutoff', '600'], ['cutoff', '500']),
}


@pytest.fixture(scope='module')
def bad_log_paths(tmp_path_factory):
    return bad_logs(tmp_path_factory.mktemp('bad_logs'))


@pytest.mark.parametrize('name', sorted(BAD_IDENTIFY))
def test_identify_bad_input_exits_2_and_writes_nothing(capsys, tmp_path,
                                                       bad_log_paths, name):
    argv, words = BAD_IDENTIFY[name]
    source = bad_log_paths.get(name, bad_log_paths[
        'bag' if name == 'missing_topic' else 'few'])
    if name == 'cutoff_above_nyquist':
        source = bad_log_paths['rest']
    out, report = tmp_path / 'out.yaml', tmp_path / 'report.png'
    code, stdout, err = run(capsys, 'identify', '--input', source, *argv,
                            '--output', out, '--report', report)
    assert_bad_input(code, stdout, err, *words)
    assert not out.exists() and not report.exists()


def test_identify_holds_what_the_log_does_not_excite_and_says_so(
        capsys, tmp_path, bad_log_paths):
    """One slider moving: identified, the others' friction held, noted."""
    from orthoglide_ros.formats import params_file
    out = tmp_path / 'one.yaml'
    code, stdout, _ = run(capsys, 'identify', '--input',
                          bad_log_paths['one_actuator'], '--output', out)
    assert code == 0
    (note,) = [line for line in stdout.splitlines()
               if line.startswith('note: not excited by the log')]
    assert 'viscous_b (' in note and 'coulomb_c (' in note
    assert 'held at the nominal value' in note
    assert f'# {note}' in out.read_text()
    assert params_file.load_robot(out).friction_viscous[1:] == (0.0, 0.0)


def test_identify_needs_input_and_output(capsys, tmp_path):

    source, _ = identification_log(tmp_path, duration=2.0)
    code, _, err = run(capsys, 'identify', '--input', source)
    assert code == 2 and '--output' in err
    code, _, err = run(capsys, 'identify', '--output', tmp_path / 'x.yaml')
    assert code == 2 and '--input' in err


def test_record_help_needs_no_ros(capsys):
    code, out, _ = run(capsys, 'record', '--help')
    assert code == 0 and 'rosbag2' in out and '--storage' in out
    assert '/joint_states' in out


def test_record_needs_output_and_duration(capsys):
    code, _, err = run(capsys, 'record', '--output', 'bag')
    assert code == 2 and '--duration' in err


def rough_log(tmp_path, name, seed, duration, lag=0.0):
    """Write a noise-free log of a robot with every friction term."""
    from orthoglide_ros.tools.identification import Log
    from synthetic_logs import write_csv
    robot = Robot(m5=18.75, friction_viscous=(30.0, 40.0, 50.0),
                  friction_coulomb=(5.0, 3.0, 4.0),
                  friction_coulomb_negative=(8.0, 1.5, 6.0),
                  friction_stribeck=(6.0, 4.0, 5.0),
                  friction_stribeck_velocity=0.02)
    motion = trajectory.excitation(seed, 6.0)
    times = np.arange(0.0, duration, 1e-3)
    lambdas = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times)).lambda_
    forces = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times - lag)).force
    return write_csv(tmp_path / name, Log(times, lambdas, forces, name)), \
        robot


def values_of(out, label):
    """Return the three numbers ending the line that starts with ``label``."""
    (line,) = [x for x in out.splitlines() if x.startswith(label)]
    return np.array([float(v) for v in line.split()[-3:]])


def test_validate_reports_error_share_and_lag(capsys, tmp_path):
    """The robot of the log predicts it; the paper's robot does not."""
    from orthoglide_ros.formats import params_file
    log, robot = rough_log(tmp_path, 'rough.csv', 2, 8.0, lag=0.002)
    params = tmp_path / 'rough.yaml'
    params.write_text(params_file.robot_file_text(robot))
    report = tmp_path / 'validation.png'
    code, out, err = run(capsys, 'validate', '--params', params, '--input',
                         log, '--report', report)
    assert (code, err) == (0, '')
    assert values_of(out, 'force error RMS (N)').max() < 0.01
    assert (values_of(out, 'share of the force explained (%)')
            > 99.999).all()
    assert 'force lag 2 ms (estimated' in out
    assert report.read_bytes().startswith(PNG_MAGIC)
    code, out, _ = run(capsys, 'validate', '--input', log, '--force-lag',
                       0.002)
    assert code == 0 and 'force lag 2 ms (given)' in out
    assert values_of(out, 'force error RMS (N)').min() > 1.0


def test_identify_chooses_the_friction_law_or_takes_it(capsys, tmp_path):
    from orthoglide_ros.formats import params_file
    log, robot = rough_log(tmp_path, 'rough.csv', 0, 20.0)
    out_file = tmp_path / 'found.yaml'
    code, out, _ = run(capsys, 'identify', '--input', log, '--output',
                       out_file)
    assert code == 0
    assert 'friction law chosen: coulomb+direction+stribeck' in out
    found = params_file.load_robot(out_file)
    assert np.allclose(found.friction_coulomb_negative,
                       robot.friction_coulomb_negative, rtol=0.05)
    assert np.allclose(found.friction_stribeck, robot.friction_stribeck,
                       rtol=0.25)
    # A law asked for is the law used, though it explains less.
    code, out, _ = run(capsys, 'identify', '--input', log, '--output',
                       out_file, '--friction', 'coulomb+direction',
                       '--force-lag', 0.0)

    assert code == 0
    assert 'friction law chosen: coulomb+direction: as asked' in out
    assert 'force lag 0 ms (given)' in out
    forced = params_file.load_robot(out_file)
    assert forced.friction_stribeck == (0.0, 0.0, 0.0)
    assert forced.friction_coulomb_negative != forced.friction_coulomb


@pytest.mark.slow     # 2.2-5.9 s of CPU, one process, 2026-12-06
def test_identify_validates_and_draws_in_one_step(capsys, tmp_path):
    log, _ = rough_log(tmp_path, 'rough.csv', 0, 20.0)
    other, _ = rough_log(tmp_path, 'other.csv', 3, 8.0)
    picture = tmp_path / 'validation.png'
    code, out, err = run(capsys, 'identify', '--input', log, '--output',
                         tmp_path / 'out.yaml', '--validate', other,
                         '--validate-report', picture)
    assert (code, err) == (0, '')
    assert (values_of(out, 'identified robot: force error RMS (N)') * 10.0
            < values_of(out, 'nominal robot: force error RMS (N)')).all()
    assert picture.read_bytes().startswith(PNG_MAGIC)


@pytest.mark.parametrize('argv', [
    ['--validate-report', 'v.png'], ['--friction', 'stiction'],
    ['--stribeck-velocity', '0'], ['--force-lag', 'nan']])
def test_identify_refuses_bad_options(capsys, tmp_path, argv):
    log, _ = rough_log(tmp_path, 'rough.csv', 0, 4.0)
    code, _, err = run(capsys, 'identify', '--input', log, '--output',
                       tmp_path / 'out.yaml', *argv)
    assert code == 2 and err.strip()
    assert not (tmp_path / 'out.yaml').exists()


def test_validate_refuses_a_bad_log_in_one_line(capsys, tmp_path):
    bad = tmp_path / 'bad.csv'
    bad.write_text('t,lambda_a,lambda_b,lambda_c,force_a,force_b,force_c\n'
                   '0,0,0,0,1,1,nan\n')
    code, out, err = run(capsys, 'validate', '--input', bad, '--report',
                         tmp_path / 'v.png')
    assert code == 2 and out == ''
    assert len(err.strip().splitlines()) == 1 and 'force_c' in err
    assert not (tmp_path / 'v.png').exists()


def test_excitation_optimize_lowers_the_condition_number(capsys, tmp_path):
    """Checked on the written file, within the bounds and the force limit."""
    from orthoglide_ros.tools import identification
    path = tmp_path / 'optimized.csv'
    code, out, _ = run(capsys, 'excitation', '--duration', 6, '--output',
                       path, '--optimize', '--evaluations', 80,
                       '--max-velocity', 0.3, '--max-force', 400, '--rate',
                       100)
    assert code == 0
    _, rows = read_csv(path.read_text())
    table = np.array([[float(row[c]) for c in (
        'x', 'y', 'z', 'vx', 'vy', 'vz', 'ax', 'ay', 'az')] for row in rows])
    p, v, a = table[:, :3], table[:, 3:6], table[:, 6:]
    written = identification.condition_number(Robot(), p, v, a)
    start = trajectory.excitation(0, 6.0, max_velocity=0.3)
    seed = identification.condition_number(Robot(), *trajectory.
                                           excitation_batch(start, np.arange(
                                               0.0, 6.0, 0.01)))
    print(f'condition number: seed {seed:.4g}, optimized {written:.4g}')
    assert written < seed
    assert f'{seed:.4g} (seed 0) -> {written:.4g} (optimized)' in out
    # The budget is kept: 80 evaluations at most, not 80 and a gradient.
    spent = int(re.search(r'\((\d+) evaluations\)', out).group(1))
    assert 0 < spent <= 80, out
    assert np.abs(v).max() <= 0.3 and np.abs(p).max() <= 0.15
    assert np.abs(a).max() <= 4.0
    assert np.abs(mechanics.solve_batch(Robot(), p, v, a).force).max() \
        <= 400.0


def test_excitation_refuses_a_force_limit_no_seed_keeps(capsys, tmp_path):
    code, _, err = run(capsys, 'excitation', '--duration', 6, '--output',
                       tmp_path / 'e.csv', '--max-force', 10)
    assert code == 2 and '--max-force 10 N' in err
    assert not (tmp_path / 'e.csv').exists()


def test_identify_validates_with_the_lag_it_found(capsys, tmp_path):
    """The lag is the drive's: the validation takes identify's."""
    log, _ = rough_log(tmp_path, 'rough.csv', 0, 20.0, lag=0.0015)
    other, _ = rough_log(tmp_path, 'other.csv', 3, 8.0, lag=0.0015)
    code, out, _ = run(capsys, 'identify', '--input', log, '--output',
                       tmp_path / 'out.yaml', '--validate', other)
    assert code == 0
    (found,) = [line for line in out.splitlines()
                if line.startswith('force lag ') and 'estimated' in line]
    lag = float(found.split()[2])
    assert lag == pytest.approx(1.5, abs=0.2)
    assert f'force lag {lag:.4g} ms (given)' in out
