"""
Read and write ROS 2 parameters files the way rcl does, without ROS.

The nodes and the ``orthoglide`` tool share one file
(``config/orthoglide.yaml``), so the tool applies rcl's sections and
typing (:class:`ParametersFile`, read once, its sections on demand;
:func:`load_parameters`, :func:`load_robot`) and writes a robot with the
same typing (:func:`robot_file_text`). The rules: doc/cli.md#--params.
"""

from __future__ import annotations

from typing import Any, Sequence
import math
import re

import yaml

from orthoglide_ros.formats.text import clip, read_text
from orthoglide_ros.model.robot import (is_vector, ParameterError, Robot,
                                        ROW, ROWS)
from orthoglide_ros.model.types import Path

NODE_NAME = 'feedforward'     # the node whose robot the tools read
# The section every node reads (rcl's wildcard): where the tools write a
# robot, so that one file serves every node and command as is.
EVERY_NODE = '/**'
ROBOT_PREFIX = 'robot.'
_SCALAR = {'double': float, 'integer': int, 'string': str, 'bool': bool}
_ELEMENT = {'double_array': float, 'integer_array': int, 'string_array': str}
# A parameters file is small: config/orthoglide.yaml takes 4 kB.
MAX_FILE_BYTES = 1024 * 1024
# Deepest nesting of mappings and sequences (robot: {gravity: [...]} is 3).
MAX_DEPTH = 32


# Why a parameters file is refused (ParametersFileError.reason): for
# callers that react to one (a node's section may be absent: NO_SECTION).
UNREADABLE = 'unreadable'           # not a readable UTF-8 file in the bound
NOT_YAML = 'not_yaml'               # not YAML, or a value YAML cannot hold
NOT_PARAMETERS = 'not_parameters'   # YAML, not rcl's form
NO_SECTION = 'no_section'           # no section for the node asked for


class ParametersFileError(ValueError):
    """
    A parameters file that cannot be read: ``reason`` is why.

    ``path``: the file; ``reason``: UNREADABLE, NOT_YAML, NOT_PARAMETERS
    or NO_SECTION; ``detail``: the message without the path. The message
    is ``path: detail``.
    """

    def __init__(self, path: Path, reason: str, detail: str) -> None:
        """Keep the ``path``, the ``reason`` and the ``detail``."""
        super().__init__(f'{path}: {detail}')
        self.path = path
        self.reason = reason
        self.detail = detail


class _RclLoader(yaml.SafeLoader):
    """
    SafeLoader that also reads ``1e-3``-style plain scalars as doubles.

    It refuses aliases and nesting deeper than MAX_DEPTH while composing,
    before anything is expanded.
    """

    _depth = 0

    def compose_node(self, parent, index):
        """Compose one node; refuse an alias or a node too deep."""
        if self.check_event(yaml.AliasEvent):
            raise yaml.composer.ComposerError(
                None, None, 'aliases (*name) are not supported',
                self.peek_event().start_mark)
        if self._depth >= MAX_DEPTH:
            raise yaml.composer.ComposerError(
                None, None, f'nested more than {MAX_DEPTH} deep',
                self.peek_event().start_mark)
        self._depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node, deep=False):
        """Refuse a key given twice in one mapping (YAML leaves it open)."""
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if not isinstance(key, str):
                continue
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f'the key {clip(key, 80)!r} appears twice',
                    key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep)


_INT, _FLOAT = 'tag:yaml.org,2002:int', 'tag:yaml.org,2002:float'
_RclLoader.add_implicit_resolver(
    _FLOAT,
    re.compile(r'^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$'),
    list('-+0123456789.'))


class _DecimalLoader(_RclLoader):
    """
    _RclLoader whose numbers are decimal only: ASCII digits, a point, an exponent.

    YAML 1.1's other spellings (``0x1F``, ``0o17``, ``1_000``, ``1:30``,
    ``.inf``) stay strings, which a reader of numbers refuses.
    """


_DecimalLoader.yaml_implicit_resolvers = {
    first: [(tag, rx) for tag, rx in resolvers if tag not in (_INT, _FLOAT)]
    for first, resolvers in _RclLoader.yaml_implicit_resolvers.items()}
