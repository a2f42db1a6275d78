"""
The planner node's core without DDS: its parameters, rules and counters.

The ``joint_limits.*`` parameters give the limits of ros2_control's form
(a flag true with its maximum 0: refused, naming the maximum), the
defaults are the paper robot's; a path is planned from rest at its first
pose to rest at its last; every refusal is counted by reason, names the
pose, and publishes nothing; inactive, nothing is planned. A pose far
away, a path beyond the node's memory, a motion beyond the output message
and a plan past its time are refused, and the next path planned.
"""

import math

import numpy as np
import pytest

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.planner import limits_of, PARAMETERS, Planner
from orthoglide_ros.model.robot import ParameterError
from orthoglide_ros.planning.limits import paper_limits
from orthoglide_testing.chord_programs import bulge_points

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
    # The first pose: the path's start, where the statics are refused.
    assert 'pose 1: the start of the path at [0, 0, 0] m' in str(error.value)
    assert 'slider_c needs 256.5' in str(error.value)


def test_inactive_plans_nothing():
    core = Planner(PARAMETERS.parse({}))
    core.deactivate()
    assert core.path('', (), LINE, 0.0) is None
    assert core.withheld == 1 and core.planned == 0


def test_a_pose_far_away_is_refused_not_an_internal_error():
    core = Planner(PARAMETERS.parse({}))
    with pytest.raises(Rejected) as error:
        core.path('', (), np.array([(0.0, 0.0, 0.0), (1e300, 0.0, 0.0)]),
                  0.0)
    assert error.value.reason == 'infeasible'
    assert str(error.value) == ('pose 2: the point [1e+300, 0.0, 0.0] m is '
                                'beyond 1,000,000,000 m')


def test_a_straight_path_of_many_poses_is_one_line():
    core = Planner(PARAMETERS.parse({}))
    points = np.linspace((0.0, 0.0, 0.0), (0.07, -0.03, 0.05), 100)
    _, motion = core.path('', (), points, 0.0)
    speed = np.linalg.norm(motion.velocity, axis=1)
    assert (speed[1:-1] > 0.0).all()
    assert np.allclose(motion.position[-1], points[-1], atol=1e-12)


def test_a_path_beyond_the_nodes_memory_is_refused_before_it_is_made():
    """10^5 poses with corners: counted before any piece is made."""
    import tracemalloc
    core = Planner(PARAMETERS.parse({}))
    points = np.random.default_rng(0).uniform(-0.1, 0.1, (100_000, 3))
    tracemalloc.start()
    try:
        with pytest.raises(Rejected) as error:
            core.path('', (), points, 0.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert error.value.reason == 'oversize'
    assert str(error.value) == ('100000 points make a path of 199997 pieces '
                                'at least (lines and corner blends): more '
                                'than 78769')
    assert peak < 50e6
    assert core.path('', (), LINE, 0.0) is not None     # the next one


def test_a_motion_longer_than_the_output_message_holds_is_refused():
    """At 0.2 mm/s, 5 cm: 250 s, 250,000 points, a 46 MB message."""
    core = Planner(PARAMETERS.parse({'max_speed': 0.0002}))
    with pytest.raises(Rejected) as error:
        core.path('', (), np.array([(0.0, 0.0, 0.0), (0.05, 0.0, 0.0)]),
                  0.0)
    assert error.value.reason == 'oversize'
    assert 'samples at 1000 Hz, more than the 45,589 this planner may ' \
        'hold' in str(error.value)


@pytest.mark.parametrize('frame', ('base_link', 'f' * 5000))
def test_the_longest_motion_fits_the_feedforwards_input(frame):
    from orthoglide_ros.cores.inputs import CARTESIAN_TRAJECTORY_BYTES
    from orthoglide_ros.cores.planner import max_points
    from orthoglide_ros.formats import cdr
    n = max_points(frame)
    data = cdr.multi_dof_trajectory(
        (0, 0), frame, ('platform',), np.zeros((n, 2), dtype=np.int64),
        *(np.zeros((n, 3)) for _ in range(3)))
    assert len(data) <= CARTESIAN_TRAJECTORY_BYTES
    assert len(data) + 2 * cdr.MULTI_DOF_POINT_BYTES \
        > CARTESIAN_TRAJECTORY_BYTES


def test_a_plan_past_max_planning_time_is_refused_and_the_next_planned():
    """A circle of 2000 poses takes 50 times 0.01 s here."""
    core = Planner(PARAMETERS.parse({'max_planning_time': 0.01}))
    angles = np.linspace(0.0, 2.0 * math.pi, 2000)
    circle = 0.1 * np.stack((np.cos(angles), np.sin(angles),
                             np.zeros_like(angles)), 1)
    with pytest.raises(Rejected) as error:
        core.path('', (), circle, 0.0)
    assert error.value.reason == 'timeout'
    assert str(error.value) == 'planning took more than 0.01 s'
    core.configure(PARAMETERS.parse({}))
    assert core.path('', (), circle, 0.0) is not None


def planner_path(kind):
    """
    Return the poses (m) of a Path a planner might send at its worst.

    ``reverse``: out along an arc and back; ``twice``: every pose sent
    twice; ``micro``: 20,000 poses 1 um apart; ``dense``: a 10^5-pose
    circle; ``bulge``: poses within the workspace whose curve is not.
    """
    if kind == 'bulge':
        return bulge_points()
    count, sweep = {'micro': (20_000, 1.0), 'dense': (100_000, 2 * math.pi)
                    }.get(kind, (40, math.pi))
    a = np.linspace(0.0, sweep, count + 1)
    radius = 0.1 if kind == 'dense' else 0.02
    points = radius * np.stack((np.cos(a), np.sin(a), 0 * a), 1)
    if kind == 'reverse':
        points = np.vstack((points, points[::-1][1:]))
    if kind == 'twice':
        points = np.repeat(points, 2, axis=0)
    return points


@pytest.mark.parametrize('kind', ('reverse', 'twice', 'micro', pytest.param(
    'dense', marks=pytest.mark.slow), 'bulge'))
def test_paths_as_planners_send_them_plan_or_are_refused(kind):
    """
    A plan from the first pose to the last, or a refusal naming a pose.

    The dense circle plans in about 2 s of CPU (2026-12-06); the curve
    that leaves the workspace between poses 10 and 11 is refused naming
    pose 11 (``infeasible``), and the next path planned.
    """
    core = Planner(PARAMETERS.parse({}))
    points = planner_path(kind)
    if kind == 'bulge':
        with pytest.raises(Rejected) as error:
            core.path('', (), points, 0.0)
        assert error.value.reason == 'infeasible'
        assert str(error.value).startswith('pose 11: the path at [')
        assert core.path('', (), LINE, 0.0) is not None
        return
    _, motion = core.path('', (), points, 0.0)
    assert np.allclose(motion.position[[0, -1]], points[[0, -1]], rtol=0,
                       atol=1e-12)
    assert np.all(motion.velocity[[0, -1]] == 0.0)
