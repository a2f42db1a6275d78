"""
What the DDS tests assert of a node: its outputs, its exit, its scripts.

- :func:`close` and :func:`assert_vector`: outputs against
  ``mechanics.solve`` to TOL (the node publishes the core's doubles
  unchanged);
- :func:`assert_clean_exit`: exit code 0 within a bound, no traceback;
- :func:`assert_declared`: every row of a parameter table declared;
- :func:`needs_scripts`: skip unless the console scripts are installed.
"""

import os

import pytest

from orthoglide_testing.processes import node_executable


# Outputs are checked against mechanics.solve to this (relative above 1,
# absolute below): the node publishes the core's doubles unchanged.
TOL = 1e-9


def close(actual, expected):
    """Say whether two floats agree to TOL (relative above 1, else absolute)."""
    return abs(actual - expected) <= TOL * max(1.0, abs(expected))


def assert_vector(actual, expected, what):
    """Check three received floats against the expected 3-tuple."""
    actual = list(actual)
    assert len(actual) == 3 and all(
        close(a, e) for a, e in zip(actual, expected)), (
        f'{what}: got {actual}, expected {list(expected)}')


def assert_clean_exit(code, stderr, seconds, prompt):
    """Assert an exit code 0 within ``prompt`` s and no traceback."""
    assert code == 0, f'exit code {code} after SIGINT; stderr:\n{stderr}'
    assert seconds < prompt, f'took {seconds:.1f} s to exit after SIGINT'
    assert 'Traceback' not in stderr, stderr


def needs_scripts(*names):
    """
    Return a pytest mark: skip unless the console scripts are installed.

    ``names`` default to the feedforward; the scripts are looked for next to
    the running Python (:func:`node_executable`).
    """
    missing = [name for name in names or ('feedforward',)
               if not os.path.exists(node_executable(name))]
    return pytest.mark.skipif(
        bool(missing), reason='not installed next to python: '
        + ', '.join(missing))


def assert_declared(node, table):
    """Every Spec of ``table`` is a parameter of ``node``, as the row says."""
    for spec in table.specs:
        assert node.has_parameter(spec.name), spec.name
        descriptor = node.describe_parameter(spec.name)
        assert descriptor.description == spec.description
        if spec.range is not None:
            r = (descriptor.integer_range if spec.type == 'integer'
                 else descriptor.floating_point_range)[0]
            assert (r.from_value, r.to_value) == spec.range