_DecimalLoader.add_implicit_resolver(_INT, re.compile(r'^[-+]?[0-9]+$'),
                                     list('-+0123456789'))


def _decimal_int(loader: _DecimalLoader, node: yaml.ScalarNode) -> int:
    """Return a plain integer scalar in base ten (010 is ten, not octal)."""
    return int(str(loader.construct_scalar(node)))


_DecimalLoader.add_constructor(_INT, _decimal_int)
_DecimalLoader.add_implicit_resolver(
    _FLOAT, re.compile(r'^[-+]?(?:[0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)'
                       r'(?:[eE][-+]?[0-9]+)?$'), list('-+0123456789.'))


def read_yaml(path: Path, decimal: bool = False) -> Any:
    """
    Return the YAML document in ``path``, read as a parameters file is.

    UTF-8, at most MAX_FILE_BYTES, no aliases, nested at most MAX_DEPTH
    deep, no key twice in a mapping, ``1e-3`` a double; ``decimal``:
    numbers only in decimal (:class:`_DecimalLoader`). Raises
    :class:`ParametersFileError` (UNREADABLE, NOT_YAML) naming the path:
    the parameters file's or another YAML file's (joint limits).
    """
    try:
        text = read_text(path, MAX_FILE_BYTES)
    except ValueError as failure:
        raise ParametersFileError(path, UNREADABLE, str(failure)) from None
    try:
        return yaml.load(text, Loader=_DecimalLoader if decimal
                         else _RclLoader)
    except yaml.YAMLError as failure:
        raise ParametersFileError(
            path, NOT_YAML,
            f'not valid YAML: {" ".join(str(failure).split())}') from None
    except ValueError as failure:   # e.g. an integer of over 4300 digits
        raise ParametersFileError(
            path, NOT_YAML, f'a value cannot be read: {failure}') from None


class ParametersFile:
    """
    A parameters file read once; each node's section on demand.

    :meth:`read` reads and parses it (:func:`read_yaml`), so that a command
    reads its ``--params`` once whatever it takes from it.
    """

    def __init__(self, path: Path, document: dict) -> None:
        """Keep the parsed ``document`` of ``path`` (use :meth:`read`)."""
        self.path = path
        self.document = document

    @classmethod
    def read(cls, path: Path) -> 'ParametersFile':
        """
        Read ``path``; raise :class:`ParametersFileError` if it is not one.

        Not readable, not YAML (:func:`read_yaml`), or not a mapping.
        """
        document = read_yaml(path)
        if not isinstance(document, dict):
            raise ParametersFileError(path, NOT_PARAMETERS,
                                      'not a ROS 2 parameters file')
        return cls(path, document)

    def section(self, node: str = NODE_NAME) -> dict[str, Any]:
        """
        Return node ``node``'s parameters as a flat ``{name: value}``.

        ``/**`` first, then the node's own (``node``, ``/node``), the later
        overriding, as rcl applies them. Raises
        :class:`ParametersFileError` without a section for the node.
        """
        keys = _section_keys(node)
        sections = [self.document[key] for key in keys
                    if key in self.document]
        if not sections:
            raise ParametersFileError(
                self.path, NO_SECTION, 'no section for the node: expected '
                'one of ' + ', '.join(repr(k) for k in keys))
        params: dict[str, Any] = {}
        for section in sections:
            values = section.get('ros__parameters') if isinstance(
                section, dict) else None
            if not isinstance(values, dict):
                raise ParametersFileError(
                    self.path, NOT_PARAMETERS,
                    'the node section has no ros__parameters mapping')
            _flatten(values, '', params)
        return params

    def robot(self) -> Robot:
        """Return the robot of the ``feedforward`` section's ``robot.*``."""
        return robot_from_parameters(self.section())


def _section_keys(node):
    return ('/**', node, '/' + node)


