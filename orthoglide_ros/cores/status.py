"""
Status rules shared by the nodes' cores, without ROS.

Every node reports one status about once a second on ``/diagnostics``. The
rules that make it (which level, which message, which values) live in each
node's core, in a ``status(now, internal_errors)`` method that returns a
:class:`Status`; the ROS side only turns it into a DiagnosticArray
(``node_runtime.diagnostic_array``). This module holds what those methods
share:

- the levels :data:`OK`, :data:`WARN`, :data:`ERROR` (the values of
  diagnostic_msgs' level bytes, so a Status maps onto a DiagnosticStatus
  one to one);
- :class:`Period`: the counters at the start of the period, so a status
  can report rates and increases "in the last period";
- :func:`first`: the ladder, the first condition that holds sets the level
  and the message, an internal error (a defect) always first.

>>> period = Period(0.0, published=0)
>>> seconds, new = period.advance(2.0, published=100)
>>> seconds, new['published']
(2.0, 100)
>>> first(0, (False, WARN, 'stale'), (True, OK, 'ok'))
(0, 'ok')
>>> first(3, (True, OK, 'ok'))
(2, '3 internal error(s): see the log')
"""

from collections import namedtuple

OK, WARN, ERROR = 0, 1, 2

Status = namedtuple('Status', 'level message values')
Status.__doc__ = """One status: ``level`` (OK, WARN or ERROR), ``message``
(one line) and ``values``, ``(key, value)`` pairs in display order."""


class Period:
    """
    Counters at the start of the current status period.

    :meth:`advance` starts the next period and returns how long the last
    one lasted and how much each counter grew in it.
    """

    def __init__(self, now, **counters):
        """Start the first period at ``now`` (s) with these counter values."""
        self.start = now
        self.counters = counters

    def advance(self, now, **counters):
        """
        End the period at ``now``: return ``(seconds, increases)``.

        ``increases`` maps each counter to its growth over the period;
        ``seconds`` is never below 1e-9 (a rate can always be divided).
        """
        seconds = max(now - self.start, 1e-9)
        increases = {name: value - self.counters.get(name, 0)
                     for name, value in counters.items()}
        self.start, self.counters = now, counters
        return seconds, increases


def first(internal_errors, *steps):
    """
    Return ``(level, message)`` of the first step whose condition holds.

    ``steps``: ``(condition, level, message)`` triples, in order; an
    internal error count above zero comes before all of them (ERROR), and
    when none holds the level is OK with the message ``'ok'``.
    """
    if internal_errors:
        return ERROR, f'{internal_errors} internal error(s): see the log'
    for condition, level, message in steps:
        if condition:
            return level, message
    return OK, 'ok'
