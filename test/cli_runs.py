"""
The ``orthoglide`` tool run in the test's process, and its inputs.

:func:`run` calls ``cli.main`` and returns the exit code and the output,
:func:`run_measured` runs the tool as a process and measures its peak
memory,
:func:`read_csv` parses what it wrote (:data:`HEADER`: batch's columns);
:func:`assert_bad_input` checks a refusal's one line; :func:`write_trajectory`
writes a trajectory CSV; :func:`identification_log` an identification log.
"""

from collections import namedtuple
import csv
import io
import os
import resource
import subprocess
import sys
import tempfile
import threading

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


Measured = namedtuple('Measured', 'code out err peak_rss killed')
# Address space of a measured run: a reader that regressed fails here
# rather than take the machine's memory.
ADDRESS_SPACE = 2 << 30


def run_measured(*argv, stdin=None, timeout=60.0):
    """
    Run the tool as a process; return its code, output and peak memory.

    ``peak_rss`` in bytes (the process's own ru_maxrss, from wait4);
    ``stdin`` a path (default /dev/null); the process is killed after
    ``timeout`` s (``killed``) and limited to ADDRESS_SPACE bytes.
    """
    def limit():
        resource.setrlimit(resource.RLIMIT_AS,
                           (ADDRESS_SPACE, ADDRESS_SPACE))
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err, \
            open(stdin or os.devnull, 'rb') as source:
        proc = subprocess.Popen(
            [sys.executable, '-m', 'orthoglide_ros.tools.cli',
             *map(str, argv)], stdin=source, stdout=out, stderr=err,
            preexec_fn=limit)
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            killed = not timer.is_alive()
            timer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return Measured(proc.returncode, out.read().decode(errors='replace'),
                        err.read().decode(errors='replace'),
                        usage.ru_maxrss * 1024, killed)


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
