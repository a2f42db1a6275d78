"""
Hostile files and paths against the ``orthoglide`` tool.

Every case is a file, a path or a size a user (or an attacker) can hand
the tool;
the rule for each: exit 2 with one line ``orthoglide: error: ...``, no
traceback, nothing written, memory bounded; and an output path is never
replaced by something else (a device or a FIFO is written through, a
symbolic link followed to its target, a regular file replaced
atomically).
"""

import math
import os
from pathlib import Path
import stat
import subprocess
import sys
import threading

import numpy as np
import pytest

from orthoglide_ros.formats import csvfile
from orthoglide_ros.model.robot import Robot
from cli_runs import (assert_bad_input, PNG_MAGIC, run, run_measured,
                      write_trajectory)

TRAJECTORY = [(0.0, 0.0, 0.0, 0.0), (0.1, 0.01, 0.0, 0.0)]


@pytest.fixture
def trajectory_csv(tmp_path):
    return write_trajectory(tmp_path / 'in.csv', ('t', 'x', 'y', 'z'),
                            TRAJECTORY)


def device(path, minor):
    """Make a character device of the memory driver (3 null, 7 full)."""
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, minor))
    except (PermissionError, OSError) as error:
        pytest.skip(f'cannot make a device node here: {error}')
    return path


# -- outputs ------------------------------------------------------------------

def test_a_full_device_is_written_through_and_stays_a_device(
        capsys, tmp_path, trajectory_csv):
    """A device is written through, never replaced (root may replace it)."""
    full = device(tmp_path / 'full', 7)
    code, out, err = run(capsys, 'batch', '--input', trajectory_csv,
                         '--output', full)
    assert_bad_input(code, out, err, 'No space left on device')
    assert stat.S_ISCHR(os.stat(full).st_mode)
    null = device(tmp_path / 'null', 3)
    assert run(capsys, 'batch', '--input', trajectory_csv,
               '--output', null)[0] == 0
    assert stat.S_ISCHR(os.stat(null).st_mode)


def test_a_fifo_is_written_through(capsys, tmp_path, trajectory_csv):
    fifo = tmp_path / 'fifo'
    os.mkfifo(fifo)
    received = []
    reader = threading.Thread(target=lambda: received.append(
        fifo.read_bytes()), daemon=True)
    reader.start()
    code = run(capsys, 'batch', '--input', trajectory_csv, '--output',
               fifo)[0]
    reader.join(10.0)
    if reader.is_alive():   # nothing opened the FIFO: release the reader
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
    assert code == 0 and stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert received and received[0].startswith(b't,x,y,z,lambda_a')


def test_a_symbolic_link_is_followed_to_its_target(capsys, tmp_path,
                                                   trajectory_csv):
    target, link = tmp_path / 'target.csv', tmp_path / 'link.csv'
    target.write_text('old\n')
    link.symlink_to(target)
    assert run(capsys, 'batch', '--input', trajectory_csv, '--output',
               link)[0] == 0
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert target.read_text().startswith('t,x,y,z,lambda_a')
    dangling = tmp_path / 'dangling.csv'
    dangling.symlink_to(tmp_path / 'new.csv')
    assert run(capsys, 'batch', '--input', trajectory_csv, '--output',
               dangling)[0] == 0
    assert dangling.is_symlink() and (tmp_path / 'new.csv').is_file()


def test_every_output_is_checked_before_any_is_written(capsys, tmp_path):
    """`identify --report DIR` fails before the parameters file is written."""
    from cli_runs import identification_log
    source, _ = identification_log(tmp_path, duration=2.0)
    out, directory = tmp_path / 'out.yaml', tmp_path / 'report.png'
    directory.mkdir()
    code, stdout, err = run(capsys, 'identify', '--input', source,
                            '--output', out, '--report', directory)
    assert_bad_input(code, stdout, err, '--report', 'is a directory')
    assert not out.exists()
    code, stdout, err = run(capsys, 'identify', '--input', source,
                            '--output', tmp_path / 'nowhere' / 'out.yaml')
    assert_bad_input(code, stdout, err, '--output', 'no such directory')


# -- an output that is an input or another output ------------------------------

