"""
A node's ROS parameters, declared from its core's table and read back.

An empty array default is declared by its type alone: rclpy 7.1.6 types
``[]`` as a byte array whatever the descriptor says; that can go when it
does not (``benchmarks/upstream_checks.py``, ``empty_array_default``).
"""

import array

from rclpy.exceptions import (InvalidParameterValueException,
                              ParameterUninitializedException)
from rclpy.parameter import Parameter

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange,
                                ParameterDescriptor)

from orthoglide_ros.cores.parameters import ParameterError
from orthoglide_ros.formats.text import clip

_TYPES = {'double': Parameter.Type.DOUBLE,
          'double_array': Parameter.Type.DOUBLE_ARRAY,
          'integer': Parameter.Type.INTEGER,
          'integer_array': Parameter.Type.INTEGER_ARRAY,
          'string': Parameter.Type.STRING,
          'string_array': Parameter.Type.STRING_ARRAY,
          'bool': Parameter.Type.BOOL}


def declare_specs(node, specs):
    """
    Declare one ROS parameter per Spec (type, default, range, text).

    A start-up value that rclpy refuses against its descriptor (out of
    range) raises :class:`ParameterError` naming it, as the table would.
    An empty array default is declared by its type alone (rclpy takes
    ``[]`` for a byte array): unset, it reads as the table's default.
    """
    for spec in specs:
        descriptor = ParameterDescriptor(
            description=spec.description, type=_TYPES[spec.type].value,
            read_only=spec.read_only)
        if spec.range is not None and spec.type == 'double':
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=spec.range[0], to_value=spec.range[1])]
        elif spec.range is not None and spec.type == 'integer':
            descriptor.integer_range = [IntegerRange(
                from_value=spec.range[0], to_value=spec.range[1])]
        try:
            node.declare_parameter(
                spec.name, _TYPES[spec.type] if spec.default in (None, [])
                else spec.default, descriptor)
        except InvalidParameterValueException as error:
            raise ParameterError(spec.name, clip(error.args[0])) from None


def overridden(node, names):
    """
    Return which of ``names`` (undeclared) the node was given at start.

    By ``-p`` or a parameters file: rclpy keeps such overrides for a
    later declaration, so each name is declared without a type, read and
    undeclared again.
    """
    given = []
    for name in names:
        value = node.declare_parameter(
            name, None, ParameterDescriptor(dynamic_typing=True))
        if value.type_ != Parameter.Type.NOT_SET:
            given.append(name)
        node.undeclare_parameter(name)
    return given


def spec_values(node, specs, changes=()):
    """
    Return ``{name: value}`` of the specs' parameters with ``changes`` applied.

    Plain types: rclpy gives double arrays as ``array.array``, this gives
    lists; a parameter declared without a value gives None, or is left
    out when its spec has a default (an empty array: see
    :func:`declare_specs`), so that the table's default applies.
    """
    values = {}
    for spec in specs:
        try:
            values[spec.name] = node.get_parameter(spec.name).value
        except ParameterUninitializedException:
            if spec.default is None:
                values[spec.name] = None
    values.update((p.name, p.value) for p in changes)
    return {name: list(value) if isinstance(value, array.array)
            else value for name, value in values.items()}
