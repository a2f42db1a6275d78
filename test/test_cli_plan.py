"""
``orthoglide plan``: a program in, the motion ``batch`` reads out.

The CSV has ``batch``'s input columns and solves with ``batch`` into the
forces the plan kept; ``--format joint_trajectory`` writes what ``batch``
writes; limits come from --limits, else the --params file's planner
section, else the paper robot's (with a note); every refusal is one line,
exit 2, and leaves the output file as it was.
"""

import math
from pathlib import Path

from cli_runs import assert_bad_input, read_csv, run
import numpy as np
import pytest
import yaml

from orthoglide_testing.chord_programs import bulge_points

ROOT = Path(__file__).resolve().parents[1]
PROGRAM = 'G21 G90 F12000\nG1 X40\nG3 X60 Y20 I0 J20\nG1 Y40\nM2\n'
LIMITS = ('joint_limits:\n'
          '  slider_a: {has_effort_limits: true, max_effort: 200.0}\n'
          '  slider_b: {has_effort_limits: true, max_effort: 200.0}\n'
          '  slider_c: {has_effort_limits: true, max_effort: 400.0}\n')


@pytest.fixture
def files(tmp_path):
    program = tmp_path / 'part.nc'
    program.write_text(PROGRAM)
    limits = tmp_path / 'limits.yaml'
    limits.write_text(LIMITS)
    return program, limits, tmp_path / 'motion.csv'


def test_plan_writes_what_batch_reads_within_the_limits(capsys, files):
    program, limits, output = files
    code, out, err = run(capsys, 'plan', '--input', program, '--output',
                         output, '--limits', limits)
    assert code == 0, err
    assert out.startswith('planned ') and err == ''
    header, rows = read_csv(output.read_text())
    assert header == 't,x,y,z,vx,vy,vz,ax,ay,az'
    t = np.array([float(r['t']) for r in rows])
    assert t[0] == 0.0 and np.allclose(np.diff(t), 1e-3)
    last = rows[-1]
    assert [float(last[k]) for k in 'xyz'] == pytest.approx([0.06, 0.04,
                                                             0.0])
    assert all(float(last[k]) == 0.0 for k in ('vx', 'vy', 'vz'))
    code, solved, err = run(capsys, 'batch', '--input', output)
    assert code == 0, err
    _, rows = read_csv(solved)
    force = np.array([[float(r[f'force_{leg}']) for leg in 'abc']
                      for r in rows])
    assert (np.abs(force) <= np.array([200.0, 200.0, 400.0]) * 1.001).all()
    speed = np.array([[float(r[k]) for k in ('vx', 'vy', 'vz')]
                      for r in read_csv(output.read_text())[1]])
    assert np.linalg.norm(speed, axis=1).max() <= 0.2 * 1.001


def test_joint_trajectory_format_is_batchs(capsys, files):
    program, limits, output = files
    target = output.with_suffix('.yaml')
    assert run(capsys, 'plan', '--input', program, '--output', target,
               '--limits', limits, '--format', 'joint_trajectory')[0] == 0
    message = yaml.safe_load(target.read_text())
    assert message['joint_names'] == ['slider_a', 'slider_b', 'slider_c']
    points = message['points']
    assert points[0]['time_from_start'] == {'sec': 0, 'nanosec': 0}
    assert all(len(p['effort']) == 3 for p in points)
    assert points[-1]['velocities'] == [0.0, 0.0, 0.0]


def test_limits_from_the_params_planner_section_else_the_papers(
        capsys, files, tmp_path):
    program, _, output = files
    code, _, err = run(capsys, 'plan', '--input', program, '--output',
                       output)
    assert code == 0 and 'the paper robot\'s limits' in err
    default = output.read_text()
    code, _, err = run(capsys, 'plan', '--input', program, '--output',
                       output, '--params', ROOT / 'config' / 'orthoglide.yaml')
    assert code == 0 and err == ''
    assert output.read_text() == default
    slow = tmp_path / 'slow.yaml'
    slow.write_text((ROOT / 'config' / 'orthoglide.yaml').read_text()
                    .replace('max_velocity: 1.0', 'max_velocity: 0.05'))
    assert run(capsys, 'plan', '--input', program, '--output', output,
               '--params', slow)[0] == 0
    assert len(output.read_text()) > len(default)


