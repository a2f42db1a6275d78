"""
The simulator's logic without ROS: actuator forces in, measured state out.

:class:`Simulator` steps a plant (:class:`plant.Plant` or
:class:`mujoco_plant.MujocoPlant`) on a fixed grid of ``1 / rate_hz`` s
(doc/simulator.md). Units: m, m/s, N, s.
"""

from collections import namedtuple
import math
import time

from orthoglide_ros.model import mechanics, mujoco_plant
from orthoglide_ros.cores.inputs import joint_columns, Rejected
from orthoglide_ros.model.mechanics import format_vector, ZERO
from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.parameters import (
    arrival_timeout_spec, at_most, base_frame_spec, every_joint, joint_limit,
    joint_limit_name, joint_limit_specs, joint_limits_rule, joint_names_spec,
    one_of, ParameterError, singularity_margin_spec, Spec, Table, triple)
from orthoglide_ros.model.plant import Diverged, Plant
from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.status import ERROR, OK, WARN
from orthoglide_ros.formats.text import read_text

HELD, RUNNING, STOPPED, DIVERGED = 'held', 'running', 'stopped', 'diverged'
# Why a command was rejected: the keys of Simulator.rejected.
COMMAND_REASONS = ('length', 'non_finite', 'malformed', 'oversize',
                   'missing_joint')
# Steps of the grid made at once to catch up with it (10 ms at 1 kHz);
# beyond, the missed time is dropped (an overrun: slower than real time).
MAX_CATCH_UP = 10
# Share of a status period whose time may be dropped before the status
# says the simulation runs slower than real time.
SLOW_FRACTION = 0.1


def _initial_position_in_workspace(settings):
    """Refuse an initial position outside its own set's workspace."""
    try:
        mechanics.solve(settings.robot, settings.initial_position, ZERO,
                        ZERO, settings.singularity_margin)
    except mechanics.WorkspaceError as error:
        raise ParameterError('initial_position', (
            f'{list(settings.initial_position)} m is outside the workspace '
            f'of singularity_margin {settings.singularity_margin:g} '
            f'({error.reason}): {error}')) from None


ENGINES = ('builtin', 'mujoco')


def _engine(value):
    one_of(ENGINES)(value)
    if value == 'mujoco' and mujoco_plant.unavailable():
        raise ValueError(mujoco_plant.unavailable())
    return value


# The plant's drives: each saturates at 1000 N (model.urdf.SLIDER_EFFORT,
# the URDF's effort limit of the sliders).
DRIVES = every_joint(max_effort=1000.0)
# Longest MJCF file read (bytes), as a parameters file.
MJCF_FILE_BYTES = 1 << 20


def _mjcf_file(path):
    """Read and check an MJCF file (an empty path: none); return its text."""
    if not path:
        return ''
    if mujoco_plant.unavailable():
        raise ValueError(mujoco_plant.unavailable())
    try:
        text = read_text(path, MJCF_FILE_BYTES)
        mujoco_plant.check_model(text)
    except ValueError as error:
        raise ValueError(f'{path!r}: {error}') from None
    return text


def _mjcf_file_needs_mujoco(settings):
    if settings.mjcf_file and settings.engine != 'mujoco':
        raise ParameterError('mjcf_file', 'needs engine mujoco')


def _mjcf_file_has_the_robots_legs(settings):
    """Refuse an mjcf_file whose legs are not robot.*'s (the workspace's)."""
    if settings.mjcf_file:
        try:
            mujoco_plant.check_legs(settings.mjcf_file, settings.robot)
        except ValueError as error:
            raise ParameterError('mjcf_file', str(error)) from None


def _timeout_of_a_step_at_least(settings):
    if settings.command_timeout * settings.rate_hz < 1.0:
        raise ParameterError('command_timeout', (
            f'must last at least one step, 1/rate_hz = '
            f'{1.0 / settings.rate_hz:g} s, got {settings.command_timeout} '
            's'))


