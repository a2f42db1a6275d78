"""
The feedforward node's parameters: one table, validated as a whole.

The table below is the single source of the names, types, defaults, ranges
and descriptions: the node declares its ROS parameters from it, and
:func:`settings_from_parameters` validates a complete set of values (at start
and for every run-time change) into one immutable :class:`Settings`. No
rclpy here, so the rules are testable without ROS.
"""

from collections import namedtuple
import math

from orthoglide_ros.mechanics import DEFAULT_SINGULARITY_MARGIN
from orthoglide_ros.params_file import ROBOT_PREFIX, robot_from_parameters
from orthoglide_ros.robot import DESCRIPTIONS, Robot, UNITS

Spec = namedtuple('Spec', 'name type default description range')
Spec.__doc__ = """One parameter: ``type`` is one of ``double``,
``double_array``, ``string``, ``string_array``, ``bool``; ``default`` None
means declared without a value; ``range`` an inclusive ``(low, high)`` or
None."""

JOINT_NAMES = ('slider_a', 'slider_b', 'slider_c')


def joint_names_spec(description):
    """Return the ``joint_names`` Spec every node shares (its own text)."""
    return Spec('joint_names', 'string_array', list(JOINT_NAMES),
                description + ' (three distinct, non-empty)', None)


NODE_SPECS = (
    joint_names_spec('names of the prismatic joints of actuators A, B, C '
                     'in feedforward/joint_states'),
    Spec('base_frame', 'string', 'base_link',
         'frame of the setpoints (the paper\'s frame 0); a setpoint stamped '
         'with another non-empty frame is rejected', None),
    Spec('rate_hz', 'double', 0.0,
         'control tick in Hz: 0.0 computes and publishes once per new '
         'setpoint; a positive value publishes the newest setpoint\'s '
         'result at this fixed rate', (0.0, 10000.0)),
    Spec('setpoint_timeout', 'double', 0.1,
         'seconds (by arrival time) without a fresh setpoint after which '
         'the node stops publishing until the next fresh setpoint',
         (0.001, 3600.0)),
    Spec('pairing_timeout', 'double', 0.05,
         'seconds a partial setpoint (pose, twist or accel of one stamp) '
         'waits for its partners before it is dropped; at most '
         'setpoint_timeout', (0.0001, 3600.0)),
    Spec('singularity_margin', 'double', DEFAULT_SINGULARITY_MARGIN,
         'smallest accepted singularity distance, min(alpha_i / l3, '
         '1 / kappa_F(J_lambda)), both 1 at home and 0 at a singularity of '
         'J1 or J2', (0.0, 0.99)),
    Spec('pose_only', 'bool', False,
         'serve each pose alone as a setpoint with zero velocity and '
         'acceleration (twist and accel topics ignored); trajectory points '
         'may then omit velocities and accelerations', None),
)

_DEFAULT_ROBOT = Robot()
ROBOT_SPECS = tuple(
    Spec(ROBOT_PREFIX + name,
         'double_array' if name == 'gravity' else 'double',
         None if name in ('m4', 'm6') else _DEFAULT_ROBOT.as_parameters()[name],
         f'{DESCRIPTIONS[name]} ({UNITS[name]})', None)
    for name in Robot.parameter_names())

SPECS = ROBOT_SPECS + NODE_SPECS

Settings = namedtuple('Settings', (
    'robot', 'joint_names', 'base_frame', 'rate_hz', 'setpoint_timeout',
    'pairing_timeout', 'singularity_margin', 'pose_only'))
Settings.__doc__ = """Everything the node's logic reads, swapped as one."""


def default_parameters():
    """Return ``{name: default}`` for every parameter that has a default."""
    return {s.name: s.default for s in SPECS if s.default is not None}


def settings_from_parameters(values):
    """
    Validate a complete set of parameter values into :class:`Settings`.

    ``values``: ``{name: value}``; a robot parameter that is absent or None
    takes its default (``m4``, ``m6``: ``m2``, ``m3``). Raises ValueError
    naming the parameter and the rule it breaks.
    """
    robot = robot_from_parameters(
        {k: v for k, v in values.items()
         if k.startswith(ROBOT_PREFIX) and v is not None})
    node = {s.name: values.get(s.name, s.default) for s in NODE_SPECS}
    for spec in NODE_SPECS:
        check_value(spec, node[spec.name])
    names = check_joint_names(node['joint_names'])
    if node['pairing_timeout'] > node['setpoint_timeout']:
        raise ValueError(
            f'pairing_timeout: must not exceed setpoint_timeout '
            f'({node["pairing_timeout"]} > {node["setpoint_timeout"]} s)')
    return Settings(robot, names, node['base_frame'],
                    node['rate_hz'], node['setpoint_timeout'],
                    node['pairing_timeout'], node['singularity_margin'],
                    node['pose_only'])


def check_value(spec, value):
    """Raise ValueError naming ``spec`` unless ``value`` fits its type/range."""
    kind = {'double': float, 'string': str, 'bool': bool}.get(spec.type)
    if kind is not None and type(value) is not kind:
        raise ValueError(f'{spec.name}: must be a {spec.type}, got {value!r}')
    if spec.type == 'string_array' and not (
            isinstance(value, (list, tuple))
            and all(isinstance(v, str) for v in value)):
        raise ValueError(
            f'{spec.name}: must be an array of strings, got {value!r}')
    if spec.range is not None:
        low, high = spec.range
        if not (math.isfinite(value) and low <= value <= high):
            raise ValueError(
                f'{spec.name}: must lie in [{low}, {high}], got {value!r}')


def check_joint_names(names):
    """Return ``joint_names`` as a tuple; ValueError unless 3 distinct."""
    names = tuple(names)
    if len(names) != 3 or len(set(names)) != 3 or not all(names):
        raise ValueError(
            'joint_names: must be three distinct non-empty names, got '
            f'{list(names)!r}')
    return names


def check_triple(name, value, what, example='[0.0, 0.0, 0.0]'):
    """
    Return ``value`` as a 3-tuple of finite doubles, else raise ValueError.

    ``what`` says what the three values are (e.g. ``'(m)'``); doubles as
    rcl types them: ``0`` is an integer, ``0.0`` a double.
    """
    if not (isinstance(value, (list, tuple)) and len(value) == 3
            and all(type(c) is float for c in value)):
        raise ValueError(
            f'{name}: must be an array of three doubles {what}, such as '
            f'{example}, got {value!r}')
    if not all(math.isfinite(c) for c in value):
        raise ValueError(f'{name}: must be finite, got {list(value)!r}')
    return tuple(value)
