"""
The planner node's core without DDS: its parameters, rules and counters.

The ``joint_limits.*`` parameters give the limits of ros2_control's form
(a flag true with its maximum 0: refused, naming the maximum), the
defaults are the paper robot's; a path is planned from rest at its first
pose to rest at its last; every refusal is counted by reason, names the
pose, and publishes nothing; inactive, nothing is planned.
"""

import math

import numpy as np
import pytest

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.planner import limits_of, PARAMETERS, Planner
from orthoglide_ros.model.robot import ParameterError
from orthoglide_ros.planning.limits import paper_limits

LINE = np.array([(0.0, 0.0, 0.0), (0.02, 0.0, 0.0), (0.02, 0.02, 0.0)])


def test_defaults_are_the_paper_robots_limits():
    limits = limits_of(PARAMETERS.parse({}))
    paper = paper_limits()
    for name in ('effort', 'velocity', 'acceleration', 'deceleration',
                 'jerk'):
        assert np.array_equal(getattr(limits, name), getattr(paper, name))


def test_a_flag_without_its_value_is_refused():
    with pytest.raises(ParameterError) as error:
        PARAMETERS.parse({'joint_limits.slider_b.has_jerk_limits': True})
    assert error.value.name == 'joint_limits.slider_b.max_jerk'
    assert 'must be above 0' in str(error.value)
    settings = PARAMETERS.parse({'joint_limits.slider_b.has_jerk_limits':
                                 True, 'joint_limits.slider_b.max_jerk':
                                 500.0})
    assert limits_of(settings).jerk[1] == 500.0


def test_a_path_is_planned_from_rest_to_rest():
    core = Planner(PARAMETERS.parse({}))
    frame, motion = core.path('base_link', ('', 'base_link', ''), LINE, 0.0)
    assert frame == 'base_link'
    assert np.allclose(motion.position[[0, -1]], LINE[[0, -1]], atol=1e-12)
    assert np.all(motion.velocity[[0, -1]] == 0.0)
    assert np.allclose(np.diff(motion.t), 1e-3)
    assert core.planned == 1 and core.last_points == len(motion.t)


@pytest.mark.parametrize('frame, frames, points, reason, words', (
    ('map', (), LINE, 'frame', "the path in frame 'map'"),
    ('', ('', 'odom', ''), LINE, 'frame', "pose 2 in frame 'odom'"),
    ('', (), np.array([[0.0, 0.0, 0.0], [math.nan, 0, 0]]), 'non_finite',
     'pose 2'),
    ('', (), LINE[:1], 'too_few_poses', '1 pose(s)'),
    ('', (), np.zeros((3, 3)), 'too_few_poses', 'zero-length'),
    ('', (), np.array([[0.0, 0.0, 0.0], [0.9, 0.0, 0.0]]), 'infeasible',
     'pose 2: the path at ['),
))
def test_refusals_are_counted_by_reason(frame, frames, points, reason,
                                        words):
    core = Planner(PARAMETERS.parse({}))
    with pytest.raises(Rejected) as error:
        core.path(frame, frames, points, 0.0)
    assert error.value.reason == reason and words in str(error.value)
    assert core.rejected[reason] == 1 and core.planned == 0


def test_statics_beyond_max_effort_name_the_pose_and_joint():
    core = Planner(PARAMETERS.parse({
        'joint_limits.slider_c.max_effort': 200.0}))
    with pytest.raises(Rejected) as error:
        core.path('', (), LINE, 0.0)
    assert 'pose 2: at [' in str(error.value)
    assert 'slider_c needs 256.5' in str(error.value)


def test_inactive_plans_nothing():
    core = Planner(PARAMETERS.parse({}))
    core.deactivate()
    assert core.path('', (), LINE, 0.0) is None
    assert core.withheld == 1 and core.planned == 0
