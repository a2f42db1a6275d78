"""
Node parameters: one mechanism for every node of the package, without ROS.

Each core module owns one :class:`Table` of :class:`Spec` rows (plus
:data:`ROBOT_SPECS` when it models the robot); the node declares its ROS
parameters from it and :meth:`Table.parse` validates a whole set into one
settings tuple or raises :class:`ParameterError`
(doc/decisions.md#parameters-status-and-errors). The rows several nodes
declare are here: ``robot.*``, the actuators' ``joint_limits.<joint>.*``
(:func:`joint_limit_specs`), ``joint_names``, ``base_frame``...

>>> table = Table('Demo', (Spec('rate_hz', 'double', 10.0, 'rate (Hz)',
...                             (0.0, 100.0)),))
>>> table.parse({}).rate_hz
10.0
>>> try:
...     table.parse({'rate_hz': 1})
... except ParameterError as error:
...     print(error)
rate_hz: must be a double, got 1
"""

from collections import namedtuple
import math

from orthoglide_ros.formats.params_file import (rcl_typed, ROBOT_PREFIX,
                                                robot_from_parameters)
from orthoglide_ros.formats.text import clip
from orthoglide_ros.model.mechanics import DEFAULT_SINGULARITY_MARGIN
from orthoglide_ros.model.robot import (is_vector, JOINT_NAMES,
                                        ParameterError, ROWS)
from orthoglide_ros.planning.limits import KINDS, LIMIT_BOUND

TYPES = ('double', 'double_array', 'integer', 'integer_array', 'string',
         'string_array', 'bool')


class Spec(namedtuple('Spec', 'name type default description range check '
                      'read_only')):
    """
    One parameter.

    ``type``: one of TYPES. ``default``: None means declared without a
    value (the rules then supply one). ``range``: an inclusive ``(low,
    high)`` for a double or an integer (declared in the ROS descriptor
    too), or None. ``check``: None or a function taking the typed value
    and returning the value the settings hold, raising ValueError with the
    rule (the name is added). ``read_only``: fixed once the node runs.
    """

    __slots__ = ()

    def __new__(cls, name, type, default, description, range=None,
                check=None, read_only=False):
        """Make a row; see the class docstring."""
        if type not in TYPES:
            raise ValueError(f'{name}: unknown parameter type {type!r}')
        if range is not None and type not in ('double', 'integer'):
            raise ValueError(f'{name}: a range needs a double or an '
                             'integer (use a check for arrays)')
        return super().__new__(cls, name, type, default, description, range,
                               check, read_only)

    def validate(self, value):
        """Return the settings value of ``value``; ParameterError if bad."""
        try:
            value = rcl_typed(self.type, value)
            if self.range is not None:
                _in_range(self.range, value)
            return value if self.check is None else self.check(value)
        except ParameterError:
            raise
        except ValueError as error:
            raise ParameterError(self.name, str(error)) from None


class Table:
    """
    One node's parameters: rows, settings tuple, rules across rows.

    ``name``: the settings tuple's type name. ``specs``: the node's own
    rows (a dotted name, ``joint_limits.slider_a.max_effort``, is the
    field ``joint_limits__slider_a__max_effort``); with ``robot`` the
    :data:`ROBOT_SPECS` come first and the
    settings' first field ``robot`` holds the validated :class:`Robot`.
    ``rules``: functions ``rule(settings)`` that raise
    :class:`ParameterError` when several values together break a rule.
    ``retired``: ``{old name: what replaced it}``, names refused with
    that hint wherever they are given (:meth:`refuse_retired`).
    """

    def __init__(self, name, specs, rules=(), robot=False, retired=None):
        """Build the settings type from the rows (see the class docstring)."""
        self.own_specs = tuple(specs)
        self.robot = robot
        self.specs = (ROBOT_SPECS if robot else ()) + self.own_specs
        self.rules = tuple(rules)
        self.retired = dict(retired or {})
        names = [s.name for s in self.specs]
        if len(names) != len(set(names)) or set(names) & set(self.retired):
            raise ValueError(f'{name}: a parameter name repeats')
        self.Settings = namedtuple(name, (('robot',) if robot else ())
                                   + tuple(field(s.name)
                                           for s in self.own_specs))

    def defaults(self):
        """Return ``{name: default}`` of every row that has a default."""
        return {s.name: s.default for s in self.specs
                if s.default is not None}

    def parse(self, values):
        """
        Validate a complete ``{name: value}`` set into the settings tuple.

        An absent name takes its default (a ``robot.*`` name that is None
        too: ``m4``, ``m6`` and ``friction_coulomb_negative`` then follow
        ``m2``, ``m3`` and ``friction_coulomb``); names of
        other tables are ignored, a retired one refused. Raises
        :class:`ParameterError` naming the first bad parameter
        (``robot.l3``, ``rate_hz``).
        """
        self.refuse_retired(values)
        fields = {}
        if self.robot:
            fields['robot'] = robot_from_parameters(
                {k: v for k, v in values.items()
                 if k.startswith(ROBOT_PREFIX) and v is not None})
        for spec in self.own_specs:
            fields[field(spec.name)] = spec.validate(
                values.get(spec.name, spec.default))
        settings = self.Settings(**fields)
        for rule in self.rules:
            rule(settings)
        return settings

    def refuse_retired(self, names):
        """Raise :class:`ParameterError` for the first retired name given."""
        for name in names:
            if name in self.retired:
                raise ParameterError(name, 'no longer a parameter; use '
                                     + self.retired[name])


