"""
Read ROS 2 parameters files the way rcl does, without ROS.

The node and the ``orthoglide`` tool share one file (``config/orthoglide.yaml``).
rcl starts a node only if every value has the declared type, so the tools
apply the same rules here:

- a node's section is keyed by its name (``feedforward``, ``/feedforward``)
  or ``/**`` (several may be present: ``/**`` first, then the node's own
  name, the later overriding), with its values under ``ros__parameters``;
- parameters may be nested mappings (``robot: {l3: 0.85}``) or dotted keys
  (``robot.l3: 0.85``);
- a double needs a decimal point or an exponent (``0.0``, not ``0``), an array
  must not mix integers and floats, booleans are not numbers;
- a plain scalar such as ``1e-3`` is a double, as in rcl (YAML 1.1, which
  PyYAML implements, would read it as a string).
"""

import re

import yaml

from orthoglide_ros.robot import Robot, RobotParameterError

NODE_NAME = 'feedforward'     # the node whose robot the tools read
ROBOT_PREFIX = 'robot.'


class ParametersFileError(ValueError):
    """A parameters file that cannot be read; the message says why."""


class _RclLoader(yaml.SafeLoader):
    """SafeLoader that also reads ``1e-3``-style plain scalars as doubles."""


_RclLoader.add_implicit_resolver(
    'tag:yaml.org,2002:float',
    re.compile(r'^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$'),
    list('-+0123456789.'))


def load_parameters(path, node=NODE_NAME):
    """
    Return node ``node``'s parameters in ``path`` as a flat ``{name: value}``.

    Raises :class:`ParametersFileError` if the file cannot be read, is not
    YAML, or has no section for the node.
    """
    try:
        with open(path, encoding='utf-8') as stream:
            document = yaml.load(stream, Loader=_RclLoader)
    except OSError as error:
        raise ParametersFileError(f'{path}: {error.strerror}') from None
    except yaml.YAMLError as error:
        raise ParametersFileError(f'{path}: not valid YAML: {error}') from None
    if not isinstance(document, dict):
        raise ParametersFileError(f'{path}: not a ROS 2 parameters file')
    keys = ('/**', node, '/' + node)
    sections = [document[key] for key in keys if key in document]
    if not sections:
        raise ParametersFileError(
            f'{path}: no section for the node: expected one of '
            + ', '.join(repr(k) for k in keys))
    params = {}
    for section in sections:
        values = section.get('ros__parameters') if isinstance(
            section, dict) else None
        if not isinstance(values, dict):
            raise ParametersFileError(
                f'{path}: the node section has no ros__parameters mapping')
        _flatten(values, '', params)
    return params


def robot_from_parameters(params):
    """
    Build a :class:`Robot` from the ``robot.*`` entries of ``params``.

    Other entries are ignored. An unknown ``robot.*`` name, a value of the
    wrong type (by rcl's rules) or a value the :class:`Robot` refuses raises
    :class:`RobotParameterError` naming the parameter.
    """
    names = Robot.parameter_names()
    values = {}
    for key, value in params.items():
        if not key.startswith(ROBOT_PREFIX):
            continue
        name = key[len(ROBOT_PREFIX):]
        if name not in names:
            raise RobotParameterError(
                name, 'unknown parameter; known: ' + ', '.join(names))
        values[name] = _typed(name, value)
    return Robot(**values)


def load_robot(path):
    """Return the :class:`Robot` described by the parameters file ``path``."""
    return robot_from_parameters(load_parameters(path))


def _typed(name, value):
    """Check a value against rcl's typing of the declared parameter."""
    if name == 'gravity':
        if not isinstance(value, list) or not all(
                type(v) is float for v in value):
            raise RobotParameterError(name, (
                f'must be an array of doubles such as [0.0, 0.0, -9.81] '
                f'(rcl refuses integers or mixed arrays), got {value!r}'))
        return value
    if type(value) is not float:
        raise RobotParameterError(name, (
            f'must be a double written with a decimal point (rcl refuses '
            f'{value!r} of type {type(value).__name__})'))
    return value


def _flatten(mapping, prefix, out):
    for key, value in mapping.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            _flatten(value, name + '.', out)
        else:
            out[name] = value
