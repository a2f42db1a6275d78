"""
The ``orthoglide`` tool run in the test's process, and its inputs.

:func:`run` calls ``cli.main`` and returns the exit code and the output,
:func:`read_csv` parses what it wrote (:data:`HEADER`: batch's columns);
:func:`assert_bad_input` checks a refusal's one line; :func:`write_trajectory`
writes a trajectory CSV; :func:`identification_log` an identification log.
"""

import csv
import io

from orthoglide_ros.tools import cli
from synthetic_logs import synthetic_log, TRUE, write_csv

HEADER = ('t,x,y,z,lambda_a,lambda_b,lambda_c,lambdadot_a,lambdadot_b,'
          'lambdadot_c,lambdaddot_a,lambdaddot_b,lambdaddot_c,force_a,'
          'force_b,force_c,power_a,power_b,power_c')
PNG_MAGIC = b'\x89PNG\r\n\x1a\n'


def read_csv(text):
    """Parse CSV text into (header, rows of dicts)."""
    reader = csv.DictReader(io.StringIO(text))
    return ','.join(reader.fieldnames), list(reader)


def run(capsys, *argv):
    """Run the tool in-process; return (exit code, stdout, stderr)."""
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def write_trajectory(path, columns, rows):
    """Write a trajectory CSV with the given header and rows of numbers."""
    lines = [','.join(columns)] + [','.join(map(repr, r)) for r in rows]
    path.write_text('\n'.join(lines) + '\n')
    return path


def assert_bad_input(code, out, err, *words):
    """Exit code 2, one error line naming ``words``, nothing on stdout."""
    assert code == 2
    assert out == ''
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith('orthoglide: error: ')
    for word in words:
        assert word in lines[0]


def identification_log(tmp_path, name='log.csv', seed=0, duration=20.0):
    """Write a synthetic log of a robot unlike the paper's (test_identification)."""
    log = synthetic_log(TRUE, seed, 5.0, 11, duration=duration)
    return write_csv(tmp_path / name, log), log
