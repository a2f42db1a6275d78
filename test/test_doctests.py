"""
The ``>>>`` examples in the package's docstrings run as doctests.

Every module of ``orthoglide_ros`` is imported and its examples run; a
module without examples passes trivially, so a new example is tested as
soon as it is written. The ROS glue modules need rclpy to import (no DDS is
started); they are skipped where it is missing.
"""

import doctest
import importlib
import pkgutil

import pytest

import orthoglide_ros

MODULES = sorted(m.name for m in pkgutil.walk_packages(
    orthoglide_ros.__path__, 'orthoglide_ros.')
    if not m.ispkg and not m.name.endswith('.__main__'))


@pytest.mark.parametrize('name', MODULES)
def test_docstring_examples(name):
    try:
        module = importlib.import_module(name)
    except ImportError as error:
        if 'rclpy' in str(error) or 'msgs' in str(error):
            pytest.skip(f'{name} needs ROS: {error}')
        raise
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f'{result.failed} example(s) of {name} failed'
