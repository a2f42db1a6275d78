"""
The mechanism state publisher's logic without ROS: sliders in, every joint out.

The URDF of the Orthoglide (:mod:`orthoglide_ros.model.urdf`) is a cut tree: the
three slider positions alone do not tell ``robot_state_publisher`` where the
bars are. :func:`joint_state` solves every non-fixed joint of the URDF from
the sliders in closed form: the platform centre G by the forward kinematics
(eq. 14, :func:`mechanics.forward_kinematics`), its velocity by eq. (15)
(:func:`mechanics.platform_velocity`), then each leg's angles and rates by
the inverse kinematics (eqs. 9 and 13, :func:`mechanics.leg_joints`). The
result closes every cut of the URDF (``x_leg_end`` on ``x_platform_mount``,
``x_a7_bar`` on ``x_a7_rod``). The ROS node
(``mechanism_state_publisher_node``) only converts messages, so every rule
below is testable without DDS.

Rules (``doc/mechanism_state_publisher.md`` states them for users):

- Joint states are matched by name, in any order; joints not in
  ``joint_names`` are ignored. Positions are needed, velocities are used
  when the message has them (then the output has velocities too).
- A message is rejected, counted by reason and publishes nothing when one
  of ``joint_names`` is absent (``missing_joint``), names repeat or an
  array is neither empty nor as long as the names (``malformed``), it has
  no positions (``missing_position``), a value read is NaN or infinite
  (``non_finite``), the sliders have no platform position
  (``unreachable``), the platform is nearer a singularity than
  ``singularity_margin`` (``singular``) or a rate overflows
  (``overflow``). Messages refused before they are read count as
  ``oversize`` or ``malformed``.
- The output carries the input's stamp and frame id unchanged: the sliders
  of the input are the robot's state at that stamp, and so is every joint
  solved from them.
"""

from collections import namedtuple
import math

from orthoglide_ros.model import mechanics
from orthoglide_ros.cores.inputs import read_joint_state, Rejected
from orthoglide_ros.model.mechanics import DEFAULT_SINGULARITY_MARGIN, ZERO
from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.parameters import joint_names_spec, Spec, Table
from orthoglide_ros.cores.status import first, OK, Period, Status, WARN
from orthoglide_ros.model.urdf import moving_joints, RATES

REASONS = ('missing_joint', 'malformed', 'missing_position', 'non_finite',
           'unreachable', 'singular', 'overflow', 'oversize')

PARAMETERS = Table('MechanismStateSettings', (
    joint_names_spec(
        'names of the prismatic joints of actuators A, B, C: read from '
        'joint_states by name, and the sliders\' names in the URDF and in '
        'mechanism/joint_states'),
    Spec('singularity_margin', 'double', DEFAULT_SINGULARITY_MARGIN,
         'smallest singularity distance min(alpha_i / l3, 1 / '
         'kappa_F(J_lambda)) of a published state; nearer a singularity '
         'the joint state is refused (singular)', (0.0, 0.99)),
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
    legs = mechanics.leg_joints(robot, position, velocity, margin)
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


class MechanismState:
    """
    Inputs, rules and counters of the mechanism state publisher.

    Every method takes ``now``, a monotonic time in seconds, so tests can
    drive time. :meth:`joint_state` returns the :class:`MechanismJoints` to
    publish or raises :class:`Rejected`, already counted.
    """

    def __init__(self, settings, now=0.0):
        self.settings = settings
        self.received = 0
        self.published = 0
        self.rejected = dict.fromkeys(REASONS, 0)
        self.latest = None              # the last MechanismJoints published
        self.latest_arrival = None
        self.last_rejection = None      # the last Rejected
        self._period = Period(now)

    def configure(self, settings):
        """Use new settings from the next message on."""
        self.settings = settings

    def reject(self, source, rejection):
        """Count a message refused before it was read (one input)."""
        self.received += 1
        self._count(rejection)

    def joint_state(self, names, position, velocity, now):
        """
        Take one JointState's arrays; return the :class:`MechanismJoints`.

        ``names``, ``position``, ``velocity``: the message's sequences (its
        efforts are not used).
        """
        self.received += 1
        settings = self.settings
        try:
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
            self._count(rejection)
            raise
        self.published += 1
        self.latest, self.latest_arrival = state, now
        return state

    def _count(self, rejection):
        self.rejected[rejection.reason] += 1
        self.last_rejection = rejection

    def status(self, now, internal_errors=0):
        """
        Return the :class:`Status` of the period ending at ``now``.

        ERROR after an internal error; WARN when joint states were rejected
        in the period (the message gives the last reason); else OK
        (``waiting for joint states`` until one came).
        """
        rejected = sum(self.rejected.values())
        seconds, new = self._period.advance(
            now, published=self.published, rejected=rejected)
        last = self.last_rejection
        level, message = first(
            internal_errors,
            (new['rejected'], WARN,
             f'{new["rejected"]} joint state(s) rejected in the last '
             f'period, the last ({last.reason if last else ""}): {last}'),
            (self.received == 0, OK, 'waiting for joint states'))
        age = math.nan if self.latest_arrival is None \
            else now - self.latest_arrival
        values = [
            ('publish rate (Hz)', new['published'] / seconds),
            ('joint states published', self.published),
            ('joint states received', self.received),
            ('time since last published (s)', age),
            ('singularity margin', self.settings.singularity_margin),
            ('internal errors', internal_errors),
        ]
        values += [(f'rejected {r}', self.rejected[r]) for r in REASONS]
        return Status(level, message, values)