PARAMETERS = Table('SimulatorSettings', (
    Spec('rate_hz', 'double', 1000.0,
         'simulation steps per second (Hz): each step integrates 1/rate_hz s '
         'of motion (RK4, command held over the step)', (1.0, 10000.0)),
    Spec('publish_rate_hz', 'double', 0.0,
         'joint states and poses published per second (Hz), at most '
         'rate_hz: the state of the first step at or after each 1 / '
         'publish_rate_hz; 0.0: every step', (0.0, 10000.0)),
    Spec('initial_position', 'double_array', [0.0, 0.0, 0.0],
         'position of the platform centre G (m, base frame) at start and '
         'after ~/reset, at rest; must lie in the workspace (applies at the '
         'next reset)', check=triple),
    arrival_timeout_spec('command_timeout', 0.1, 0.001,
                         'without a valid command after which a running '
                         'simulation brakes: back to held, velocity zero; '
                         'at least one step (1/rate_hz)'),
    *joint_limit_specs(DRIVES, {
        'max_effort': 'a command beyond it is clipped to it, as a drive '
                      'saturates, and the step counted'}),
    singularity_margin_spec(
        'workspace limit: smallest singularity distance a step may reach, '
        'min(alpha_i / L_i, 1 / kappa_F(J_lambda)); a step beyond it stops '
        'the simulation (applies at the next reset)', low=0.01),
    joint_names_spec('names of the prismatic joints of actuators A, B, C '
                     'in joint_states'),
    base_frame_spec('frame_id of platform/pose (the paper\'s frame 0)'),
    Spec('engine', 'string', 'builtin',
         'what integrates the plant: builtin (the package\'s forward '
         'dynamics, RK4) or mujoco (the robot\'s MJCF in MuJoCo); applies '
         'at the next reset', check=_engine),
    Spec('mjcf_file', 'string', '',
         'with engine mujoco, an MJCF file to simulate instead of the model '
         'built from robot.*: one of orthoglide mjcf (its names, the '
         'robot.* lengths; its masses, friction and armature its own); '
         'applies at the next reset', check=_mjcf_file),
    *realtime.SPECS,
), rules=(_mjcf_file_needs_mujoco, _mjcf_file_has_the_robots_legs,
          _initial_position_in_workspace,
          at_most('publish_rate_hz', 'rate_hz', 'Hz'),
          _timeout_of_a_step_at_least, joint_limits_rule),
    robot=True, retired={'force_limit': joint_limit_name('max_effort')})

Tick = namedtuple('Tick', (
    'state', 'position', 'lambda_', 'lambdadot', 'effort', 'event'))
Tick.__doc__ = """What one :meth:`Simulator.tick` publishes.

``position``: G (m, frame 0); ``lambda_`` (m) and ``lambdadot`` (m/s): the
joint state; ``effort``: the forces applied over the step after clipping
(N), zeros when no step was made; ``event``: None, ``'timeout'`` (this tick
went back to held), ``'stopped'`` (this tick's step was refused) or
``'diverged'`` (this tick's step could not be integrated).
"""


