"""
The limits file: ros2_control's joint_limits form, and what bounds.

A limit bounds with its ``has_...: true`` and its value, or with its value
alone; ``has_...: false`` or no value does not bound; a flag without its
value, an unknown joint or key, a value that is not a positive number, a
file that is not YAML: refused, naming the key. The node's parameters
(``joint_limits.<joint>.<key>``) and a parameters file's ``planner``
section give the same limits; config/orthoglide.yaml's are the paper
robot's.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from orthoglide_ros.formats.params_file import (NO_SECTION, NOT_PARAMETERS,
                                                ParametersFile,
                                                ParametersFileError)
from orthoglide_ros.planning.limits import (limits_from_mapping,
                                            limits_from_parameters,
                                            limits_from_params_file,
                                            LimitsError, load_limits,
                                            paper_limits)

CONFIG = Path(__file__).resolve().parents[1] / 'config' / 'orthoglide.yaml'


def test_what_bounds_and_what_does_not():
    limits = limits_from_mapping({
        'slider_a': {'has_effort_limits': True, 'max_effort': 300.0,
                     'has_velocity_limits': False, 'max_velocity': 1.0},
        'slider_b': {'max_acceleration': 20, 'has_jerk_limits': False},
        'slider_c': {'has_position_limits': True, 'min_position': -0.3,
                     'max_position': 0.2, 'has_soft_limits': False}})
    assert limits.effort[0] == 300.0 and np.isinf(limits.effort[1:]).all()
    assert np.isinf(limits.velocity).all()
    assert limits.acceleration[1] == 20.0
    assert np.isinf(limits.jerk).all()
    assert tuple(limits.position[2]) == (-0.3, 0.2)
    assert limits.bounding
    assert not limits_from_mapping({'slider_c': {
        'has_position_limits': True, 'min_position': -0.3,
        'max_position': 0.2}}).bounding


@pytest.mark.parametrize('entries, key, words', (
    ({'slider_d': {}}, 'joint_limits.slider_d', 'not an actuator joint'),
    ({'slider_a': {'max_efort': 1.0}}, 'joint_limits.slider_a.max_efort',
     'not a joint limit'),
    ({'slider_a': {'has_effort_limits': True}},
     'joint_limits.slider_a.max_effort',
     'needed where has_effort_limits is true'),
    ({'slider_a': {'max_effort': -1.0}}, 'joint_limits.slider_a.max_effort',
     'must be above 0'),
    ({'slider_a': {'max_effort': 'a lot'}},
     'joint_limits.slider_a.max_effort', 'must be a number'),
    ({'slider_a': {'max_effort': math.inf}},
     'joint_limits.slider_a.max_effort', 'must be finite'),
    ({'slider_a': {'has_effort_limits': 'yes', 'max_effort': 1.0}},
     'joint_limits.slider_a.has_effort_limits', 'must be true or false'),
    ({'slider_a': {'min_position': 0.1}}, 'joint_limits.slider_a',
     'position limits need both min_position and max_position'),
    ({'slider_a': 5}, 'joint_limits.slider_a', 'must be a mapping'),
))
def test_refusals_name_the_key(entries, key, words):
    """The key a field of the error, the message ``key: detail``."""
    with pytest.raises(LimitsError) as error:
        limits_from_mapping(entries)
    assert error.value.key == key
    assert error.value.detail.startswith(words)
    assert str(error.value) == f'{key}: {error.value.detail}'


def test_a_refusal_says_where_the_limits_were_read(tmp_path):
    path = tmp_path / 'joint_limits.yaml'
    path.write_text('joint_limits:\n  slider_b: {max_jerk: -2.0}\n')
    with pytest.raises(LimitsError) as error:
        load_limits(path)
    assert (error.value.source, error.value.key) == (
        str(path), 'joint_limits.slider_b.max_jerk')
    assert str(error.value) == f'{path}: joint_limits.slider_b.max_jerk: ' \
        + error.value.detail
    path.write_text('a: [')
    with pytest.raises(LimitsError) as error:
        load_limits(path)
    assert (error.value.source, error.value.key) == (str(path), '')
    assert error.value.detail.startswith('not valid YAML')
    path.write_text('planner:\n  ros__parameters:\n    joint_limits:\n'
                    '      slider_b: {max_jerk: -2.0}\n')
    with pytest.raises(LimitsError) as error:
        limits_from_params_file(ParametersFile.read(path))
    assert (error.value.source, error.value.key) == (
        f'{path}: planner', 'joint_limits.slider_b.max_jerk')


@pytest.mark.parametrize('reason, words, found', (
    (NO_SECTION, 'nothing for this node', True),
    (NOT_PARAMETERS, 'no section for the node', False)))
def test_a_missing_section_is_told_by_its_reason(monkeypatch, reason, words,
                                                 found):
    """No section: no limits from the file, whatever the message's words."""
    def section(self, node):
        raise ParametersFileError(self.path, reason, words)
    monkeypatch.setattr(ParametersFile, 'section', section)
    parameters = ParametersFile(CONFIG, {})
    if found:
        assert limits_from_params_file(parameters) is None
    else:
        with pytest.raises(ParametersFileError):
            limits_from_params_file(parameters)


