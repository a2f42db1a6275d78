"""
Parameters files are read with rcl's rules into a validated ``Robot``.

The node's section may be keyed ``feedforward``, ``/feedforward`` or
``/**`` (the node's own section overriding ``/**``), parameters may be
nested or dotted, a double needs a decimal point or an exponent (``1e-3``
is a double, as in rcl), arrays must not mix integers and doubles,
booleans are not numbers, unknown ``robot.*`` names are refused and other
names are ignored; a key given twice in one mapping is refused. A robot the
tools write (``robot_file_text``, under ``/**``) is read by every node.
"""

import math
import os
import textwrap

from orthoglide_ros.formats.params_file import (
    load_parameters, load_robot, NO_SECTION, NOT_PARAMETERS, NOT_YAML,
    ParametersFileError, robot_file_text, robot_from_parameters, UNREADABLE)
from orthoglide_ros.model.robot import ParameterError, Robot
import pytest

CONFIG = os.path.join(os.path.dirname(__file__), os.pardir, 'config',
                      'orthoglide.yaml')


def write(tmp_path, text):
    path = tmp_path / 'params.yaml'
    path.write_text(textwrap.dedent(text), encoding='utf-8')
    return str(path)


def refused(tmp_path, text, name):
    with pytest.raises(ParameterError) as error:
        load_robot(write(tmp_path, text))
    assert error.value.name == f'robot.{name}'
    assert f'robot.{name}' in str(error.value)


def test_shipped_config_is_the_paper_robot():
    robot = load_robot(CONFIG)
    assert robot == Robot()
    assert robot.alpha == pytest.approx(math.pi / 4, abs=1e-15)
    assert robot.m4 == robot.m2 and robot.m6 == robot.m3
    assert robot.gravity == (0.0, 0.0, -9.81)


@pytest.mark.parametrize('key', ['feedforward', '/feedforward', '/**',
                                 "'/**'"])
def test_section_keys(tmp_path, key):
    text = f"""
    {key}:
      ros__parameters:
        robot:
          l3: 0.9
          m5: 18.0
    """
    robot = load_robot(write(tmp_path, text))
    assert robot.l3 == 0.9 and robot.m5 == 18.0
    assert robot.m1 == Robot().m1


@pytest.mark.parametrize('node', ['feedforward', 'simulator', 'planner',
                                  'mechanism_state_publisher'])
def test_a_robot_file_is_read_by_every_node(tmp_path, node):
    robot = Robot(m5=18.0, bar_length=(0.851, 0.85, 0.849))
    path = write(tmp_path, robot_file_text(robot, ['calibrated']))
    assert robot_from_parameters(load_parameters(path, node)) == robot


def test_node_section_overrides_wildcard(tmp_path):
    text = """
    feedforward:
      ros__parameters:
        robot.l3: 0.8
    /**:
      ros__parameters:
        robot:
          l3: 0.9
          m1: 0.5
    """
    robot = load_robot(write(tmp_path, text))
    assert robot.l3 == 0.8
    assert robot.m1 == 0.5


@pytest.mark.parametrize('text, reason, words', (
    ('some_other_node:\n  ros__parameters:\n    robot.l3: 0.8\n',
     NO_SECTION, 'no section for the node'),
    (None, UNREADABLE, 'No such file'),
    ('feedforward: [1, 2\n', NOT_YAML, 'not valid YAML'),
    ('- feedforward\n', NOT_PARAMETERS, 'not a ROS 2 parameters file'),
    ('feedforward: {robot: 1}\n', NOT_PARAMETERS,
     'has no ros__parameters mapping'),
))
def test_other_nodes_and_missing_sections(tmp_path, text, reason, words):
    """Each refusal's reason a field (NO_SECTION...), the path one too."""
    path = (str(tmp_path / 'missing.yaml') if text is None
            else write(tmp_path, text))
    with pytest.raises(ParametersFileError) as error:
        load_parameters(path)
    assert (error.value.reason, error.value.path) == (reason, path)
    assert words in error.value.detail
    assert str(error.value) == f'{path}: {error.value.detail}'


