"""
What the nodes' statuses share, without ROS: levels, periods, rules.

Every core's ``status(now, internal_errors)`` returns a :class:`Status`,
published on ``/diagnostics`` once a second (the keys: each node's page).

>>> period = Period(0.0, published=0)
>>> seconds, increases = period.advance(2.0, published=100)
>>> seconds, increases['published']
(2.0, 100)
>>> first_rule_that_holds(0, (False, WARN, 'stale'), (True, OK, 'ok'))
(0, 'ok')
>>> first_rule_that_holds(3, (True, OK, 'ok'))
(2, '3 internal error(s): see the log')
"""

from collections import namedtuple

OK, WARN, ERROR = 0, 1, 2  # diagnostic_msgs' level bytes

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


def first_rule_that_holds(internal_errors, *rules):
    """
    Return ``(level, message)`` of the first rule whose condition holds.

    ``rules``: ``(condition, level, message)`` triples, in order; an
    internal error count above zero comes before all of them (ERROR), and
    when none holds the level is OK with the message ``'ok'``.
    """
    if internal_errors:
        return ERROR, f'{internal_errors} internal error(s): see the log'
    for condition, level, message in rules:
        if condition:
            return level, message
    return OK, 'ok'
