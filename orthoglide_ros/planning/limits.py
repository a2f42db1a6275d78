"""
The actuators' limits in the ros2_control / MoveIt ``joint_limits`` form.

One entry per actuator joint (``slider_a``, ``slider_b``, ``slider_c``)::

    joint_limits:
      slider_c:
        has_velocity_limits: true
        max_velocity: 1.0          # |lambdadot| (m/s)
        has_acceleration_limits: true
        max_acceleration: 20.0     # |lambdaddot| (m/s^2)
        has_deceleration_limits: false
        max_deceleration: 0.0      # |lambdaddot| slowing down (m/s^2)
        has_jerk_limits: false
        max_jerk: 0.0              # |d lambdaddot / dt| (m/s^3)
        has_effort_limits: true
        max_effort: 500.0          # |force| (N)
        has_position_limits: false
        min_position: -0.3         # lambda (m)
        max_position: 0.3

A limit bounds when its ``has_...`` is true, or absent with its ``max_...``
given (a limit written is never ignored); ``has_...: false`` or no
``max_...`` does not bound; ``has_...: true`` without its value is refused.
ros2_control's soft-limit keys are accepted and not used. Read from a YAML
file's top-level ``joint_limits:`` (:func:`load_limits`) or from a node's
``joint_limits.<joint>.*`` parameters (:func:`limits_from_parameters`).

:data:`PAPER_LIMITS` are the paper robot's (config/orthoglide.yaml's
``planner`` section): see doc/planning.md for how they were chosen.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from orthoglide_ros.formats.params_file import (NO_SECTION, ParametersFile,
                                                ParametersFileError,
                                                read_yaml)
from orthoglide_ros.formats.text import clip
from orthoglide_ros.model.robot import JOINT_NAMES
from orthoglide_ros.model.types import Array, Path
from orthoglide_ros.planning.moves import NUMBER_BOUND

# Every limit: (its key, the has_ key, unit, what it bounds).
KINDS = (
    ('max_velocity', 'has_velocity_limits', 'm/s', '|lambdadot|'),
    ('max_acceleration', 'has_acceleration_limits', 'm/s^2', '|lambdaddot|'),
    ('max_deceleration', 'has_deceleration_limits', 'm/s^2',
     '|lambdaddot| slowing down'),
    ('max_jerk', 'has_jerk_limits', 'm/s^3', '|d lambdaddot / dt|'),
    ('max_effort', 'has_effort_limits', 'N', '|force|'),
)
POSITION_KEYS = ('has_position_limits', 'min_position', 'max_position')
# ros2_control's keys the planner accepts and does not use.
UNUSED_KEYS = ('has_soft_limits', 'k_position', 'k_velocity',
               'soft_lower_limit', 'soft_upper_limit', 'angle_wraparound')
# Largest value of any limit, and magnitude of a position limit: the
# program's bound on every number (far beyond any drive).
LIMIT_BOUND = NUMBER_BOUND

# The paper robot's limits: each drive the same; see doc/planning.md.
PAPER_LIMITS = {name: {'has_velocity_limits': True, 'max_velocity': 1.0,
                       'has_acceleration_limits': False,
                       'max_acceleration': 0.0,
                       'has_jerk_limits': False, 'max_jerk': 0.0,
                       'has_effort_limits': True, 'max_effort': 650.0}
                for name in JOINT_NAMES}


class LimitsError(ValueError):
    """
    Limits that cannot be used: ``key`` names the key, ``detail`` says why.

    ``key``: ``joint_limits.slider_a.max_effort`` (a joint's or the whole
    mapping's where no one key is to blame; '' where the file is);
    ``detail``: the message without it; ``source``: where the limits were
    read ('', a file, ``file: node``). The message: ``source: key: detail``.
    """

    def __init__(self, key: str, detail: str, source: str = '') -> None:
        """Keep the ``key``, the ``detail`` and the ``source``."""
        super().__init__(': '.join(part for part in (source, key, detail)
                                   if part))
        self.key = key
        self.detail = detail
        self.source = source


@dataclass(frozen=True)
class Limits:
    """
    Per actuator A, B, C: each limit, ``inf`` where none bounds.

    ``velocity`` (m/s), ``acceleration`` and ``deceleration`` (m/s^2),
    ``jerk`` (m/s^3), ``effort`` (N): (3,) arrays; ``position``: (3, 2)
    ``lambda`` bounds (m, -inf and inf where none). ``names``: the joints.
    """

    velocity: Array
    acceleration: Array
    deceleration: Array
    jerk: Array
    effort: Array
    position: Array
    names: tuple = JOINT_NAMES

    @property
    def bounding(self) -> bool:
        """Whether any limit bounds the motion (position limits do not)."""
        return bool(np.isfinite(np.r_[
            self.velocity, self.acceleration, self.deceleration, self.jerk,
            self.effort]).any())

    def scaled(self, factor: float) -> 'Limits':
        """Return the limits times ``factor`` (effort, rates; not positions)."""
        return Limits(self.velocity * factor, self.acceleration * factor,
                      self.deceleration * factor, self.jerk * factor,
                      self.effort * factor, self.position, self.names)


def limits_from_mapping(entries: Any, names: Sequence[str] = JOINT_NAMES,
                        where: str = 'joint_limits') -> Limits:
    """
    Return the :class:`Limits` of a ``joint_limits`` mapping.

    ``entries``: ``{joint: {key: value}}``; ``names``: the actuators' joint
    names, A, B, C. A joint not listed has no limits. Raises
    :class:`LimitsError` naming the key (``joint_limits.slider_a.max_effort``).
    """
    if not isinstance(entries, Mapping):
        raise LimitsError(where, 'must be a mapping of joints to their '
                          f'limits, got {type(entries).__name__}')
    unknown = [str(k) for k in entries if k not in names]
    if unknown:
        raise LimitsError(f'{where}.{unknown[0]}', 'not an actuator joint; '
                          'known: ' + ', '.join(names))
    values = {key: np.full(3, math.inf) for key, *_ in KINDS}
    position = np.tile([-math.inf, math.inf], (3, 1))
    for j, name in enumerate(names):
        entry = entries.get(name)
        if entry is None:
            continue
        prefix = f'{where}.{name}'
        if not isinstance(entry, Mapping):
            raise LimitsError(prefix, 'must be a mapping of limits')
        known = {k for kind in KINDS for k in kind[:2]} | set(
            POSITION_KEYS) | set(UNUSED_KEYS)
        for key in entry:
            if key not in known:
                raise LimitsError(f'{prefix}.{key}', 'not a joint limit; '
                                  'known: ' + ', '.join(
                                      sorted(known - set(UNUSED_KEYS))))
        for key, has, unit, _ in KINDS:
            value = _bound(entry, prefix, key, has, unit)
            if value is not None:
                values[key][j] = value
        position[j] = _position(entry, prefix)
    return Limits(values['max_velocity'], values['max_acceleration'],
                  values['max_deceleration'], values['max_jerk'],
                  values['max_effort'], position, tuple(names))


def _flag(entry: Mapping, prefix: str, key: str) -> Optional[bool]:
    flag = entry.get(key)
    if flag is not None and not isinstance(flag, bool):
        raise LimitsError(f'{prefix}.{key}', 'must be true or false, got '
                          f'{flag!r}')
    return flag


def _number(entry: Mapping, prefix: str, key: str) -> Optional[float]:
    value = entry.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LimitsError(f'{prefix}.{key}', 'must be a number (decimal), '
                          f'got {clip(repr(value), 80)}')
    if isinstance(value, float) and not math.isfinite(value):
        raise LimitsError(f'{prefix}.{key}', f'must be finite, got {value!r}')
    if not abs(value) <= LIMIT_BOUND:     # an int of any size too
        raise LimitsError(f'{prefix}.{key}', 'must be at most '
                          f'{LIMIT_BOUND:,.0f} in magnitude, got '
                          f'{clip(repr(value), 40)}')
    return float(value)


def _bound(entry: Mapping, prefix: str, key: str, has: str,
           unit: str) -> Optional[float]:
    """Return one limit's value, or None where it does not bound."""
    flag = _flag(entry, prefix, has)
    value = _number(entry, prefix, key)
    if flag is False or (flag is None and value is None):
        return None
    if value is None:
        raise LimitsError(f'{prefix}.{key}', f'needed where {has} is true')
    if not 0.0 < value <= LIMIT_BOUND:
        raise LimitsError(f'{prefix}.{key}', 'must be above 0 and at most '
                          f'{LIMIT_BOUND:g} {unit}, got {value!r}')
    return value


def _position(entry: Mapping, prefix: str) -> tuple[float, float]:
    flag = _flag(entry, prefix, 'has_position_limits')
    low = _number(entry, prefix, 'min_position')
    high = _number(entry, prefix, 'max_position')
    if flag is False or (flag is None and low is None and high is None):
        return (-math.inf, math.inf)
    if low is None or high is None:
        raise LimitsError(prefix, 'position limits need both min_position '
                          'and max_position')
    if not low < high:
        raise LimitsError(f'{prefix}.min_position', 'must be below '
                          f'max_position, got {low!r} and {high!r}')
    return (low, high)


def load_limits(path: Path, names: Sequence[str] = JOINT_NAMES) -> Limits:
    """
    Return the limits of a YAML file's top-level ``joint_limits:``.

    The file is read as a parameters file is (:func:`read_yaml`: UTF-8, at
    most 1 MiB, no aliases, nested at most 32 deep, no key twice), its
    numbers decimal only. Raises :class:`LimitsError`.
    """
    try:
        document = read_yaml(path, decimal=True)
    except ParametersFileError as error:
        raise LimitsError('', error.detail, str(path)) from None
    if not isinstance(document, dict) or 'joint_limits' not in document:
        raise LimitsError('', 'no top-level joint_limits: mapping', str(path))
    try:
        return limits_from_mapping(document['joint_limits'], names)
    except LimitsError as error:
        raise LimitsError(error.key, error.detail, str(path)) from None


def limits_from_parameters(params: Mapping[str, Any],
                           names: Sequence[str] = JOINT_NAMES) -> Limits:
    """
    Return the limits of flat ``joint_limits.<joint>.<key>`` parameters.

    Other parameters are ignored (a node's, a parameters file's section).
    """
    entries: dict = {}
    for key, value in params.items():
        if not key.startswith('joint_limits.'):
            continue
        parts = key.split('.')
        if len(parts) != 3:
            raise LimitsError(key, 'expected joint_limits.<joint>.<key>')
        entries.setdefault(parts[1], {})[parts[2]] = value
    return limits_from_mapping(entries, names)


def limits_from_params_file(parameters: ParametersFile,
                            node: str = 'planner',
                            names: Sequence[str] = JOINT_NAMES
                            ) -> Optional[Limits]:
    """
    Return the ``joint_limits.*`` of a parameters file's ``node`` section.

    ``parameters``: the file, read once (:meth:`ParametersFile.read`).
    None where the file has no such section or no ``joint_limits`` in it.
    Raises :class:`LimitsError` (its ``source`` the file and the node) or
    :class:`ParametersFileError` (a section not in rcl's form).
    """
    try:
        params = parameters.section(node)
    except ParametersFileError as error:
        if error.reason == NO_SECTION:
            return None
        raise
    if not any(k.startswith('joint_limits.') for k in params):
        return None
    try:
        return limits_from_parameters(params, names)
    except LimitsError as error:
        raise LimitsError(error.key, error.detail,
                          f'{parameters.path}: {node}') from None


def paper_limits() -> Limits:
    """Return :data:`PAPER_LIMITS` as :class:`Limits`."""
    return limits_from_mapping(PAPER_LIMITS)