def field(name):
    """Return the settings field of parameter ``name``: dots as ``__``."""
    return name.replace('.', '__')


# Checks used by several tables ------------------------------------------------
def joint_names(value):
    """Return three distinct non-empty names as a tuple (a Spec check)."""
    names = tuple(value)
    if len(names) != 3 or len(set(names)) != 3 or not all(names):
        raise ValueError(f'must be three distinct non-empty names, got '
                         f'{list(names)!r}')
    return names


def one_of(choices):
    """Return a Spec check: the value one of ``choices``."""
    def check(value):
        if value not in choices:
            raise ValueError(f'must be one of {", ".join(choices)}, got '
                             f'{value!r}')
        return value
    return check


def triple(value):
    """Return a double array of exactly three values as a tuple."""
    if len(value) != 3:
        raise ValueError(f'must be an array of three doubles, such as '
                         f'[0.0, 0.0, 0.0], got {_short(list(value))}')
    return tuple(value)


def nonnegative_triple(value):
    """Return three doubles >= 0 as a tuple (gains, limits)."""
    value = triple(value)
    if not all(v >= 0.0 for v in value):
        raise ValueError(f'must be >= 0, got {list(value)!r}')
    return value


def at_most(name, other, unit):
    """Return a rule across rows: parameter ``name`` at most ``other``."""
    def rule(settings):
        value, bound = getattr(settings, name), getattr(settings, other)
        if value > bound:
            raise ParameterError(name, f'must not exceed {other} ({value} > '
                                 f'{bound} {unit})')
    return rule


# Rows several nodes declare: name, type, default and range once, the
# text each node's own.
def joint_names_spec(description):
    """Return the ``joint_names`` row every node shares (its own text)."""
    return Spec('joint_names', 'string_array', list(JOINT_NAMES),
                description + ' (three distinct, non-empty)',
                check=joint_names)


def base_frame_spec(description):
    """Return a ``base_frame`` row: ``base_link`` by default."""
    return Spec('base_frame', 'string', 'base_link', description)


def singularity_margin_spec(description, low=0.0):
    """Return a ``singularity_margin`` row: the model's default, below 1."""
    return Spec('singularity_margin', 'double', DEFAULT_SINGULARITY_MARGIN,
                description, (low, 0.99))


def arrival_timeout_spec(name, default, low, description):
    """Return a timeout row: seconds by arrival time, ``low`` to an hour."""
    return Spec(name, 'double', default,
                'seconds (by arrival time) ' + description, (low, 3600.0))


# The actuators' limits in ros2_control's form, joint_limits.<joint>.*
# (planning/limits.py reads the form): the planner declares every kind,
# another node the kinds it applies, each row the same but for its
# default and what the node does beyond it.
_FLAGS = {key: has for key, has, _, _ in KINDS}
_FIELDS = {key: tuple((field(f'joint_limits.{joint}.{key}'),
                       field(f'joint_limits.{joint}.{has}'))
                      for joint in JOINT_NAMES)
           for key, has in _FLAGS.items()}