def test_a_file_of_joint_limits(tmp_path):
    path = tmp_path / 'joint_limits.yaml'
    path.write_text('joint_limits:\n  slider_c:\n    has_effort_limits: true'
                    '\n    max_effort: 520.0\n')
    assert load_limits(path).effort[2] == 520.0
    # Numbers as rcl reads a parameters file: an exponent without a dot.
    for written, value in (('5e-1', 0.5), ('520', 520.0), ('.5', 0.5)):
        path.write_text('joint_limits:\n  slider_c:\n    max_effort: '
                        f'{written}\n')
        assert load_limits(path).effort[2] == value, written
    for text, words in (('a: [', 'not valid YAML'),
                        ('robot: {}', 'no top-level joint_limits'),
                        ('joint_limits: &a {}\nx: *a', 'aliases')):
        path.write_text(text)
        with pytest.raises(LimitsError, match=words):
            load_limits(path)
    with pytest.raises(LimitsError, match='No such file'):
        load_limits(tmp_path / 'missing.yaml')


def test_parameters_and_the_config_file_give_the_paper_robots_limits():
    flat = {f'joint_limits.{joint}.{key}': value
            for joint, entry in {'slider_a': {'max_effort': 650.0}}.items()
            for key, value in entry.items()}
    flat['robot.m5'] = 15.0
    assert limits_from_parameters(flat).effort[0] == 650.0
    config = ParametersFile.read(CONFIG)
    from_config = limits_from_params_file(config, 'planner')
    paper = paper_limits()
    for field in ('effort', 'velocity', 'acceleration', 'jerk'):
        assert np.array_equal(getattr(from_config, field),
                              getattr(paper, field)), field
    assert limits_from_params_file(config, 'mechanism_state_publisher') \
        is None
    # The simulator's drives: the same form, their own values.
    drives = limits_from_params_file(config, 'simulator')
    assert list(drives.effort) == [1000.0] * 3
    assert not np.isfinite(drives.velocity).any()


@pytest.mark.parametrize('text, words', (
    ('joint_limits:\n  slider_c:\n    max_effort: 520.0\n    max_effort: 5.0\n',
     "the key 'max_effort' appears twice"),
    ('joint_limits:\n  slider_c: {max_effort: 1.0}\n  slider_c: {}\n',
     "the key 'slider_c' appears twice"),
    ('joint_limits:\n  slider_c:\n    max_effort: 0x1F4\n',
     "max_effort: must be a number (decimal), got '0x1F4'"),
    ('joint_limits:\n  slider_c:\n    max_effort: 1_000\n',
     "must be a number (decimal), got '1_000'"),
    ('joint_limits:\n  slider_c:\n    max_effort: 8:20\n',
     "must be a number (decimal), got '8:20'"),
    ('joint_limits:\n  slider_c:\n    max_effort: .inf\n',
     "must be a number (decimal), got '.inf'"),
    ('joint_limits:\n  slider_c:\n    max_effort: 1e400\n', 'must be finite'),
    ('joint_limits:\n  slider_c:\n    max_effort: ' + '9' * 400 + '\n',
     'must be at most 1,000,000,000 in magnitude'),
    ('joint_limits:\n  slider_c:\n    min_position: -1.0e300\n'
     '    max_position: 0.3\n', 'min_position: must be at most '
     '1,000,000,000 in magnitude'),
))
def test_numbers_and_keys_follow_the_programs_rule(tmp_path, text, words):
    """Decimal, finite, at most 1e9 in magnitude; no key twice."""
    path = tmp_path / 'joint_limits.yaml'
    path.write_text(text)
    with pytest.raises(LimitsError) as error:
        load_limits(path)
    assert words in str(error.value)
    assert len(str(error.value)) < 300


def test_a_leading_zero_is_decimal(tmp_path):
    path = tmp_path / 'joint_limits.yaml'
    path.write_text('joint_limits:\n  slider_c:\n    max_effort: 0520\n')
    assert load_limits(path).effort[2] == 520.0
