"""
The contract between a node and its core, and what every core shares.

A node (:class:`orthoglide_ros.ros.managed_node.ManagedNode`) makes one
core at configure and drops it at cleanup. It calls nothing but:

- ``configure(settings)``: new settings, whole, from the next input on
  (run-time parameter changes; the lock is held);
- ``activate()`` / ``deactivate()``: outputs start, or stop at once; the
  inputs are still read and counted while inactive (:attr:`Core.active`);
- one method per row of the node's input table, ``method(*fields, now)``:
  the decoded message's fields and its arrival time (monotonic s).
  It returns what to publish, or None; it raises
  :class:`~orthoglide_ros.cores.inputs.Rejected` when a rule refuses the
  input, which it has counted;
- ``reject(source, rejection)``: count a message of input ``source``
  refused before it was read (``oversize``, ``malformed``);
- ``status(now, internal_errors)``: the
  :class:`~orthoglide_ros.cores.status.Status` of the period ending at
  ``now``, published on ``/diagnostics`` once a second.

:class:`Core` is that contract with the part every core has: the counters
of what came in (``received``, per input) and what was refused
(``rejected``, per reason, or per input and reason), the period of the
status, its ladder with the inactive step first and its counter values.
A core adds its inputs, its rules and :meth:`Core.ladder` and
:meth:`Core.values`; every method takes ``now`` so that tests drive time.
"""

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.status import first, OK, Period, Status


class Core:
    """
    The shared part of a node's core (see the module docstring).

    Subclasses set :attr:`INPUTS` (the inputs' source names), :attr:`REASONS`
    (the rejection reasons) and :attr:`REJECTED_BY_INPUT` (count refusals
    per input and reason, shown as ``rejected <input> <reason>``, rather
    than per reason, ``rejected <reason>``).
    """

    INPUTS = ()
    REASONS = ()
    REJECTED_BY_INPUT = False
    INACTIVE = 'inactive: inputs taken, no output published'

    def __init__(self, settings, now=0.0):
        """Start with ``settings``, active, the first period at ``now``."""
        self.settings = settings
        self.active = True
        self.received = dict.fromkeys(self.INPUTS, 0)
        self.rejected = {(i, r): 0 for i in self.INPUTS
                         for r in self.REASONS} if self.REJECTED_BY_INPUT \
            else dict.fromkeys(self.REASONS, 0)
        self._period = Period(now)

    def configure(self, settings):
        """Use new settings from the next input on (one assignment)."""
        self.settings = settings

    def activate(self):
        """Publish outputs (a lifecycle node's ``active`` state)."""
        self.active = True

    def deactivate(self):
        """Publish nothing; inputs are still taken and counted."""
        self.active = False

    def reject(self, source, rejection):
        """Count a message on input ``source`` refused before it was read."""
        self.received[source] += 1
        self.count(source, rejection)

    def count(self, source, rejection):
        """Count ``rejection`` (a :class:`Rejected`) of input ``source``."""
        key = (source, rejection.reason) if self.REJECTED_BY_INPUT \
            else rejection.reason
        self.rejected[key] += 1

    def refuse(self, source, reason, message):
        """Count a refusal of input ``source`` and raise it."""
        rejection = Rejected(reason, message)
        self.count(source, rejection)
        raise rejection

    def status(self, now, internal_errors=0):
        """
        Return the :class:`Status` of the period ending at ``now``.

        The level and message: ERROR after an internal error, then
        ``inactive`` (OK), then the core's :meth:`ladder`, else OK
        ``ok``. The values: the core's :meth:`values`, the counters of
        :meth:`counter_values`, the internal errors.
        """
        seconds, new = self._period.advance(
            now, rejected=sum(self.rejected.values()),
            **self.period_counters())
        level, message = first(
            internal_errors, (not self.active, OK, self.inactive_message()),
            *self.ladder(now, seconds, new))
        values = self.values(now, seconds, new) + self.counter_values()
        values.append(('internal errors', internal_errors))
        return Status(level, message, values)

    def inactive_message(self):
        """Return the status message while inactive."""
        return self.INACTIVE

    def period_counters(self):
        """Return the counters whose growth per period the status uses."""
        return {}

    def ladder(self, now, seconds, new):
        """
        Return the status steps after ``inactive``, in order.

        ``(condition, level, message)`` triples (:func:`first`);
        ``seconds``: the period's length; ``new``: each counter's growth
        over it, ``rejected`` among them.
        """
        return ()

    def values(self, now, seconds, new):
        """Return the status pairs of the core's own (a list)."""
        return []

    def counter_values(self):
        """Return ``received <input>`` and ``rejected ...`` values."""
        values = [(f'received {i}', n) for i, n in self.received.items()]
        if self.REJECTED_BY_INPUT:
            values += [(f'rejected {i} {r}', n)
                       for (i, r), n in self.rejected.items()]
        else:
            values += [(f'rejected {r}', n) for r, n in self.rejected.items()]
        return values
