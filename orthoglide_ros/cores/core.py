"""
The contract between a node and its core, and what every core shares.

A node calls only what :class:`Core` lists; every method takes ``now`` so
that tests drive time (doc/decisions.md#nodes).
"""

from orthoglide_ros.cores.inputs import Rejected
from orthoglide_ros.cores.status import (first_rule_that_holds, OK, Period,
                                         Status, WARN)


class Core:
    """
    The shared part of a node's core: counters, status period and rules.

    The counters of what came in (``received``, per input) and what was
    refused (``rejected``, per reason, or per input and reason). Subclasses
    set :attr:`INPUTS` (the inputs' source names), :attr:`REASONS` (the
    rejection reasons) and :attr:`REJECTED_BY_INPUT` (count refusals per
    input and reason, shown as ``rejected <input> <reason>``, rather than
    per reason, ``rejected <reason>``), and add their input methods,
    :meth:`status_rules` and :meth:`values`.
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
        self.last_rejection = None      # the last Rejected counted
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
        self.last_rejection = rejection

    def refuse(self, source, reason, message):
        """Count a refusal of input ``source`` and raise it."""
        rejection = Rejected(reason, message)
        self.count(source, rejection)
        raise rejection

    def status(self, now, internal_errors=0):
        """
        Return the :class:`Status` of the period ending at ``now``.

        The level and message: ERROR after an internal error, then
        ``inactive`` (OK), then the core's :meth:`status_rules`, else OK
        ``ok``. The values: the core's :meth:`values`, the counters of
        :meth:`counter_values`, the internal errors.
        """
        seconds, increases = self._period.advance(
            now, rejected=sum(self.rejected.values()),
            **self.period_counters())
        level, message = first_rule_that_holds(
            internal_errors, (not self.active, OK, self.inactive_message()),
            *self.status_rules(now, seconds, increases))
        values = self.values(now, seconds, increases) + self.counter_values()
        values.append(('internal errors', internal_errors))
        return Status(level, message, values)

    def inactive_message(self):
        """Return the status message while inactive."""
        return self.INACTIVE

    def period_counters(self):
        """Return the counters whose growth per period the status uses."""
        return {}

    def status_rules(self, now, seconds, increases):
        """
        Return the status rules after ``inactive``, in order.

        ``(condition, level, message)`` triples
        (:func:`~orthoglide_ros.cores.status.first_rule_that_holds`);
        ``seconds``: the period's length; ``increases``: each counter's
        growth over it, ``rejected`` among them.
        """
        return ()

    def rejected_rule(self, increases, what):
        """Return the WARN rule of the period's refusals, the last named."""
        last = self.last_rejection
        return (increases['rejected'], WARN,
                f'{increases["rejected"]} {what} rejected in the last period, '
                f'the last ({last.reason if last else ""}): {last}')

    def values(self, now, seconds, increases):
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