def test_waypoints_with_feeds_and_standard_streams(capsys, files,
                                                   monkeypatch, tmp_path):
    import io
    _, limits, _ = files
    waypoints = 'x,y,z,feed\n0.05,0,0,0.1\n0.05,0.05,0,0.05\n'
    monkeypatch.setattr('sys.stdin', io.TextIOWrapper(io.BytesIO(
        waypoints.encode())))
    code, out, err = run(capsys, 'plan', '--input', '-', '--output', '-',
                         '--limits', limits, '--tolerance', '0.0001')
    assert code == 0, err
    _, rows = read_csv(out)
    v = np.array([[float(r[k]) for k in ('vx', 'vy', 'vz')] for r in rows])
    assert np.linalg.norm(v, axis=1).max() <= 0.1 * 1.001


@pytest.mark.parametrize('program, words', (
    ('G21 F600\nG1 X10\nG41 D1\n',
     ['part.nc: line 3: G41 (cutter compensation) is not supported']),
    ('G21 F600\nG1 X10\nG1 X900\n', ['part.nc: line 3: the path at [',
                                     'm is too near a singularity']),
    ('G21 F600\nG1 X1..2\n', ['line 2: malformed number X1..2']),
    ('G21 F600\nG2 X30 R10\n', ['line 2: the arc radius 10 mm does not '
                                'fit']),
    ('(nothing)\nG21 F600\n', ['zero-length program']),
    ('x,y,z\n0,0,0\n', ['zero-length program']),
    ('G21 G64 F600\nG1 X0.000001\n', ['zero-length program', '1e-09 m']),
    ('G21 G61 F600\nG1 X0.000001\n', ['zero-length program', '1e-09 m']),
    ('x,y,z\n0,0,0\n0.000000001,0,0\n', ['zero-length program']),
    ('x,y,z\n0.01,nan,0\n', ['line 2', "'y'", 'not a finite number']),
))
def test_refusals_are_one_line_and_leave_the_output(capsys, files, program,
                                                    words):
    path, limits, output = files
    path.write_text(program)
    output.write_text('before')
    assert_bad_input(*run(capsys, 'plan', '--input', path, '--output',
                          output, '--limits', limits), *words)
    assert output.read_text() == 'before'


def test_statics_beyond_max_effort_is_refused(capsys, files):
    path, limits, output = files
    limits.write_text(LIMITS.replace('400.0', '250.0'))
    assert_bad_input(*run(capsys, 'plan', '--input', path, '--output',
                          output, '--limits', limits),
                     'part.nc: the start of the path at [0, 0, 0] m',
                     'slider_c needs 256.5', 'N at rest',
                     'max_effort 250 N')
    assert not output.exists()


@pytest.mark.parametrize('argv, words', (
    (['--rate', '0'], ['--rate', 'in [1, 100000] Hz']),
    (['--tolerance', '-1'], ['--tolerance']),
    (['--tolerance=-1e-5'], ['--tolerance', 'in [0, 0.01] m']),
    (['--max-speed', 'nan'], ['--max-speed']),
    (['--start', '0', '0'], ['--start']),
))
def test_bad_options(capsys, files, argv, words):
    path, limits, output = files
    code, out, err = run(capsys, 'plan', '--input', path, '--output', output,
                         '--limits', limits, *argv)
    assert code == 2 and out == ''
    for word in words:
        assert word in err


def test_a_tolerance_below_a_blend_of_1_nm_stops_at_corners_as_0(capsys,
                                                                 files):
    program, limits, output = files
    program.write_text('G64\nG1 F600 X10\nG1 Y10\nG1 X20 Y12\nM2\n')
    motions = []
    for tolerance in ('1e-300', '0', '1e-5'):
        assert run(capsys, 'plan', '--input', program, '--output', output,
                   '--tolerance', tolerance)[0] == 0
        motions.append(output.read_text())
    assert motions[0] == motions[1] != motions[2]


def test_limits_that_bound_nothing_are_refused(capsys, files, tmp_path):
    path, limits, output = files
    limits.write_text('joint_limits:\n  slider_a: {has_effort_limits: '
                      'false, max_effort: 100.0}\n')
    path.write_text('G0 X10\n')
    assert_bad_input(*run(capsys, 'plan', '--input', path, '--output',
                          output, '--limits', limits),
                     'nothing bounds the motion')
    limits.write_text('joint_limits:\n  slider_a: {max_efort: 100.0}\n')
    assert_bad_input(*run(capsys, 'plan', '--input', path, '--output',
                          output, '--limits', limits),
                     'joint_limits.slider_a.max_efort: not a joint limit')


