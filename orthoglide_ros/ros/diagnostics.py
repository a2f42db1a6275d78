"""
A node's ``/diagnostics``: its core's status once a second.

:class:`Diagnostics`, owned by every node, publishes the core's
:class:`~orthoglide_ros.cores.status.Status` as one DiagnosticStatus named
``'<node name>: <title>'`` from a periodic thread that lives as long as the
node, with the node's own values (replies dropped, lifecycle state, the
real-time scheduling in effect). The keys: each node's page, diagnostics.
"""

import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from orthoglide_ros.cores import realtime
from orthoglide_ros.cores.status import OK, Status, WARN
from orthoglide_ros.formats.text import printable

PERIOD = 1.0    # s between two /diagnostics messages

# The status of a node without a core, by lifecycle state.
_NO_CORE = {'unconfigured': 'unconfigured: waiting for configure',
            'finalized': 'finalized: shut down'}


class Diagnostics:
    """The ``/diagnostics`` of one node (see the module docstring)."""

    def __init__(self, node, title, asked=None):
        """
        Publish ``node``'s status as ``title`` every PERIOD.

        ``asked``: the real-time settings asked for
        (:func:`orthoglide_ros.cores.realtime.settings_of`), or None.
        """
        self._node = node
        self._title = title
        self._asked = asked
        self._publisher = node.create_publisher(DiagnosticArray,
                                                '/diagnostics', 10)
        node.inputs.periodic(lambda: PERIOD, self.publish, 'diagnostics',
                             keep_on_cleanup=True)

    def status(self):
        """
        Return the node's Status now, its own values added.

        ``core.status`` runs with the node's lock held, on the core as it
        is then: a node without one (unconfigured, finalized) is OK with
        its lifecycle state as the message.
        """
        node = self._node
        with node.lock:
            core = node.core
            status = core.status(time.monotonic(), node.internal_errors) \
                if core is not None else Status(
                    OK, _NO_CORE.get(node.lifecycle_state, ''),
                    [('internal errors', node.internal_errors)])
        status.values.extend((
            ('replies dropped (client gone)', node.replies.replies_dropped),
            ('lifecycle state', node.lifecycle_state)))
        if self._asked is not None:
            status = _with_realtime(status, self._asked)
        return status

    def publish(self):
        """Publish the status now."""
        self._publisher.publish(diagnostic_array(self._node, self._title,
                                                 self.status()))


def _with_realtime(status, asked):
    """
    Add the scheduling in effect to ``status``; WARN if short of ``asked``.

    The shortfall leads the message of an OK or WARN status: it lasts, a
    node's other warnings (stale, rejected input) come and go.
    """
    effect = realtime.in_effect()
    level, message, values = status
    values = values + realtime.status_values(effect)
    missing = realtime.shortfall(*asked, effect)
    if missing is not None and level == OK:
        level, message = WARN, missing
    elif missing is not None and level == WARN:
        message = f'{missing}; {message}'
    return Status(level, message, values)


def diagnostic_array(node, title, status):
    """
    Return a DiagnosticArray holding one :class:`Status` of ``node``.

    Named ``'<node name>: <title>'``, hardware id ``orthoglide``; the
    values shown as text (booleans in lower case, floats with 6
    significant digits).
    """
    level, message, values = status
    diagnostic = DiagnosticStatus(
        name=f'{node.get_name()}: {title}', hardware_id='orthoglide',
        level=bytes((level,)), message=printable(message),
        values=[KeyValue(key=k, value=_text(v)) for k, v in values])
    array_message = DiagnosticArray(status=[diagnostic])
    array_message.header.stamp = node.get_clock().now().to_msg()
    return array_message


def _text(value):
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f'{value:.6g}'
    return str(value)
