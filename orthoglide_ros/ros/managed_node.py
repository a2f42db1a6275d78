"""
The one shape of the package's nodes: a managed node around one core.

:class:`ManagedNode`, rclpy's ``LifecycleNode`` around one core
(:mod:`orthoglide_ros.cores.core`), owns its :class:`InputThreads`,
:class:`ReplyGuard` and :class:`Diagnostics`; a subclass's
:meth:`ManagedNode.build` makes the core, outputs and inputs at configure
(doc/feedforward.md#lifecycle, doc/decisions.md#nodes).
"""

import sys
import threading
import time
import traceback

from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from rclpy.qos_overriding_options import QoSOverridingOptions

from rcl_interfaces.msg import SetParametersResult

from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.parameters import Spec
from orthoglide_ros.formats.text import clip, printable
from orthoglide_ros.ros.diagnostics import Diagnostics
from orthoglide_ros.ros.input_threads import default_qos, InputThreads
from orthoglide_ros.ros.node_runtime import NotStarting
from orthoglide_ros.ros.parameters import (declare_specs, overridden,
                                           spec_values)
from orthoglide_ros.ros.reply_guard import ReplyGuard

__all__ = ('AUTOSTART', 'default_qos', 'ManagedNode')

AUTOSTART = Spec(
    'autostart', 'bool', True,
    'configure and activate at start (ros2 run as a plain node); false: '
    'wait unconfigured for ~/change_state', read_only=True)
WARNING_PERIOD = 1.0        # s between two warnings of the same reason

SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE
ERROR = TransitionCallbackReturn.ERROR
# The state a successful transition ends in.
_STATE_AFTER = {'configure': 'inactive', 'activate': 'active',
                'deactivate': 'inactive', 'cleanup': 'unconfigured',
                'shutdown': 'finalized'}


