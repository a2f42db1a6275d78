"""
The mechanism state publisher's logic without ROS: sliders in, every joint out.

:func:`joint_state` solves every non-fixed joint of the Orthoglide's cut-tree
URDF from the three sliders in closed form: G by the forward kinematics
(eq. 14), its velocity by eq. (15), each leg's angles and rates by eqs. (9)
and (13). :class:`MechanismState` is the node's core: its rules and
reasons are in ``doc/mechanism_state_publisher.md``.
"""

from collections import namedtuple
import math

from orthoglide_ros.model import bodies, mechanics
from orthoglide_ros.cores.inputs import (check_stamp, read_joint_state,
                                         Rejected)
from orthoglide_ros.model.mechanics import DEFAULT_SINGULARITY_MARGIN, ZERO
from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.parameters import (joint_names_spec,
                                             singularity_margin_spec, Table)
from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.status import OK
from orthoglide_ros.model.urdf import moving_joints, RATES

REASONS = ('stamp', 'missing_joint', 'malformed', 'missing_position',
           'non_finite', 'unreachable', 'singular', 'overflow', 'oversize')

PARAMETERS = Table('MechanismStateSettings', (
    joint_names_spec(
        'names of the prismatic joints of actuators A, B, C: read from '
        'joint_states by name, and the sliders\' names in the URDF and in '
        'mechanism/joint_states'),
    singularity_margin_spec(
        'smallest singularity distance min(alpha_i / L_i, 1 / '
        'kappa_F(J_lambda)) of a published state; nearer a singularity '
        'the joint state is refused (singular)'),
    *realtime.SPECS,
), robot=True)

MechanismJoints = namedtuple('MechanismJoints', 'names position velocity')
MechanismJoints.__doc__ = """Every non-fixed joint of the URDF.

``names`` (:func:`urdf.moving_joints` order), ``position`` (m for the
sliders, rad for the revolute joints) and ``velocity`` (m/s, rad/s; an
empty tuple when the input had none), tuples of equal length."""


def joint_state(robot, joint_names, lam, lambdadot=None,
                margin=DEFAULT_SINGULARITY_MARGIN):
    """
    Solve every non-fixed joint of the URDF from the three sliders.

    ``lam``: lambda_A, lambda_B, lambda_C (m); ``lambdadot`` (m/s) or None.
    Returns :class:`MechanismJoints` with the sliders named ``joint_names``
    (their values are the inputs, unchanged). Raises
    :class:`mechanics.WorkspaceError` (``non_finite``, ``unreachable``,
    ``singular``, ``overflow``) where there is no such state.

    >>> from orthoglide_ros.model.robot import Robot
    >>> state = joint_state(Robot(), ('a', 'b', 'c'), (0.0, 0.0, 0.0))
    >>> state.names[3:6], state.position[3:6]
    (('a_phi21', 'a_phi32', 'a_phi62'), (0.0, 0.0, 0.0))
    """
    position = tuple(mechanics.forward_kinematics(robot, lam).tolist())
    velocity = ZERO if lambdadot is None else \
        mechanics.platform_velocity(robot, position, lambdadot)
    legs = bodies.leg_joints(robot, position, velocity, margin)
    joints = moving_joints(joint_names)
    values = [getattr(legs[leg], variable) for _, leg, variable in joints]
    values[:3] = lam
    rates = ()
    # (v + 0.0 below: a -0.0 of the kinematics is published as 0.0.)
    if lambdadot is not None:
        rates = [getattr(legs[leg], RATES[variable])
                 for _, leg, variable in joints]
        rates[:3] = lambdadot
        rates = tuple(float(v) + 0.0 for v in rates)
        if not all(math.isfinite(v) for v in rates):
            raise mechanics.WorkspaceError('overflow', (
                f'lambdadot {mechanics.format_vector(lambdadot)} m/s gives '
                'joint rates that are not finite'))
    return MechanismJoints(tuple(name for name, _, _ in joints),
                           tuple(float(v) + 0.0 for v in values), rates)


class MechanismState(Core):
    """
    Inputs, rules and counters of the mechanism state publisher.

    The core of :mod:`orthoglide_ros.cores.core`: every method takes
    ``now``, a monotonic time in seconds, so tests can drive time.
    :meth:`joint_state` returns what to publish or raises
    :class:`Rejected`, already counted.
    """

    INPUTS = ('joint_states',)
    REASONS = REASONS

    def __init__(self, settings, now=0.0):
        super().__init__(settings, now)
        self.published = 0
        self.withheld = 0               # not published while inactive
        self.latest = None              # the last MechanismJoints published
        self.latest_arrival = None

    def joint_state(self, stamp, frame, names, position, velocity, effort,
                    now):
        """
        Take one JointState; return ``(stamp, frame, MechanismJoints)``.

        The message's fields, as :func:`orthoglide_ros.formats.cdr.joint_state`
        reads them (its efforts are not used); the output keeps its stamp
        and frame. None (withheld) while inactive.
        """
        self.received['joint_states'] += 1
        settings = self.settings
        try:
            check_stamp(stamp, zero_allowed=True)
            values = read_joint_state(settings.joint_names, names, position,
                                      velocity, (), False, True)
            try:
                state = joint_state(settings.robot, settings.joint_names,
                                    values.position, values.velocity,
                                    settings.singularity_margin)
            except mechanics.WorkspaceError as error:
                raise Rejected(error.reason, (
                    f'lambda {mechanics.format_vector(values.position)} m: '
                    f'{error}')) from None
        except Rejected as rejection:
            self.count('joint_states', rejection)
            raise
        if not self.active:
            self.withheld += 1
            return None
        self.published += 1
        self.latest, self.latest_arrival = state, now
        return stamp, frame, state

    # Status: ERROR after an internal error; WARN when joint states were
    # rejected in the period (the message gives the last reason); else OK
    # (``waiting for joint states`` until one came).
    def period_counters(self):
        """Return the counters of the period's rates."""
        return dict(published=self.published)

    def status_rules(self, now, seconds, increases):
        """Return the rejections and the wait steps."""
        return (
            self.rejected_rule(increases, 'joint state(s)'),
            (self.received['joint_states'] == 0, OK,
             'waiting for joint states'))

    def values(self, now, seconds, increases):
        """
        Return the rate, the counters, the margin and the robot's legs.

        ``legs``: ``as drawn`` (the installed URDF is the robot's) or
        ``as built`` (robot_state_publisher needs the URDF of the same
        ``robot.*``, doc/mechanism_state_publisher.md#a-robot-as-built).
        """
        age = math.nan if self.latest_arrival is None \
            else now - self.latest_arrival
        return [
            ('publish rate (Hz)', increases['published'] / seconds),
            ('joint states published', self.published),
            ('joint states received', self.received['joint_states']),
            ('outputs withheld (inactive)', self.withheld),
            ('time since last published (s)', age),
            ('singularity margin', self.settings.singularity_margin),
            ('legs', 'as drawn' if self.settings.robot.as_drawn
             else 'as built'),
        ]