@pytest.mark.parametrize('program, words', (
    # 4.8 hours at 1 kHz: more samples than the command's memory holds.
    ('G21 G1 F0.035 X10\n', ['the motion lasts 17160 s: 17,160,001 samples '
                             'at 1000 Hz, more than the 2,993,320 this '
                             'planner may hold']),
    ('G21 F6000\nG0 X10\nG2 X10 Y0 Z-1 I-10 J0 P100000\n',
     ['needs 18,000,006 gridpoints: more than the 900 MB left for the '
      'plan']),
    ('G1 F600 X' + '9' * 159 + '\n', ['line 1: X999', 'beyond 1,000,000,000']),
    ('G21 F600\nG0 X10\nG2 X20 I1000000 J0\n',
     ['line 3: the arc\'s end is 999990 mm from its centre']),
    ('x,y,z\n1e300,0,0\n', ['line 2: the point [1e+300, 0.0, 0.0] m is '
                            'beyond 1,000,000,000 m']),
))
def test_hostile_programs_are_refused_in_one_line(capsys, files, program,
                                                  words):
    path, limits, output = files
    path.write_text(program)
    assert_bad_input(*run(capsys, 'plan', '--input', path, '--output',
                          output, '--limits', limits), *words)
    assert not output.exists()


def test_a_start_out_of_the_workspace_is_named_as_the_start(capsys, files):
    path, limits, output = files
    assert_bad_input(*run(capsys, 'plan', '--input', path, '--output',
                          output, '--limits', limits, '--start', '0.9', '0',
                          '0'),
                     'part.nc: the start of the path at [0.9, 0, 0] m is '
                     'out of reach of leg B')


def test_a_limits_file_with_a_key_twice_is_refused(capsys, files):
    path, limits, output = files
    limits.write_text(LIMITS + '  slider_a: {max_effort: 300.0}\n')
    assert_bad_input(*run(capsys, 'plan', '--input', path, '--output',
                          output, '--limits', limits),
                     "the key 'slider_a' appears twice")


def cam_program(kind):
    """
    Return a program CAM might write badly, and its last point (m).

    ``reverse``: chords out along an arc and back; ``zero``: every chord
    followed by one of 0.1 nm; ``micro``: 30,000 chords of 1 um;
    ``many``: 100,000 chords of a 3D curve; ``bulge``: a curve beyond the
    workspace through points within it.
    """
    if kind == 'bulge':
        points = bulge_points() * 1e3
    elif kind == 'many':
        t = np.linspace(0.0, 10 * math.pi, 100_001)
        points = np.stack((40 * np.cos(t), 40 * np.sin(t),
                           10 * np.sin(3 * t)), 1)
    else:
        count, sweep = (30_000, 1.5) if kind == 'micro' else (30, math.pi)
        a = np.linspace(0.0, sweep, count + 1)
        points = np.stack((20 * np.cos(a), 20 * np.sin(a), 0 * a), 1)
        if kind == 'reverse':
            points = np.vstack((points, points[::-1][1:]))
        if kind == 'zero':
            points = np.repeat(points, 2, axis=0)
            points[1::2, 0] += 1e-7
    text = 'G21 G90 G64 F6000\n' + ''.join(
        'G1 X{:.7f} Y{:.7f} Z{:.7f}\n'.format(*p) for p in points)
    return text + 'M2\n', points[-1] * 1e-3


@pytest.mark.parametrize('kind', ('reverse', 'zero', 'micro', pytest.param(
    'many', marks=pytest.mark.slow), 'bulge'))
def test_chord_programs_plan_or_are_refused_in_one_line(capsys, files,
                                                        kind):
    """
    Chords at their worst: a plan, or one line naming the program's line.

    A reversal stops where it turns; chords of 0.1 nm and of 1 um are
    merged into points within the tolerance; 10^5 chords plan (about 12 s
    of CPU, 2026-12-06); the curve that leaves the workspace between two
    points is refused naming the second's line, nothing written.
    """
    path, limits, output = files
    text, last = cam_program(kind)
    path.write_text(text)
    result = run(capsys, 'plan', '--input', path, '--output', output,
                 '--limits', limits)
    if kind == 'bulge':
        assert_bad_input(*result, 'part.nc: line 12: the path at [',
                         'too near a singularity')
        assert not output.exists()
        return
    code, out, err = result
    assert code == 0 and err == '', err
    _, rows = read_csv(output.read_text())
    end = [float(rows[-1][k]) for k in 'xyz']
    assert end == pytest.approx(last.tolist(), abs=1e-10)   # as written
    if kind == 'reverse':       # at rest where it turns about, between two
        speed = np.linalg.norm([[float(r[k]) for k in ('vx', 'vy', 'vz')]
                                for r in rows], axis=1)
        turn = np.linalg.norm(np.array([[float(r[k]) for k in 'xy']
                                        for r in rows]) - (-0.02, 0.0),
                              axis=1).argmin()
        assert speed[turn - 1:turn + 2].min() <= 0.05 * speed.max()
