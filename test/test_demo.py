"""
End-to-end test of ``scripts/demo.py``: node, publisher, summary, plot.

Runs the demo as the README does (a subprocess, DDS on this host, the test
session's domain) on a short pass of eq. (6) and checks its exit code, the
summary's key lines, the PNG and the CSV.
"""

import csv
from pathlib import Path
import subprocess
import sys

import pytest

from orthoglide_ros.tools.cli import CSV_COLUMNS
from orthoglide_testing.verdicts import first_unspoiled

# DDS and node processes; a timing verdict (the stream's rate), so alone.
pytestmark = [pytest.mark.ros, pytest.mark.serial]

pytest.importorskip('rclpy')

ROOT = Path(__file__).resolve().parents[1]
PNG_MAGIC = b'\x89PNG\r\n\x1a\n'
TIMEOUT = 90.0


def run_demo(plot, table):
    """
    Run the demo at real-time priority; again if the machine spoiled it.

    A run the demo itself calls spoiled (rate, gaps, loss: another load on
    the machine) says nothing of the package: run again by the suite's one
    rule (:func:`verdicts.first_unspoiled`).
    """
    return first_unspoiled(
        lambda: subprocess.run(
            [sys.executable, str(ROOT / 'scripts' / 'demo.py'), '--duration',
             '0.5', '--realtime', '--plot', str(plot), '--csv', str(table)],
            stdin=subprocess.DEVNULL, capture_output=True, text=True,
            timeout=TIMEOUT),
        lambda result: ('spoiled' if 'the run was spoiled' in result.stderr
                        else None),
        lambda result, spoiled, attempt: print(result.stderr,
                                               file=sys.stderr))


def test_demo_runs_end_to_end(tmp_path):
    plot, table = tmp_path / 'demo.png', tmp_path / 'demo.csv'
    result = run_demo(plot, table)
    report = result.stdout + result.stderr
    assert result.returncode == 0, report
    assert 'verdict    OK' in result.stdout, report
    lines = result.stdout.splitlines()
    for start in ('Orthoglide feedforward demo: eq. (6) for 0.5 s at 500 Hz',
                  'setpoints  sent ', 'outputs    received ',
                  'latency    setpoint stamp -> reception here: p50 ',
                  'check      max |node - mechanics.solve| 0 over ',
                  'peak |lambda| (mm)', 'peak |force| (N)',
                  'peak |power| (W)', 'node       ', 'plot       '):
        assert any(line.startswith(start) for line in lines), (start, report)
    assert plot.read_bytes().startswith(PNG_MAGIC)
    assert any(line.startswith('animation  ') for line in lines), report
    assert (tmp_path / 'demo.gif').read_bytes().startswith(b'GIF89a')
    with open(table, newline='') as stream:
        reader = csv.reader(stream)
        assert tuple(next(reader)) == CSV_COLUMNS
        rows = [[float(cell) for cell in row] for row in reader]
    assert rows, report
    times = [row[0] for row in rows]
    assert times == sorted(times) and 0.0 <= times[0] and times[-1] <= 0.5