# '@name' is a file of the case's directory: log.csv and other.csv (logs),
# traj.csv and traj.gif (trajectories), link.csv (a symbolic link to
# traj.csv) and hard.csv (a hard link of it), params.yaml and params.png
# (parameters files), bag (a bag directory); others do not exist.
SAME_FILE = (     # (the command line, the option refused, the one it names again)
    ('identify --input @log.csv --output @log.csv', '--output', '--input'),
    ('identify --input @log.csv --validate @other.csv --output @other.csv',
     '--output', '--validate'),
    ('identify --input @log.csv --params @params.yaml --output @params.yaml',
     '--output', '--params'),
    ('identify --input @log.csv --output @new.yaml --report @new.yaml', '--report', '--output'),
    ('identify --input @log.csv --output @new.yaml --report '
     '@new.png --validate @other.csv --validate-report @sub/../new.png',
     '--validate-report', '--report'),
    ('identify --input @bag --output @bag/metadata.yaml',
     '--output', 'inside the directory --input'),
    ('validate --input @log.csv --report @log.csv', '--report', '--input'),
    ('validate --input @log.csv --params @params.png --report @params.png',
     '--report', '--params'),
    ('mjcf --params @params.yaml --output @params.yaml', '--output', '--params'),
    ('urdf --params @params.yaml --output @params.yaml', '--output', '--params'),
    ('batch --input @traj.csv --output @traj.csv', '--output', '--input'),
    ('batch --input @link.csv --output @traj.csv', '--output', '--input'),
    ('batch --input @traj.csv --output @hard.csv', '--output', '--input'),
    ('animate --input @traj.gif --output @traj.gif', '--output', '--input'),
    ('plan --input @traj.csv --output @traj.csv', '--output', '--input'),
    ('plan --input @traj.csv --limits @params.yaml --output @params.yaml', '--output', '--limits'),
    ('paper --csv @new.csv --plot @./new.csv', '--plot', '--csv'),
    ('excitation --duration 1 --params @params.yaml --output @params.yaml',
     '--output', '--params'),
    ('draw --position 0 0 0 --params @params.png --output @params.png', '--output', '--params'),
    ('render --position 0 0 0 --params @params.png --output @params.png', '--output', '--params'),
)


@pytest.fixture(scope='module')
def case_files(tmp_path_factory):
    """Every file a SAME_FILE case names, valid for its command."""
    from cli_runs import identification_log
    from synthetic_logs import write_bag
    root = tmp_path_factory.mktemp('same_file')
    source, log = identification_log(root, duration=2.0)
    params = (Path(__file__).parents[1] / 'config'
              / 'orthoglide.yaml').read_bytes()
    trajectory = write_trajectory(root / 'traj.csv', ('t', 'x', 'y', 'z'),
                                  TRAJECTORY).read_bytes()
    write_bag(root / 'bag', log, 'mcap')
    files = {'log.csv': source.read_bytes(), 'params.yaml': params,
             'params.png': params, 'traj.csv': trajectory,
             'traj.gif': trajectory}
    files['other.csv'] = files['log.csv']
    bag = {path.name: path.read_bytes() for path in (root / 'bag').iterdir()}
    return files, bag


def snapshot(directory):
    """Every file under ``directory``: {relative path: bytes or link}."""
    return {str(path.relative_to(directory)): (
        os.readlink(path) if path.is_symlink() else path.read_bytes())
        for path in sorted(directory.rglob('*')) if not path.is_dir()}


@pytest.mark.parametrize('line,option,other', SAME_FILE)
def test_an_output_that_is_an_input_or_another_output_is_refused(
        capsys, tmp_path, case_files, line, option, other):
    """`identify --input rec.csv --output rec.csv` leaves the log as it was."""
    files, bag = case_files
    for file, data in files.items():
        (tmp_path / file).write_bytes(data)
    (tmp_path / 'bag').mkdir()
    for file, data in bag.items():
        (tmp_path / 'bag' / file).write_bytes(data)
    (tmp_path / 'link.csv').symlink_to(tmp_path / 'traj.csv')
    os.link(tmp_path / 'traj.csv', tmp_path / 'hard.csv')
    before = snapshot(tmp_path)
    code, out, err = run(capsys, *(str(tmp_path / a[1:]) if a[0] == '@'
                                   else a for a in line.split()))
    assert_bad_input(code, out, err, option, other, 'nothing was written')
    assert snapshot(tmp_path) == before


