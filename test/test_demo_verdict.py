"""
The demo's verdict: a run the machine spoiled is FAILED, named why.

``scripts/demo.py``'s rule, without DDS: fewer setpoints than the rate
promises, a gap of several periods, outputs lost.
"""

import argparse
import importlib.util
from pathlib import Path

import pytest

pytest.importorskip('rclpy')

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope='module')
def demo():
    spec = importlib.util.spec_from_file_location(
        'demo_script', ROOT / 'scripts' / 'demo.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


ARGS = argparse.Namespace(duration=2.0, rate=500.0)


def test_a_stream_that_kept_its_rate_is_not_spoiled(demo):
    assert demo._spoiled(ARGS, 1001, 2.3, 0) == []


def test_a_slow_gapped_lossy_stream_is_spoiled_and_says_why(demo):
    """662 of 1000 setpoints at 330 Hz, a 170 ms gap, 5 lost."""
    reasons = demo._spoiled(ARGS, 662, 170.0, 5)
    assert len(reasons) == 3, reasons
    assert reasons[0] == '662 of 1000 setpoints sent (331 of 500 Hz)'
    assert reasons[1].startswith('a gap of 170.0 ms')
    assert reasons[2] == '5 of 662 outputs lost'


def test_no_word_from_the_publisher_is_spoiled(demo):
    assert demo._spoiled(ARGS, None, None, None) == [
        'the setpoint publisher did not say what it sent']