def test_nested_and_dotted_keys_mix(tmp_path):
    text = """
    feedforward:
      ros__parameters:
        robot.l3: 0.9
        robot:
          m5: 18.0
          m4: 0.25
        robot.gravity: [0.0, -9.81, 0.0]
    """
    robot = load_robot(write(tmp_path, text))
    assert (robot.l3, robot.m5, robot.m4) == (0.9, 18.0, 0.25)
    assert robot.gravity == (0.0, -9.81, 0.0)


def test_a_key_given_twice_is_refused(tmp_path):
    """YAML leaves a repeated key open (rcl keeps the last): refused here."""
    text = """
    feedforward:
      ros__parameters:
        robot:
          m5: 18.0
          m5: 15.0
    """
    with pytest.raises(ParametersFileError, match="the key 'm5' appears "
                       'twice'):
        load_robot(write(tmp_path, text))


def test_exponent_notation_is_a_double(tmp_path):
    text = """
    feedforward:
      ros__parameters:
        robot:
          l: 1e-1
          l1: 15E-2
          m1: 3.5e-1
          gravity: [0.0, 0.0, -981e-2]
    """
    robot = load_robot(write(tmp_path, text))
    assert robot.l == 0.1 and robot.l1 == 0.15 and robot.m1 == 0.35
    assert robot.gravity == (0.0, 0.0, -9.81)


@pytest.mark.parametrize('line, name', [
    ('l3: 1', 'l3'),
    ('m5: 15', 'm5'),
    ('l3: true', 'l3'),
    ("l3: '0.85'", 'l3'),
    ('gravity: [0, 0.0, -9.81]', 'gravity'),
    ('gravity: [0, 0, -10]', 'gravity'),
    ('gravity: [0.0, false, -9.81]', 'gravity'),
    ('gravity: 9.81', 'gravity'),
    ('stiffness: 1.0', 'stiffness'),
    ('l3: -0.85', 'l3'),
    ('alpha: 2.0', 'alpha'),
])
def test_refused_values_name_the_parameter(tmp_path, line, name):
    text = f"""
    feedforward:
      ros__parameters:
        robot:
          {line}
    """
    refused(tmp_path, text, name)


def test_non_robot_parameters_are_ignored(tmp_path):
    text = """
    feedforward:
      ros__parameters:
        rate_hz: 1000
        use_sim_time: false
        frames: [a, b]
        controller:
          gain: 3
        robot:
          m5: 16.0
    """
    assert load_robot(write(tmp_path, text)) == Robot(m5=16.0)


def test_robot_from_parameters_on_a_flat_dict():
    robot = robot_from_parameters({'robot.l3': 0.9, 'other': 1,
                                   'robot.gravity': [0.0, 0.0, -1.62]})
    assert robot.l3 == 0.9 and robot.gravity == (0.0, 0.0, -1.62)
    with pytest.raises(ParameterError):
        robot_from_parameters({'robot.m2': 1})


@pytest.mark.parametrize('node', ['simulator', 'tracking_controller',
                                  'mechanism_state_publisher', 'planner'])
def test_shipped_config_sections_hold_the_defaults(node):
    """
    The other nodes' sections parse by rcl's rules and are the defaults.

    So the file documents the defaults and cannot drift from them; the
    simulator's robot is absent from its section (the paper's by default).
    """
    if node == 'simulator':
        from orthoglide_ros.cores.simulator import PARAMETERS
    elif node == 'mechanism_state_publisher':
        from orthoglide_ros.cores.mechanism_state_publisher import PARAMETERS
    elif node == 'planner':
        from orthoglide_ros.cores.planner import PARAMETERS
    else:
        from orthoglide_ros.cores.tracking_controller import PARAMETERS
    specs, parse = PARAMETERS.specs, PARAMETERS.parse
    values = load_parameters(CONFIG, node)
    assert values and set(values) <= {s.name for s in specs}
    defaults = {s.name: s.default for s in specs if s.default is not None}
    assert all(values[name] == defaults[name] for name in values)
    assert parse(values) == parse({})


def test_node_section_by_name(tmp_path):
    """load_parameters(path, node) picks that node's section over /**."""
    path = write(tmp_path, """\
        /**:
          ros__parameters:
            rate_hz: 100.0
        simulator:
          ros__parameters:
            rate_hz: 500.0
        """)
    assert load_parameters(path, 'simulator') == {'rate_hz': 500.0}
    assert load_parameters(path, 'tracking_controller') == {'rate_hz': 100.0}