def test_standard_input_and_output_count_as_files(tmp_path):
    """`batch --input - --output X < X`; `paper --csv - --plot -`."""
    path = write_trajectory(tmp_path / 'traj.csv', ('t', 'x', 'y', 'z'),
                            TRAJECTORY)
    before = path.read_bytes()
    for argv, stdin, words in (
            (['batch', '--input', '-', '--output', str(path)], path,
             ('--output', 'the same file as --input -')),
            (['paper', '--csv', '-', '--plot', '-'], os.devnull,
             ('--plot -: the same file as --csv -',))):
        with open(stdin, 'rb') as stream:
            done = subprocess.run(
                [sys.executable, '-m', 'orthoglide_ros.tools.cli', *argv],
                stdin=stream, capture_output=True, text=True, timeout=60)
        assert_bad_input(done.returncode, done.stdout, done.stderr, *words)
    assert snapshot(tmp_path) == {'traj.csv': before}


def test_a_character_device_may_be_named_by_two_outputs(capsys, tmp_path):
    """/dev/null holds nothing to lose: `--csv /dev/null --plot /dev/null`."""
    null = device(tmp_path / 'null', 3)
    assert run(capsys, 'paper', '--samples', 3, '--csv', null,
               '--plot', null)[0] == 0


def test_a_picture_goes_to_standard_output_as_bytes():
    """`paper --plot -` was a UnicodeDecodeError traceback."""
    done = subprocess.run(
        [sys.executable, '-m', 'orthoglide_ros.tools.cli', 'paper',
         '--samples', '3', '--plot', '-'], capture_output=True, timeout=60)
    assert done.returncode == 0 and done.stderr == b''
    assert done.stdout.startswith(PNG_MAGIC)


def test_every_file_option_is_declared_an_input_or_an_output():
    """A new subcommand's file options get check_distinct for free."""
    import argparse
    from orthoglide_ros.tools import cli
    from orthoglide_ros.tools.cli import common
    sub = next(action for action in cli._parser()._actions
               if isinstance(action, argparse._SubParsersAction))
    declared = set(common.INPUT_OPTIONS) | set(common.OUTPUT_OPTIONS)
    files = {(name, action.dest) for name, parser in sub.choices.items()
             for action in parser._actions
             if isinstance(action.metavar, str) and any(
                 word in action.metavar for word in ('FILE', 'LOG', 'BAG'))}
    assert {dest for _, dest in files} == declared
    assert not set(common.INPUT_OPTIONS) & set(common.OUTPUT_OPTIONS)


# -- parameters files -----------------------------------------------------------

BOMB = ''.join(
    f'{name}: &{name} [{", ".join([f"*{previous}"] * 9)}]\n'
    for previous, name in zip('abcdefgh', 'bcdefghi'))
PARAMS = {
    'alias_bomb': ('a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n'
                   + BOMB + 'feedforward: {ros__parameters: {robot: *i}}\n',
                   'aliases'),
    'recursive_alias': ('feedforward: &x\n  ros__parameters: *x\n',
                        'aliases'),
    'nested_brackets': ('feedforward: {ros__parameters: {robot: {m5: '
                        + '[' * 100_000 + ']' * 100_000 + '}}}\n',
                        'nested more than'),
    'long_integer': ('feedforward: {ros__parameters: {robot: {m5: '
                     + '9' * 5000 + '}}}\n', '4300 digits'),
    'not_utf8': (b'feedforward:\n  ros__parameters: {robot: {m5: 15.0}}'
                 b' # \xff\xfe\n', 'not UTF-8'),
    'huge': ('feedforward: {ros__parameters: {robot: {m5: 15.0}}}\n'
             + '#' * (2 * 1024 * 1024) + '\n', 'larger than'),
}