def joint_limit_specs(defaults, effects=None):
    """
    Return the ``joint_limits.<joint>.has_*`` and ``max_*`` rows.

    For each joint of actuators A, B, C (JOINT_NAMES) and each kind of
    :data:`planning.limits.KINDS` (``max_velocity``, ...,
    ``max_effort``), a bool flag and a double in ``[0, LIMIT_BOUND]``.
    ``defaults``: ``{joint: {key: value}}`` (as
    :data:`planning.limits.PAPER_LIMITS`), a key absent off (false,
    0.0). ``effects``: ``{max key: what the node does beyond it}``, the
    kinds the node applies (None: every kind, the planner's). A flag true
    with its value 0.0 is :func:`joint_limits_rule`'s to refuse.
    """
    specs = []
    for joint in JOINT_NAMES:
        given = defaults.get(joint, {})
        for key, has, unit, what in KINDS:
            if effects is not None and key not in effects:
                continue
            effect = '' if effects is None else '; ' + effects[key]
            specs.append(Spec(
                f'joint_limits.{joint}.{has}', 'bool', given.get(has, False),
                f'whether {key} of {joint} bounds {what}'))
            specs.append(Spec(
                f'joint_limits.{joint}.{key}', 'double', given.get(key, 0.0),
                f'largest {what} of {joint} ({unit}) where {has} is true'
                + effect, (0.0, LIMIT_BOUND)))
    return specs


def joint_limit_name(key):
    """Return the name of limit ``key`` of every joint, for a message."""
    return (f'joint_limits.<joint>.{key} (with {_FLAGS[key]}: true) for '
            'each <joint> of ' + ', '.join(JOINT_NAMES))


def every_joint(**limits):
    """Return ``{joint: {...}}`` giving each joint ``limits``, each flag on."""
    entry = {}
    for key, value in limits.items():
        entry.update({_FLAGS[key]: True, key: value})
    return {joint: dict(entry) for joint in JOINT_NAMES}


def joint_limit_values(key, limits):
    """
    Return the parameters that set limit ``key`` of actuators A, B, C.

    ``limits``: one value for every joint or three; ``math.inf`` (or
    None) turns a joint's limit off. ``{'joint_limits.slider_a.max_effort':
    400.0, 'joint_limits.slider_a.has_effort_limits': True, ...}``.
    """
    if not isinstance(limits, (list, tuple)):
        limits = (limits,) * 3
    values = {}
    for joint, limit in zip(JOINT_NAMES, limits):
        on = limit is not None and limit != math.inf
        values[f'joint_limits.{joint}.{_FLAGS[key]}'] = on
        values[f'joint_limits.{joint}.{key}'] = float(limit) if on else 0.0
    return values


def joint_limit(settings, key):
    """
    Return limit ``key`` (``max_effort``...) of actuators A, B, C.

    A 3-tuple from the settings of :func:`joint_limit_specs` rows:
    ``math.inf`` where the joint's flag is false.
    """
    return tuple(getattr(settings, value) if getattr(settings, flag)
                 else math.inf for value, flag in _FIELDS[key])


def joint_limits_rule(settings):
    """Refuse a ``has_*`` flag true with its ``max_*`` at 0.0 (a Table rule)."""
    for key, has in _FLAGS.items():
        for joint, (value, flag) in zip(JOINT_NAMES, _FIELDS[key]):
            if getattr(settings, flag, False) and \
                    getattr(settings, value) <= 0.0:
                raise ParameterError(
                    f'joint_limits.{joint}.{key}', 'must be above 0 where '
                    f'{has} is true, got {getattr(settings, value)!r}')


def _short(value):
    """Return ``repr(value)`` shortened for a message (:func:`clip`)."""
    return clip(repr(value), 80)


def _in_range(bounds, value):
    low, high = bounds
    if not (math.isfinite(value) and low <= value <= high):
        raise ValueError(f'must lie in [{low:g}, {high:g}], got '
                         f'{_short(value)}')


ROBOT_SPECS = tuple(
    Spec(ROBOT_PREFIX + row.name,
         'double_array' if is_vector(row) else 'double',
         list(row.default) if is_vector(row) and row.default else
         row.default, f'{row.description} ({row.unit})',
         None if is_vector(row) or row.open else row.limits)
    for row in ROWS)