class Simulator(Core):
    """
    The simulated Orthoglide behind the ``simulator`` node: a state machine.

    :meth:`command` takes a command, :meth:`tick` makes one step (or none)
    and returns what to publish, :meth:`reset` starts over; ``now`` is a
    monotonic time (s). ``plant``: the :class:`plant.Plant`; ``state``:
    ``held``, ``running``, ``stopped`` or ``diverged``; ``timed_out``: the
    last ``running`` ended by the command timeout; ``stop_reason`` and
    ``stop_message``: why it stopped or diverged. The counters are the
    diagnostics' values (doc/simulator.md#diagnostics); ``step_ns_total`` /
    ``step_ns_max``: CPU of :meth:`Plant.step`.

    >>> sim = Simulator(PARAMETERS.parse({}))
    >>> sim.state, sim.tick(0.0).effort
    ('held', (0.0, 0.0, 0.0))
    >>> sim.command([0.0, 0.0, 256.5315], 0.0)
    >>> sim.state
    'running'
    >>> sim.tick(0.001).effort, sim.plant.time
    ((0.0, 0.0, 256.5315), 0.001)
    """

    INPUTS = ('commands', 'joint_commands')
    REASONS = COMMAND_REASONS
    INACTIVE = 'inactive: held, commands counted and not applied'

    def __init__(self, settings, now=0.0):
        super().__init__(settings, now)
        self.valid = 0
        self.ignored = 0
        self.withheld = 0
        self.steps = 0
        self.divergences = 0
        self.clipped = 0
        self.timeouts = 0
        self.stall_brakes = 0       # of the timeouts, by this process's stall
        self.step_ns_total = 0
        self.step_ns_max = 0
        self.published = 0
        self.overruns = 0
        self.dropped_time = 0.0     # s of the grid skipped by overruns
        self.latest_arrival = None
        self._grid = None           # time of the next step due (s)
        self._next_publish = None   # grid time of the next state published
        self._model = None
        self.reset()

    # Settings -------------------------------------------------------------
    def configure(self, settings):
        """
        Use new settings: the live ones at once, the plant's at reset.

        ``joint_limits.*`` and ``robot.payload`` (a part picked up or put
        down: the plant carries it) apply from the next step; the rest of
        ``robot``, ``initial_position`` and ``singularity_margin`` wait for
        :meth:`reset` (see :attr:`pending_reset`).
        """
        old, self.settings = self.settings, settings
        self.plant.force_limit = joint_limit(settings, 'max_effort')
        if settings.robot.payload != self.plant.robot.payload:
            self.plant.carry(settings.robot.payload)
        if settings.rate_hz != old.rate_hz:
            self._grid = None
        if settings.rate_hz != old.rate_hz or \
                settings.publish_rate_hz != old.publish_rate_hz:
            self._next_publish = None

    @property
    def pending_reset(self):
        """Whether plant parameters changed since the last reset."""
        return _plant_model(self.settings) != self._model

    def activate(self):
        """Take commands and step again, on a new grid from the next call."""
        self.active = True
        self._grid = None

    def deactivate(self):
        """Hold: brake a running platform; no step until activated."""
        self.active = False
        if self.state == RUNNING:
            self._brake(HELD)

    # Inputs ---------------------------------------------------------------
    def command(self, forces, now):
        """
        Take a command ``[f_A, f_B, f_C]`` (N) of input ``commands``.

        Raises :class:`Rejected` (counted) unless it is three finite
        numbers. A valid command becomes the one held over the next steps
        and starts (or resumes) ``running``; while ``stopped`` or
        ``diverged`` it is counted in ``ignored``, refused (reason the
        state) and changes nothing; while
        inactive it is counted in ``withheld``. Returns None (a command
        publishes nothing).
        """
        self.received['commands'] += 1
        self._take('commands', forces, now)

    def joint_command(self, stamp, frame, names, position, velocity, effort,
                      now):
        """
        Take an effort command as a JointState, by joint name.

        The form topic-based ros2_control hardware interfaces publish: the
        fields of a JointState (only ``names`` and ``effort``, N, are
        used); the forces of ``joint_names`` are picked by name, other
        joints ignored. Refused (counted) when one is absent
        (``missing_joint``), names repeat or ``effort`` is not as long as
        ``names`` (``malformed``); then as :meth:`command`.
        """
        self.received['joint_commands'] += 1
        try:
            rows = joint_columns(self.settings.joint_names, names)
            if len(effort) != len(names):
                raise Rejected('malformed', (
                    f'{len(effort)} effort(s) for {len(names)} joint '
                    'name(s)'))
        except Rejected as rejection:
            self.count('joint_commands', rejection)
            raise
        self._take('joint_commands', [effort[i] for i in rows], now)

    def _take(self, source, forces, now):
        if len(forces) != 3:
            self.refuse(source, 'length', (
                f'command of {len(forces)} value(s), expected 3 forces '
                '[f_A, f_B, f_C] (N)'))
        fa, fb, fc = (float(f) for f in forces)
        if not math.isfinite(fa + fb + fc):
            self.refuse(source, 'non_finite',
                        f'command {[fa, fb, fc]} N is not finite')
        if self.state in (STOPPED, DIVERGED):
            self.ignored += 1
            raise Rejected(self.state, 'command ignored: the simulation '
                           f'{self.state} (call ~/reset)')
        if not self.active:
            self.withheld += 1
            return
        self.valid += 1
        self._command = (fa, fb, fc)
        self.latest_arrival = now
        self.state = RUNNING
        self.timed_out = False

    def tick(self, now):
        """
        Make this tick's step, if ``running``; return a :class:`Tick`.

        First the timeout: ``running`` with no valid command for more than
        ``command_timeout`` goes back to ``held`` (velocity zero, no step).
        A step the plant refuses stops the simulation (the state stays the
        last good one, velocity zero); one it cannot integrate
        (:class:`plant.Diverged`) the same, as ``diverged``. The time step
        is always ``1 / rate_hz``, however late the tick.
        """
        event = None
        effort = ZERO
        if self.state == RUNNING and (
                now - self.latest_arrival > self.settings.command_timeout):
            self._brake(HELD)
            self.timed_out = True
            self.timeouts += 1
            event = 'timeout'
        elif self.state == RUNNING:
            plant = self.plant
            start = time.perf_counter_ns()
            try:
                step = plant.step(self._command, 1.0 / self.settings.rate_hz)
            except mechanics.WorkspaceError as error:
                self._stop(error)
                event = 'stopped'
            except Diverged as error:
                self._diverge(error)
                event = 'diverged'
            else:
                spent = time.perf_counter_ns() - start
                self.steps += 1
                self.step_ns_total += spent
                if spent > self.step_ns_max:
                    self.step_ns_max = spent
                if step.clipped[0] or step.clipped[1] or step.clipped[2]:
                    self.clipped += 1
                effort = step.force
                self._refresh()
        lambda_, lambdadot = self._joints
        return Tick(self.state, self.plant.position, lambda_, lambdadot,
                    effort, event)

    def step_due(self, now):
        """
        Make the grid's next step if it is due at ``now``.

        Returns ``(tick, instant)``, the :class:`Tick` and the grid time (s) its
        state holds at, or None when no step is due; call it until None to catch
        up. The step at grid time g integrates [g, g + 1/rate_hz] with the
        command known at g. The grid starts half a period before the first call
        (a caller's jitter below half a period makes one step per wake-up); more
        than MAX_CATCH_UP periods behind, the missed time is dropped
        (``overruns``); more than ``command_timeout`` behind, the next step is a
        timeout (doc/simulator.md#integrator-and-timing).
        """
        if not self.active:
            return None
        period = 1.0 / self.settings.rate_hz
        if self._grid is None:
            self._grid = now - 0.5 * period
        elif now - self._grid > MAX_CATCH_UP * period:
            if now - self._grid > self.settings.command_timeout:
                # This process stood still longer than the command timeout:
                # a command read on waking up waited in the queue, of
                # unknown age. Brake (the next tick times out), as a drive
                # whose cycle stalled would.
                if self.state == RUNNING:
                    self.stall_brakes += 1
                self.latest_arrival = -math.inf
            self.overruns += 1
            late = now - (MAX_CATCH_UP - 0.5) * period
            self.dropped_time += late - self._grid
            self._grid = late
        if self._grid > now:
            return None
        instant = self._grid
        self._grid += period
        return self.tick(instant), self._grid

    def publish_due(self, tick, instant):
        """
        Say whether to publish the state at grid time ``instant``.

        Every step's state with ``publish_rate_hz`` 0.0, those a late
        wake-up catches up with included (a log of the states then has no
        gap where the process was late); else the first state at or after
        each instant of the publish grid (period 1/publish_rate_hz,
        instants a late wake-up skipped are dropped); always a state that
        ends in an event (a timeout, a stop); never a state once
        ``diverged`` (no state of the robot: the last good one is not
        where it would be). A state to publish is counted as published.
        """
        due = self._publish_due(tick, instant)
        self.published += due
        return due

    def _publish_due(self, tick, instant):
        settings = self.settings
        if tick.state == DIVERGED:
            return False
        if settings.publish_rate_hz == 0.0 or tick.event is not None:
            return True
        # Half a step of slack: the two grids' float sums drift apart.
        slack = 0.5 / settings.rate_hz
        due = self._next_publish
        if due is not None and instant < due - slack:
            return False
        period = 1.0 / settings.publish_rate_hz
        due = instant if due is None else due
        while due <= instant + slack:
            due += period
        self._next_publish = due
        return True

    def reset(self):
        """
        Start over: initial_position, at rest, ``held``, time 0.

        Applies the pending plant parameters (robot, initial position,
        margin) and clears ``stopped`` and ``diverged`` (a new plant); the
        counters go on. Returns a message saying what was done.
        """
        settings = self.settings
        applied = self._model not in (None, _plant_model(settings))
        engine = mujoco_plant.MujocoPlant if settings.engine == 'mujoco' \
            else Plant
        extra = {'model_text': settings.mjcf_file} \
            if settings.mjcf_file else {}
        self.plant = engine(settings.robot, settings.initial_position, ZERO,
                            0.0, joint_limit(settings, 'max_effort'),
                            settings.singularity_margin, **extra)
        self._model = _plant_model(settings)
        self._command = None
        self.state = HELD
        self.timed_out = False
        self.stop_reason = None
        self.stop_message = None
        self._refresh()
        return (f'held at rest at initial_position '
                f'{list(settings.initial_position)} m, simulation time 0'
                + ('; new robot, initial_position or singularity_margin '
                   'applied' if applied else ''))

    @property
    def singularity_distance(self):
        """Return the singularity distance of the current position."""
        return self._solution.singularity_distance

    # Status: ERROR after an internal error or when stopped or diverged;
    # WARN when the steps fell behind real time (more than SLOW_FRACTION of
    # the period dropped: a sustained lag, not one hiccup), when held by
    # the command timeout or when commands were rejected in the period;
    # else OK (``held: waiting for a command`` or ``running``).
    def period_counters(self):
        """Return the counters of the period's rates."""
        return dict(published=self.published, steps=self.steps,
                    step_ns=self.step_ns_total, dropped=self.dropped_time)

    def status_rules(self, now, seconds, increases):
        """Return the stop, lag, timeout, rejections and state steps."""
        return (
            (self.state == STOPPED, ERROR, f'stopped: {self.stop_message}'),
            (self.state == DIVERGED, ERROR,
             f'diverged: {self.stop_message}'),
            (increases['dropped'] > SLOW_FRACTION * seconds, WARN,
             f'slower than real time: {increases["steps"] / seconds:.0f} of '
             f'{self.settings.rate_hz:g} steps/s, '
             f'{increases["dropped"]:.3g} s of the last {seconds:.3g} s '
             'dropped'),
            (self.timed_out, WARN,
             f'held: no valid command for command_timeout '
             f'{self.settings.command_timeout:g} s, braked'),
            (increases['rejected'], WARN,
             f'{increases["rejected"]} command(s) rejected in the last '
             'period'),
            (self.valid == 0 or self.state != RUNNING, OK,
             'held: waiting for a command'),
            (True, OK, 'running'))

    def values(self, now, seconds, increases):
        """Return the state, rates, compute times, counters and position."""
        mean_us = increases['step_ns'] / increases['steps'] / 1e3 \
            if increases['steps'] else 0.0
        plant = self.plant
        values = [
            ('state', self.state),
            ('engine', 'mujoco' if isinstance(
                plant, mujoco_plant.MujocoPlant) else 'builtin'),
            ('sim time (s)', plant.time),
            ('steps', self.steps),
            ('divergences', self.divergences),
            ('step rate (Hz)', increases['steps'] / seconds),
            ('outputs rate (Hz)', increases['published'] / seconds),
            ('step compute time mean (us)', mean_us),
            ('step compute time max (us)', self.step_ns_max / 1e3),
            ('commands received', self.valid),
            ('commands ignored (stopped)', self.ignored),
            ('commands withheld (inactive)', self.withheld),
            ('clipped steps', self.clipped),
            ('timeouts', self.timeouts),
            ('stall brakes', self.stall_brakes),
            ('overruns (time dropped)', self.overruns),
            ('time dropped (s)', self.dropped_time),
            ('position x (m)', plant.position[0]),
            ('position y (m)', plant.position[1]),
            ('position z (m)', plant.position[2]),
            ('singularity distance', self.singularity_distance),
            ('singularity margin', plant.margin),
            ('pending reset', self.pending_reset),
            ('payload (kg)', self.plant.robot.payload),
            ('rate_hz', self.settings.rate_hz),
            ('publish_rate_hz', self.settings.publish_rate_hz),
        ]
        self.step_ns_max = 0
        return values

    def _brake(self, state):
        """Stop the platform where it is (velocity zero) in ``state``."""
        self.state = state
        self._command = None
        self.plant.velocity = ZERO
        self._refresh()

    def _stop(self, error):
        position, velocity = self.plant.position, self.plant.velocity
        self.stop_reason = error.reason
        self.stop_message = (
            f'simulation stopped at position {format_vector(position)} m, velocity '
            f'{format_vector(velocity)} m/s, time {self.plant.time:.6g} s: the next '
            f'step under force {format_vector(self._command)} N was refused '
            f'({error.reason}): {error}; call ~/reset to start again')
        self._brake(STOPPED)

    def _diverge(self, error):
        position = self.plant.position
        self.divergences += 1
        self.stop_reason = error.reason
        self.stop_message = (
            f'the {self.settings.engine} engine diverged after time '
            f'{self.plant.time:.6g} s at position {format_vector(position)} '
            f'm (the last good state): {error}; no state is published '
            'until ~/reset')
        self._brake(DIVERGED)

    def _refresh(self):
        """
        Solve the plant's state; read its sliders (the joint state).

        The builtin plant's sliders are the closed form of its platform
        state; MuJoCo's are its slide joints (the constraints hold the rest
        to about 0.1 um).
        """
        plant = self.plant
        s = self._solution = mechanics.solve(
            plant.robot, plant.position, plant.velocity, ZERO, plant.margin)
        self._joints = (s.lambda_, s.lambdadot) if plant.closed_form \
            else plant.joint_state()


def _plant_model(settings):
    """Return the settings that describe the plant (applied at reset)."""
    return (settings.robot.replace(payload=0.0), settings.initial_position,
            settings.singularity_margin, settings.engine, settings.mjcf_file)
