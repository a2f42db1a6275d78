"""
One vocabulary for the actuators' limits: ros2_control's joint_limits.

Every node that bounds an actuator declares ``joint_limits.<joint>.*``
rows built by one function (``cores.parameters.joint_limit_specs``): the
planner every kind, the feedforward velocity and effort, the simulator and
the tracking controller effort; a row of the same name is the same row
(type, range, what it bounds) on every node, only its default and what the
node does beyond it its own. The names these replaced are refused wherever
they are given, naming the key that replaced them: by the table, and by a
node started with one in a parameters file or ``-p`` (exit 2, one line).
"""

import pytest

from orthoglide_ros.cores import feedforward, planner, simulator
from orthoglide_ros.cores import tracking_controller
from orthoglide_ros.cores.parameters import joint_limit, joint_limit_values

from node_checks import needs_scripts
from orthoglide_testing.processes import node_executable, run_to_exit

NODES = {'feedforward': feedforward, 'simulator': simulator,
         'tracking_controller': tracking_controller}
# Each node's names before joint_limits, and the key that replaced each.
RETIRED = [('feedforward', 'velocity_limit', '[1.0, 1.0, 1.0]',
            'max_velocity'),
           ('feedforward', 'force_limit', '[1.0, 1.0, 1.0]', 'max_effort'),
           ('feedforward', 'max_force', '500.0', 'max_effort'),
           ('simulator', 'force_limit', '500.0', 'max_effort'),
           ('tracking_controller', 'force_limit', '500.0', 'max_effort')]
START_WAIT = 30.0       # s for a refusing process to exit


def limit_rows(module):
    """Return ``{name: Spec}`` of a node's joint_limits rows."""
    return {s.name: s for s in module.PARAMETERS.specs
            if s.name.startswith('joint_limits.')}


@pytest.mark.parametrize('node', sorted(NODES))
def test_a_nodes_limit_rows_are_the_planners(node):
    theirs = limit_rows(planner)
    mine = limit_rows(NODES[node])
    assert mine and set(mine) <= set(theirs)
    for name, spec in mine.items():
        row = theirs[name]
        assert (spec.type, spec.range) == (row.type, row.range), name
        assert spec.description.startswith(row.description), name


def test_the_planner_declares_every_kind_for_every_actuator():
    kinds = ('velocity', 'acceleration', 'deceleration', 'jerk', 'effort')
    keys = {name.split('.', 2)[2] for name in limit_rows(planner)}
    assert keys == {f'max_{kind}' for kind in kinds} | {
        f'has_{kind}_limits' for kind in kinds}
    assert {name.split('.')[1] for name in limit_rows(planner)} == {
        'slider_a', 'slider_b', 'slider_c'}


def test_the_defaults_keep_each_nodes_bound():
    """The feedforward 10 kN (its plausibility bound), the drives 1000 N."""
    defaults = {node: module.PARAMETERS.parse({})
                for node, module in NODES.items()}
    assert joint_limit(defaults['feedforward'], 'max_effort') == \
        (10000.0,) * 3
    assert joint_limit(defaults['feedforward'], 'max_velocity') == \
        (float('inf'),) * 3
    for node in ('simulator', 'tracking_controller'):
        assert joint_limit(defaults[node], 'max_effort') == (1000.0,) * 3


@pytest.mark.parametrize('node', sorted(NODES) + ['planner'])
def test_a_flag_without_its_limit_is_refused(node):
    """One rule for every node's rows, the planner's too: one message."""
    values = joint_limit_values('max_effort', 100.0)
    values['joint_limits.slider_b.max_effort'] = 0.0
    with pytest.raises(ValueError, match=(
            r'^joint_limits\.slider_b\.max_effort: must be above 0 where '
            'has_effort_limits is true, got 0.0$')):
        dict(NODES, planner=planner)[node].PARAMETERS.parse(values)


@pytest.mark.parametrize('node, old, value, new', RETIRED)
def test_a_retired_name_is_refused_naming_its_key(node, old, value, new):
    with pytest.raises(ValueError, match=(
            f'^{old}: no longer a parameter; use '
            fr'joint_limits\.<joint>\.{new} ')):
        NODES[node].PARAMETERS.parse({old: 1.0})


@pytest.mark.ros
@needs_scripts(*NODES)
@pytest.mark.parametrize('node, old, value, new', RETIRED)
def test_a_node_given_a_retired_name_exits_2_naming_its_key(
        tmp_path, node, old, value, new):
    """In a parameters file: one FATAL line, exit 2, nothing else."""
    path = tmp_path / 'old.yaml'
    path.write_text(f'{node}:\n  ros__parameters:\n    {old}: {value}\n')
    code, stderr = run_to_exit(['--ros-args', '--params-file', str(path)],
                               [node_executable(node)], START_WAIT)
    lines = stderr.strip().splitlines()
    assert code == 2 and len(lines) == 1, (code, stderr)
    assert '[FATAL]' in lines[0] and f'{old}: no longer a parameter; use ' \
        f'joint_limits.<joint>.{new} ' in lines[0], stderr


@pytest.mark.ros
@needs_scripts('simulator')
def test_a_retired_name_given_by_p_is_refused_too():
    code, stderr = run_to_exit(
        ['--ros-args', '-p', 'force_limit:=500.0'],
        [node_executable('simulator')], START_WAIT)
    assert code == 2 and len(stderr.strip().splitlines()) == 1, stderr
    assert 'joint_limits.<joint>.max_effort' in stderr
