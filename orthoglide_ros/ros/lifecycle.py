"""
The managed lifecycle of the feedforward and the tracking controller.

:class:`ManagedNode` is an :class:`~orthoglide_ros.ros.node_runtime.InputNode`
on rclpy's ``LifecycleNode``, with the standard ``~/change_state``,
``~/get_state`` services and the states of the ROS 2 design:

- constructed: the parameters (``autostart`` among them), the diagnostics
  and the lifecycle services exist; the node is ``unconfigured`` and
  publishes nothing but its diagnostics;
- configure: the parameters are checked as a whole (an invalid set:
  FAILURE, stays unconfigured, the reason logged), then the subclass's
  :meth:`ManagedNode.build` makes the core, the inputs, the outputs and
  the periodic work, whose threads start; ``inactive``: inputs are read
  and counted, nothing is published;
- activate / deactivate: the core's ``activate()`` / ``deactivate()``,
  under the lock: outputs start, or stop at once;
- cleanup / shutdown: the threads stop, inputs and outputs are destroyed,
  the core is dropped;
- an exception in a transition: one line at ERROR (no traceback), the
  error state, whose handler releases what configure made and returns
  to ``unconfigured``.

``autostart`` (default true) configures and activates as the node is made
(:meth:`ManagedNode.start`, the last line of its constructor), so that
``ros2 run`` and code that makes the node behave as with a plain node: an
invalid start-up set raises ValueError, and the process exits 2
(:func:`~orthoglide_ros.ros.node_runtime.run`). The diagnostics carry the
state (``lifecycle state``).
"""

from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn

from orthoglide_ros.formats.text import clip
from orthoglide_ros.cores.parameters import Spec
from orthoglide_ros.ros.node_runtime import declare_specs, InputNode

AUTOSTART = Spec(
    'autostart', 'bool', True,
    'configure and activate at start (ros2 run as a plain node); false: '
    'wait unconfigured for ~/change_state', read_only=True)

SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE
ERROR = TransitionCallbackReturn.ERROR


class ManagedNode(InputNode, LifecycleNode):
    """
    A node with a managed lifecycle (see the module docstring).

    Subclasses implement :meth:`build` (the work of configure), call
    :meth:`declare_table` in their constructor and :meth:`start` last;
    ``core.activate()`` and ``core.deactivate()`` gate the outputs.
    """

    def __init__(self, name, **kwargs):
        super().__init__(name, **kwargs)
        declare_specs(self, (AUTOSTART,))
        self._outputs = []
        self.configure_error = None
        self._announce = False      # log transitions, but not autostart's
        self._refuse_unavailable_transitions()

    def _refuse_unavailable_transitions(self):
        """
        Answer a transition the state does not offer with success false.

        rclpy raises on it inside the service (rclcpp answers false): it
        would be reported as a defect of the node.
        """
        service = self._service_change_state
        callback = service.callback

        def change_state(request, response):
            wanted = request.transition
            offered = [(t[0], t[1]) for t in
                       self._state_machine.available_transitions]
            if not any(wanted.label == label if wanted.label
                       else wanted.id == number for number, label in offered):
                self.log('warning', (
                    f'transition {wanted.label or wanted.id} refused: not '
                    f'available in state {self.lifecycle_state}'))
                response.success = False
                return response
            return callback(request, response)
        service.callback = change_state

    @property
    def lifecycle_state(self):
        """Return the state's label (``unconfigured``, ``active``...)."""
        return self._state_machine.current_state[1]

    def declare_table(self, table, title):
        """Declare ``table``'s parameters; publish diagnostics as ``title``."""
        self.declare_settings(table, parse=False)
        self.publish_status(title)
        self.start_threads()

    def build(self, settings):
        """Override: make the core, inputs, outputs and periodic work."""
        raise NotImplementedError

    def create_output(self, msg_type, topic):
        """Create a publisher that cleanup destroys (as InputNode's)."""
        publisher = super().create_output(msg_type, topic)
        self._outputs.append(publisher)
        return publisher

    def start(self):
        """
        Configure and activate when ``autostart`` says so (constructors end so).

        Raises ValueError with the reason when configure refuses the
        parameters (:func:`~orthoglide_ros.ros.node_runtime.run` then exits 2).
        """
        if not self.get_parameter('autostart').value:
            self.log('info', 'unconfigured: waiting for ~/change_state '
                     '(autostart is false)')
            self._announce = True
            return
        refused = None
        if self.trigger_configure() != SUCCESS:
            refused = self.configure_error or 'configure failed'
        elif self.trigger_activate() != SUCCESS:
            refused = 'activate failed'
        if refused:
            self.stop_threads()     # the node is not made: nothing runs on
            raise ValueError(refused)
        self._announce = True

    # Transitions ----------------------------------------------------------
    def on_configure(self, state):
        """Check the parameters, then build (see the module docstring)."""
        try:
            settings = self.parse_settings()
        except (ValueError, ParameterException) as error:
            self.configure_error = clip(error)
            self.log('error', f'configure refused: invalid parameters: '
                     f'{self.configure_error}')
            return FAILURE
        return self._transition('configure', lambda: self._build(settings))

    def _build(self, settings):
        self.build(settings)
        self.start_threads()

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
            self.log('error', f'{name} failed: {_line(error)}')
            return ERROR
        if self._announce:
            self.log('info', f'{name}: {self.lifecycle_state_after(name)}')
        return SUCCESS

    @staticmethod
    def lifecycle_state_after(name):
        """Return the state a successful transition ``name`` ends in."""
        return {'configure': 'inactive', 'activate': 'active',
                'deactivate': 'inactive', 'cleanup': 'unconfigured',
                'shutdown': 'finalized'}[name]

    def _set_active(self, active):
        with self.lock:
            if active:
                self.core.activate()
            else:
                self.core.deactivate()

    def _release(self):
        self.release_threads()
        for publisher in self._outputs:
            self.destroy_publisher(publisher)
        self._outputs = []
        with self.lock:
            self.core = None
        self.publish_status(self._status_title)     # its thread, again
        self.start_threads()


def _line(error):
    """Return an exception as one clipped line: its type and text."""
    return clip(f'{type(error).__name__}: {error}'.splitlines()[0])
