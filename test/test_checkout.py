"""
The proving ground finds the checkout it was given, and says so when not.

``test/conftest.py`` names pytest's root directory; a process that names
none gets one line saying what to call, never a guess from where the
package lies.
"""

from pathlib import Path
import subprocess
import sys

import pytest

import orthoglide_testing

ROOT = Path(__file__).resolve().parents[1]


def test_the_session_runs_from_this_checkout():
    assert orthoglide_testing.checkout() == ROOT
    assert (orthoglide_testing.checkout() / 'package.xml').is_file()
    assert orthoglide_testing.params_file() == \
        ROOT / 'config' / 'orthoglide.yaml'
    assert orthoglide_testing.params_file().is_file()
    assert orthoglide_testing.config_file('fastdds_one_host.xml').is_file()


def test_a_folder_that_is_no_checkout_is_refused(tmp_path):
    with pytest.raises(orthoglide_testing.CheckoutError,
                       match='is not a checkout of orthoglide_ros'):
        orthoglide_testing.use_checkout(tmp_path)
    assert orthoglide_testing.checkout() == ROOT


def test_no_checkout_named_is_one_line_naming_the_call(tmp_path):
    result = subprocess.run(
        [sys.executable, '-c', 'import sys, orthoglide_testing\n'
         'try:\n'
         '    orthoglide_testing.params_file()\n'
         'except orthoglide_testing.CheckoutError as error:\n'
         '    sys.exit(str(error))\n'],
        cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    assert result.stderr == (
        'orthoglide_testing: no checkout named; call '
        'orthoglide_testing.use_checkout(<repository root>) first\n')