@pytest.mark.parametrize('name', sorted(PARAMS))
def test_a_hostile_parameters_file_is_refused_in_one_line(capsys, tmp_path,
                                                          name):
    text, words = PARAMS[name]
    path = tmp_path / 'params.yaml'
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    code, out, err = run(capsys, 'solve', '--position', 0, 0, 0,
                         '--params', path)
    assert_bad_input(code, out, err, str(path), words)


# -- CSV files --------------------------------------------------------------------

# Each after the header of the command's input: its last column spoiled.
CSV = {
    'long_line': ('0,' * 3 + '1' * 140_000 + '\n',
                  'line 2: longer than 131072 characters'),
    'long_field': ('0,' * 3 + '"' + ('1' * 70_000 + '\n') * 2 + '"\n',
                   'field larger than field limit'),
    'unterminated_quote': ('0,' * 3 + '"0\n' + '1,' * 3 + '0\n',
                           'is not a finite number'),
    'not_utf8': (b'0,0,0,\xff\n', 'not a UTF-8 text file'),
    'a_cell_short': ('0,' * 2 + '0\n', 'data row 1 (line 2): '),
    'a_cell_more': ('0,' * 4 + '0\n', 'cells where the header has '),
    'a_trailing_comma': ('0,' * 4 + '\n', 'cells where the header has '),
}
HEADERS = {'batch': 't,x,y,z', 'animate': 't,x,y,z'}


@pytest.mark.parametrize('command', ['batch', 'identify', 'validate',
                                     'animate'])
@pytest.mark.parametrize('name', sorted(CSV))
def test_a_hostile_csv_is_refused_in_one_line(capsys, tmp_path, name,
                                              command):
    text, words = CSV[name]
    path = tmp_path / 'in.csv'
    header = HEADERS.get(command, 't,lambda_a,lambda_b,lambda_c,force_a,'
                                  'force_b,force_c') + '\n'
    if command in ('identify', 'validate'):  # three more columns first
        text = (b'0,0,0,' if isinstance(text, bytes) else '0,0,0,') + text
    path.write_bytes(header.encode() + (
        text if isinstance(text, bytes) else text.encode()))
    output = {'batch': 'out.csv', 'identify': 'out.yaml',
              'validate': 'out.png', 'animate': 'out.gif'}[command]
    code, out, err = run(capsys, command, '--input', path,
                         '--report' if command == 'validate' else '--output',
                         tmp_path / output)
    assert_bad_input(code, out, err, words)
    assert not (tmp_path / output).exists()


@pytest.mark.parametrize('row', ['0.1,0.0', '0.1,0.0,0.0,0.0'])
def test_a_waypoint_row_of_another_cell_count_is_refused(capsys, tmp_path,
                                                         row):
    path = tmp_path / 'waypoints.csv'
    path.write_text(f'x,y,z\n0.0,0.0,0.0\n{row}\n0.1,0.1,0.0\n')
    code, out, err = run(capsys, 'plan', '--input', path, '--output',
                         tmp_path / 'plan.yaml')
    assert code == 2 and out == ''
    assert f'{path}: data row 2 (line 3): {row.count(",") + 1} cells where ' \
        'the header has 3' in err
    assert not (tmp_path / 'plan.yaml').exists()


def test_a_csv_beyond_the_row_limit_is_refused_without_reading_it_all(
        capsys, tmp_path, monkeypatch):
    """The rule of MAX_ROWS (2,000,000), shown on a limit of 100."""
    monkeypatch.setattr(csvfile, 'MAX_ROWS', 100)
    rows = [(0.001 * i, 0.0, 0.0, 0.0) for i in range(101)]
    path = write_trajectory(tmp_path / 'in.csv', ('t', 'x', 'y', 'z'), rows)
    code, out, err = run(capsys, 'batch', '--input', path)
    assert_bad_input(code, out, err, 'more than 100 data rows')
    path = write_trajectory(tmp_path / 'ok.csv', ('t', 'x', 'y', 'z'),
                            rows[:100])
    assert run(capsys, 'batch', '--input', path)[0] == 0