class ManagedNode(LifecycleNode):
    """
    A node of the package (see the module docstring).

    Subclasses set :attr:`NAME`, :attr:`TITLE` (of its diagnostics) and
    :attr:`PARAMETERS` (its :class:`orthoglide_ros.cores.parameters.Table`),
    implement :meth:`build`, and may override :meth:`reconfigure`,
    :meth:`inputs_idle`, :attr:`finished` and :meth:`on_stop`. All work on
    the core holds :attr:`lock`.
    """

    NAME = None
    TITLE = None
    PARAMETERS = None

    def __init__(self, **kwargs):
        super().__init__(self.NAME, **kwargs)
        self.lock = threading.Lock()
        self.core = None
        self._internal_errors = 0
        self._throttled = {}        # reason: (last line's time, left out)
        self._throttle_lock = threading.Lock()
        self._made_publishers = []       # made at configure, ended at cleanup
        self._made_services = []
        self._announce = False      # log transitions, not autostart's
        self._refused = None        # why the last transition failed
        self.inputs = InputThreads(self)
        self.replies = ReplyGuard(self)
        self.PARAMETERS.refuse_retired(
            overridden(self, self.PARAMETERS.retired))
        declare_specs(self, (AUTOSTART, *self.PARAMETERS.specs))
        self.diagnostics = Diagnostics(self, self.TITLE,
                                       self._apply_realtime())
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._refuse_unavailable_transitions()
        self.inputs.start()
        self._autostart()

    # What a node provides -------------------------------------------------
    def build(self, settings):
        """
        Override: make the core, outputs, inputs and periodic work (configure).

        One ``self.inputs.subscribe(...)`` per input: its topic, type,
        decoder, core method and publisher, the whole path of a message.
        """
        raise NotImplementedError

    def reconfigure(self, settings):
        """Apply accepted run-time parameter changes (lock held)."""
        self.core.configure(settings)

    def inputs_idle(self):
        """
        Override: run after each wake-up of the ``inputs`` thread.

        Once it has handled what its inputs held (or after INPUT_WAIT
        without input), the lock held: a timeout judged here by
        ``time.monotonic()`` cannot drop what a message still waiting in
        a queue would have completed (a timer could: its thread may run
        while this one is stalled).
        """

    @property
    def finished(self):
        """Override: whether the node's work is over (``run`` stops)."""
        return False

    def on_stop(self, interrupted):
        """
        Override: run by ``run`` before the node is destroyed.

        ``interrupted``: stopped by a signal (else the node finished).
        """

    # Entities -------------------------------------------------------------
    def create_output(self, msg_type, topic):
        """Create a publisher with the package's QoS and the QoS overrides."""
        publisher = self.create_publisher(
            msg_type, topic, default_qos(),
            qos_overriding_options=QoSOverridingOptions
            .with_default_policies())
        self._made_publishers.append(publisher)
        return publisher

    def create_guarded_service(self, srv_type, name, callback):
        """Create a service, guarded (:class:`ReplyGuard`), that cleanup ends."""
        service = self.replies.guard(
            self.create_service(srv_type, name, callback))
        self._made_services.append(service)
        return service

    @property
    def subscriptions(self):
        """Return the subscriptions an executor serves (not the inputs)."""
        return (s for s in super().subscriptions if not self.inputs.hides(s))

    @property
    def waitables(self):
        """Return the waitables an executor serves (not the inputs' events)."""
        return (w for w in super().waitables if not self.inputs.hides(w))

    # Parameters -----------------------------------------------------------
    def parse_settings(self):
        """Return the declared parameters parsed (ValueError if invalid)."""
        return self.PARAMETERS.parse(spec_values(self,
                                                 self.PARAMETERS.specs))

    def _apply_realtime(self):
        """
        Apply the table's real-time parameters to every thread, at start.

        Before the node's own threads start and before its first input; a
        bad value raises :class:`ParameterError` (the process exits 2), a
        refusal of the OS is one warning per setting and the node runs on.
        Returns the settings asked for, or None without such parameters.
        """
        if not set(realtime.NAMES) <= {s.name for s in
                                       self.PARAMETERS.specs}:
            return None
        asked = realtime.settings_of(spec_values(self, realtime.SPECS))
        for warning in realtime.apply(*asked):
            self.log('warning', warning)
        if any(asked):
            effect = realtime.in_effect()
            self.log('info', (
                f'real time: {effect.policy} {effect.priority} on CPUs '
                f'{realtime.format_cpus(effect.cpus)}, {effect.alike} of '
                f'{effect.threads} threads, {effect.locked_kb // 1024} MiB '
                'locked'))
        return asked

    def _validate_parameters(self, parameters):
        """
        Refuse a change unless the whole resulting set parses.

        The parse error is the reason; an accepted change is applied by
        :meth:`_apply_parameters`, so the next input sees all the new
        values and none of the old.
        """
        try:
            self.PARAMETERS.parse(spec_values(self, self.PARAMETERS.specs,
                                              parameters))
        except ValueError as error:
            reason = clip(error)
            self.warn_throttled(('parameters', 'refused'),
                                f'parameter change refused: {reason}')
            return SetParametersResult(successful=False, reason=reason)
        except Exception:   # a defect: refuse the change, report it
            self.report_defect('validating a parameter change')
            return SetParametersResult(
                successful=False, reason='internal error: see the log')
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        # Not the QoS overrides declared as outputs and inputs are made.
        names = {spec.name for spec in self.PARAMETERS.specs}
        if not any(parameter.name in names for parameter in parameters):
            return
        settings = self.parse_settings()
        with self.lock:
            if self.core is not None:   # once configured
                self.reconfigure(settings)

    # Logging --------------------------------------------------------------
    def log(self, level, text, frames=''):
        """
        Log ``text`` at ``level`` as one line (:func:`printable`).

        ``level``: ``'info'``, ``'warning'``, ``'error'`` or ``'fatal'``.
        Every character of ``text`` that is not printable is escaped and
        the line clipped: whatever a peer's string inside holds (a label,
        a frame id, a parameter name), it cannot break the line or forge
        another. ``frames``: lines of the package's own that follow it
        as they are (a traceback's stack, clipped), never a peer's text.
        One call per level: rclpy 7.1.6's logger keys its state by call
        site and refuses two severities from one line; this can be one call
        when it no longer does (``benchmarks/upstream_checks.py``,
        ``logger_severity``).
        """
        logger, text = self.get_logger(), printable(text)
        if frames:
            text = f'{text}\n{clip(frames.rstrip())}'
        if level == 'info':
            logger.info(text)
        elif level == 'warning':
            logger.warning(text)
        elif level == 'error':
            logger.error(text)
        else:
            logger.fatal(text)

    def warn_throttled(self, reason, message):
        """Log a warning, at most one per WARNING_PERIOD for ``reason``."""
        self.log_throttled('warning', reason, message)

    def log_throttled(self, level, reason, message):
        """
        Log ``message`` at most once per WARNING_PERIOD for ``reason``.

        ``reason``: a key of the package's own (never a peer's text, so
        that the keys stay few); a line logged after some were left out
        says how many. Any thread may call it.
        """
        left_out = self._throttle(reason)
        if left_out is not None:
            self.log(level, message + (
                f' ({left_out} more like it not logged in between)'
                if left_out else ''))

    def _throttle(self, reason):
        """Return how many lines ``reason`` left out, or None: not now."""
        now = time.monotonic()
        with self._throttle_lock:
            last, left_out = self._throttled.get(reason, (-1e9, 0))
            if now - last < WARNING_PERIOD:
                self._throttled[reason] = (last, left_out + 1)
                return None
            self._throttled[reason] = (now, 0)
            return left_out

    @property
    def internal_errors(self):
        """Return how many defects :meth:`report_defect` has counted."""
        return self._internal_errors

    def report_defect(self, where):
        """
        Count an exception that escaped a callback (a defect, not bad input).

        Logged with its traceback at most once a WARNING_PERIOD; the node
        goes on and its diagnostics turn ERROR. Call it from an ``except``.
        """
        self._internal_errors += 1
        left_out = self._throttle('internal')
        if left_out is not None:
            self.log_exception('error', f'internal error {where}' + (
                f' ({left_out} more not logged in between)'
                if left_out else ''))

    def log_exception(self, level, what):
        """
        Log the exception being handled: ``what``, its text, its stack.

        The exception's text (which may quote a peer's) on the first line,
        escaped as every logged text; the stack (the package's code) after
        it. Call it from an ``except``.
        """
        kind, error, stack = sys.exc_info()
        self.log(level, f'{what}: {kind.__name__}: {error}',
                 'Traceback (most recent call last):\n'
                 + ''.join(traceback.format_tb(stack)))

    # Lifecycle ------------------------------------------------------------
    @property
    def lifecycle_state(self):
        """Return the state's label (``unconfigured``, ``active``...)."""
        return self._state_machine.current_state[1]

    def _refuse_unavailable_transitions(self):
        """
        Answer a transition the state does not offer: success false, a warning.

        Works around rclpy 7.1.6, which raises inside the service on a
        transition *id* the state does not offer (rclcpp answers false; a
        label rclpy answers false itself): ``ros2 lifecycle set`` and
        lifecycle managers send ids. It can go when rclpy answers such an
        id false (``benchmarks/upstream_checks.py``, ``lifecycle_by_id``);
        the throttled warning, for ids and labels alike, is the package's
        own rule (``doc/robustness.md``, logs).
        """
        service = self._service_change_state
        callback = service.callback

        def change_state(request, response):
            wanted = request.transition
            offered = [(t[0], t[1]) for t in
                       self._state_machine.available_transitions]
            if not any(wanted.label == label if wanted.label
                       else wanted.id == number for number, label in offered):
                # A client may ask again and again: one line a second.
                self.warn_throttled(('change_state', 'unavailable'), (
                    f'transition {wanted.label or wanted.id!r} refused: not '
                    f'available in state {self.lifecycle_state}'))
                response.success = False
                return response
            return callback(request, response)
        service.callback = change_state

    def _autostart(self):
        """
        Configure and activate when ``autostart`` says so.

        Raises NotStarting with the reason when configure or activate
        fails (``run`` then exits 2); nothing of the node runs on. The
        two are one step: the inputs are read from the activation on, so
        no message is handled by the inactive state in between (a message
        that comes meanwhile waits in its subscription's history; the
        recorder lost such messages under load).
        """
        if not self.get_parameter('autostart').value:
            self.log('info', 'unconfigured: waiting for ~/change_state '
                     '(autostart is false)')
            self._announce = True
            return
        if self.trigger_configure() != SUCCESS:
            refused = self._refused or 'configure failed'
        elif self.trigger_activate() != SUCCESS:
            refused = self._refused or 'activate failed'
        else:
            self._announce = True
            self.inputs.start()
            return
        self.inputs.stop()
        raise NotStarting(refused)

    def on_configure(self, state):
        """Check the parameters, then build (see the module docstring)."""
        try:
            settings = self.parse_settings()
        except (ValueError, ParameterException) as error:
            self._refused = f'invalid parameters: {clip(error)}'
            if self._announce:      # autostart's: run says it, once
                self.log_throttled('error', ('transition', 'configure'),
                                   f'configure refused: {self._refused}')
            return FAILURE
        return self._transition('configure', self._build, settings)

    def _build(self, settings):
        self.build(settings)
        self.core.active = False
        if self._announce:      # not autostart's: it starts them once active
            self.inputs.start()

    def on_activate(self, state):
        """Start the outputs."""
        return self._transition('activate', self._set_active, True)

    def on_deactivate(self, state):
        """Stop the outputs at once; inputs are still read and counted."""
        return self._transition('deactivate', self._set_active, False)

    def on_cleanup(self, state):
        """Release what configure made."""
        return self._transition('cleanup', self._release)

    def on_shutdown(self, state):
        """Release what configure made; the node is finalized."""
        return self._transition('shutdown', self._release)

    def on_error(self, state):
        """After a failed transition: release everything, unconfigured."""
        try:
            self._release()
        except Exception as error:  # still an error: finalized
            self.log('error', f'error processing failed: {_line(error)}')
            return FAILURE
        return SUCCESS

    def _transition(self, name, work, *args):
        try:
            work(*args)
        except Exception as error:  # to the error state, one clear line
            self._refused = clip(str(error)) if isinstance(error, ValueError) \
                else _line(error)
            if self._announce:      # autostart's: run says it, once
                self.log_throttled('error', ('transition', name),
                                   f'{name} failed: {self._refused}')
            return ERROR
        if self._announce:
            self.log('info', f'{name}: {_STATE_AFTER[name]}')
        return SUCCESS

    def _set_active(self, active):
        with self.lock:
            if active:
                self.core.activate()
            else:
                self.core.deactivate()

    def _release(self):
        self.inputs.release()
        for publisher in self._made_publishers:
            self.destroy_publisher(publisher)
        for service in self._made_services:
            self.destroy_service(service)
        self._made_publishers, self._made_services = [], []
        with self.lock:
            self.core = None

    def destroy_node(self):
        """Stop the input and periodic threads, then destroy the node."""
        self.inputs.stop()
        super().destroy_node()


def _line(error):
    """Return an exception as one clipped line: its type and text."""
    return clip(f'{type(error).__name__}: {error}'.splitlines()[0])