def load_parameters(path: Path, node: str = NODE_NAME) -> dict[str, Any]:
    """
    Return node ``node``'s parameters in ``path`` as a flat ``{name: value}``.

    Raises :class:`ParametersFileError` if the file cannot be read, is not
    YAML (:func:`read_yaml`), or has no section for the node
    (:meth:`ParametersFile.section`).
    """
    return ParametersFile.read(path).section(node)


def rcl_typed(kind: str, value: Any) -> Any:
    """
    Check ``value`` against rcl's typing of ``kind``; return it.

    ``kind``: ``double``, ``integer``, ``string``, ``bool`` or an array of
    the first three (``double_array``...). A double must be a float
    (``0.0``, not ``0``), an array must not mix integers and floats, a
    bool is not a number, a double array's values must be finite. Raises
    ValueError with the rule.
    """
    scalar = _SCALAR.get(kind)
    if scalar is not None:
        if type(value) is not scalar:
            raise ValueError(f'must be a{"n" if kind == "integer" else ""} '
                             f'{kind}, got {clip(repr(value), 80)}')
        return value
    element = _ELEMENT[kind]
    if not (isinstance(value, (list, tuple))
            and all(type(v) is element for v in value)):
        what = {float: 'doubles such as [0.0, 0.0, -9.81] (rcl refuses '
                'integers or mixed arrays)', int: 'integers such as [1]',
                str: 'strings'}[element]
        raise ValueError(f'must be an array of {what}, got '
                         f'{clip(repr(value), 80)}')
    if element is float and not all(math.isfinite(v) for v in value):
        raise ValueError(f'must be finite, got {clip(repr(list(value)), 80)}')
    return tuple(value)


def robot_from_parameters(params: dict[str, Any]) -> Robot:
    """
    Build a :class:`Robot` from the ``robot.*`` entries of ``params``.

    Other entries are ignored. An unknown ``robot.*`` name, a value of the
    wrong type (by rcl's rules) or a value the :class:`Robot` refuses raises
    :class:`ParameterError` naming the parameter (``robot.l3``).
    """
    values = {}
    for key, value in params.items():
        if not key.startswith(ROBOT_PREFIX):
            continue
        name = key[len(ROBOT_PREFIX):]
        row = ROW.get(name)
        if row is None:
            raise ParameterError(key, 'unknown parameter; known: ' + ', '.join(
                r.name for r in ROWS))
        try:
            values[name] = rcl_typed(
                'double_array' if is_vector(row) else 'double', value)
        except ValueError as error:
            raise ParameterError(key, str(error)) from None
    return Robot(**values)


def load_robot(path: Path) -> Robot:
    """
    Return the :class:`Robot` of the ``robot.*`` keys in the file ``path``.

    Read with :func:`load_parameters` and validated by
    :func:`robot_from_parameters`.
    """
    return ParametersFile.read(path).robot()


def _flatten(mapping, prefix, out):
    for key, value in mapping.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            _flatten(value, name + '.', out)
        else:
            out[name] = value


def robot_file_text(robot: Robot, comments: Sequence[str] = (),
                    node: str = EVERY_NODE) -> str:
    """
    Return a parameters file holding every ``robot.*`` value of ``robot``.

    One section for ``node`` (by default ``/**``, which every node and
    the tools read), the values nested under ``robot:`` in the order of
    :meth:`Robot.parameter_names`, each written as rcl types it: doubles
    by ``repr`` (always a decimal point or an exponent: ``15.0``,
    ``1e-06``), arrays of doubles in flow style; ``m4`` and ``m6``
    explicit. ``comments``: lines put first, each after ``# ``.
    :func:`load_robot` reads the file back to an equal robot.

    >>> from orthoglide_ros.model.robot import Robot
    >>> print(robot_file_text(Robot(m5=18.0)).splitlines()[12])
          m5: 18.0
    """
    lines = [f'# {line}'.rstrip() for line in comments]
    lines += [f'{node}:', '  ros__parameters:', '    robot:']
    for name, value in robot.as_parameters().items():
        text = ('[' + ', '.join(repr(float(v)) for v in value) + ']'
                if isinstance(value, list) else repr(float(value)))
        lines.append(f'      {name}: {text}')
    return '\n'.join(lines) + '\n'