# Peak memory of a refusal: the interpreter, numpy and a line (about 40 MB
# measured; an endless line read whole grows by about 600 MB/s).
REFUSAL_RSS = 300 << 20
ENDLESS = {  # command, its options: '@' the endless input, '+' an output
    'validate': ['validate', '--input', '@'],
    'identify': ['identify', '--input', '@', '--output', '+out.yaml'],
    'batch': ['batch', '--input', '@', '--output', '+out.csv'],
    'animate': ['animate', '--input', '@', '--output', '+out.gif'],
}


@pytest.mark.parametrize('source', ['/dev/zero', 'stdin', 'one_line'])
@pytest.mark.parametrize('command', sorted(ENDLESS))
def test_an_endless_line_is_refused_as_it_arrives(tmp_path, command, source):
    """`validate --input /dev/zero` exits 2 in bounded memory and time."""
    stdin = None
    if source == 'one_line':        # 300 MB without a line end (sparse)
        path = tmp_path / 'one_line.csv'
        with open(path, 'wb') as stream:
            stream.write(b't,x,y,z,lambda_a,')
            stream.truncate(300_000_000)
    elif source == 'stdin':
        path, stdin = '-', '/dev/zero'
    else:
        path = source
    argv = [path if arg == '@' else tmp_path / arg[1:] if arg[0] == '+'
            else arg for arg in ENDLESS[command]]
    done = run_measured(*argv, stdin=stdin)
    assert not done.killed
    assert_bad_input(done.code, done.out, done.err,
                     'line 1: longer than 131072 characters')
    assert done.peak_rss < REFUSAL_RSS, done.peak_rss
    assert not list(tmp_path.glob('out.*'))


def test_a_line_is_bounded_at_its_limit_and_lines_are_counted(
        capsys, tmp_path, monkeypatch):
    """MAX_LINE (131072) and MAX_LINES (4,000,000), shown on 30 and 6."""
    monkeypatch.setattr(csvfile, 'MAX_LINE', 30)
    monkeypatch.setattr(csvfile, 'MAX_LINES', 6)
    header = 't,x,y,z'
    at_limit = '0.0,0.0,0.0,0.' + '0' * 16       # 30 characters
    path = tmp_path / 'in.csv'
    path.write_text(f'{header}\r\n{at_limit}\r\n\n\n\n{at_limit}\n')
    code, out, _ = run(capsys, 'batch', '--input', path)
    assert code == 0 and len(out.splitlines()) == 3
    path.write_text(f'{header}\n{at_limit}0\n')
    code, out, err = run(capsys, 'batch', '--input', path)
    assert_bad_input(code, out, err, 'line 2: longer than 30 characters')
    path.write_text(f'{header}\n{at_limit}\n' + '\n' * 5)
    code, out, err = run(capsys, 'batch', '--input', path)
    assert_bad_input(code, out, err, 'more than 6 lines')


def test_a_bag_beyond_the_row_limit_is_refused_as_a_csv_is(
        capsys, tmp_path, monkeypatch):
    """The same MAX_ROWS for a bag's messages, shown on a limit of 10."""
    from synthetic_logs import synthetic_log, TRUE, write_bag
    monkeypatch.setattr(csvfile, 'MAX_ROWS', 10)
    log = synthetic_log(TRUE, 0, 5.0, 1, duration=0.011)
    write_bag(tmp_path / 'bag', log, 'mcap')
    code, out, err = run(capsys, 'validate', '--input', tmp_path / 'bag')
    assert_bad_input(code, out, err, 'more than 10 messages on /joint_states')
    monkeypatch.setattr(csvfile, 'MAX_ROWS', len(log.times))
    code, out, err = run(capsys, 'validate', '--input', tmp_path / 'bag')
    assert 'messages' not in err


# -- excitation's size ------------------------------------------------------------

EXCITATION = {  # its arguments beyond --output: words of the refusal
    'duration_1e9': (['--duration', '1e9'], ['above 1000 s']),
    'rate_1e9': (['--duration', '2', '--rate', '1e9'],
                 ['2e+09 rows', 'above the 2000000 rows']),
    'at_the_row_limit_too_long': (['--duration', '2000', '--rate', '1000'],
                                  ['duration 2000 s: above 1000 s']),
    'rate_1e7': (['--duration', '1e-3', '--rate', '1e7'],
                 ['rate 1e+07 Hz: above 1e+06 Hz']),
    'short_optimized': (['--duration', '1e-3', '--optimize'],
                        ['1 row(s), fewer than 10']),
    'degenerate_optimized': (['--duration', '1e-3', '--rate', '1e6',
                              '--optimize', '--evaluations', '2'],
                             ['optimized from seed 0', 'unexcited',
                              'condition number inf']),
}


@pytest.mark.parametrize('name', sorted(EXCITATION))
def test_an_excitation_beyond_its_bounds_is_refused_before_it_is_made(
        tmp_path, name):
    """`--duration 1e9` is refused in one line before any array is made."""
    argv, words = EXCITATION[name]
    done = run_measured('excitation', *argv, '--output', tmp_path / 'e.csv')
    # One line: no numpy RuntimeWarning either.
    assert_bad_input(done.code, done.out, done.err, *words)
    assert done.peak_rss < REFUSAL_RSS, done.peak_rss
    assert not list(tmp_path.iterdir())


def test_the_excitation_rows_are_the_readers_limit(capsys, tmp_path,
                                                   monkeypatch):
    """One MAX_ROWS: what excitation may write, batch reads (limit 1000)."""
    monkeypatch.setattr(csvfile, 'MAX_ROWS', 1000)
    path = tmp_path / 'e.csv'
    code, out, err = run(capsys, 'excitation', '--duration', 2,
                         '--rate', 1000.0001, '--output', path)
    assert_bad_input(code, out, err, '2000 rows, above the 1000 rows')
    assert run(capsys, 'excitation', '--duration', 2, '--rate', 500,
               '--output', path)[0] == 0
    assert len(path.read_text().splitlines()) == 1 + 1000
    assert run(capsys, 'batch', '--input', path, '--output',
               tmp_path / 'solved.csv')[0] == 0


@pytest.mark.parametrize('period, rate', [
    (6.0, 1000.0), (0.14, 100.0), (0.3, 100.0), (1000.0, 2000.0),
    (2.5, 333.3), (1e-5, 1e6)])
def test_the_excitation_rows_are_numpys(period, rate):
    """check_size counts the rows numpy.arange(0, period, 1 / rate) makes."""
    from orthoglide_ros.tools import excitation_design
    assert excitation_design.check_size(period, rate) == len(
        np.arange(0.0, period, 1.0 / rate))


def test_an_unexcited_regressor_column_is_infinite_without_a_warning():
    """A motion at rest: every speed column zero, checked, not divided."""
    import warnings
    from orthoglide_ros.tools import identification
    rest = np.zeros((50, 3))
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        assert identification.condition_number(
            Robot(), rest, rest, rest) == math.inf


# -- record's topics ---------------------------------------------------------------

@pytest.mark.parametrize('topics, words', [
    (['bad topic!!'], ["'bad topic!!'", 'not a valid ROS topic name']),
    ([''], ["''", 'not a valid ROS topic name']),
    (['/x/'], ["'/x/'"]),
    (['/1x'], ["'/1x'"]),
    (['/joint_states', 'joint_states'], ['/joint_states given more than']),
])
def test_record_refuses_bad_and_repeated_topics_at_once(capsys, tmp_path,
                                                        topics, words):
    """Refused before anything starts: no wait, no bag, no ROS needed."""
    argv = [arg for topic in topics for arg in ('--topic', topic)]
    code, out, err = run(capsys, 'record', '--output', tmp_path / 'bag',
                         '--duration', 1, *argv)
    assert_bad_input(code, out, err, *words)
    assert not (tmp_path / 'bag').exists()


def test_a_csv_refusal_names_its_file_apart_from_where_and_why(tmp_path):
    """Callers put the file's name their own way: no message is parsed."""
    path = tmp_path / 'w.csv'
    path.write_text('x,y\n0,0\n')
    with pytest.raises(csvfile.CsvError) as error:
        csvfile.read_columns(path, [('position', ('x', 'y', 'z'), True)],
                             'waypoints')
    assert error.value.source == 'waypoints'
    assert error.value.detail.startswith("no 'z' column")
    assert str(error.value) == 'waypoints: ' + error.value.detail
