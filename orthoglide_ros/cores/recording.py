"""
The recorder's logic without ROS: which message goes into the bag.

:class:`Recording`: each message's bytes returned unchanged, counted per
topic; a drop counted per topic and reason (doc/cli.md#record).
"""

from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.inputs import RECORD_MESSAGE_BYTES, Rejected
from orthoglide_ros.cores.status import OK, WARN

# The exit code of a recording that dropped messages (0: none dropped).
LOSSY = 3
# Why a message of each reason did not reach the bag, as said at the end.
WHY = {'oversize': f'larger than {RECORD_MESSAGE_BYTES // 2**20} MiB',
       'malformed': 'unreadable',
       'inactive': 'received while the recorder was not active',
       'write_failed': 'the bag\'s writer refused them'}


class Recording(Core):
    """What was recorded and dropped, per topic."""

    REASONS = tuple(WHY)
    REJECTED_BY_INPUT = True
    INACTIVE = 'inactive: messages counted, not recorded'

    def __init__(self, topics, now=0.0):
        """Record ``topics`` (their resolved names)."""
        self.INPUTS = tuple(topics)
        super().__init__(None, now)
        self.written = dict.fromkeys(self.INPUTS, 0)

    def message(self, topic, data, now):
        """
        Take one message of ``topic``; return ``(topic, data)`` to write.

        None while inactive: the message is counted as dropped
        (``inactive``), without a warning (a deactivated recorder is
        asked for that).
        """
        self.received[topic] += 1
        if not self.active:
            self.count(topic, Rejected('inactive', WHY['inactive']))
            return None
        self.written[topic] += 1
        return topic, data

    def write_failed(self, topic, error):
        """Count a message of ``topic`` handed to the bag and refused there."""
        self.written[topic] -= 1
        self.count(topic, Rejected('write_failed', error))

    @property
    def dropped(self):
        """Return ``{(topic, reason): count}`` of the messages dropped."""
        return {key: n for key, n in self.rejected.items() if n}

    def summary(self, output):
        """
        Return the line that ends a recording into ``output``.

        What went into the bag, per topic, then what was dropped, per
        topic and reason, and why. Every message received is in one of
        the two.

        >>> r = Recording(['/a', '/b'])
        >>> r.message('/a', b'', 0.0)
        ('/a', b'')
        >>> r.reject('/b', Rejected('oversize', ''))
        >>> r.summary('bag')
        'recorded 1 message(s) into bag (/a: 1, /b: 0); dropped 1 (/b \
oversize: 1, larger than 4 MiB)'
        """
        line = (f'recorded {sum(self.written.values())} message(s) into '
                f'{output} (' + ', '.join(
                    f'{t}: {n}' for t, n in self.written.items()) + ')')
        dropped = self.dropped
        if dropped:
            line += (f'; dropped {sum(dropped.values())} (' + '; '.join(
                f'{topic} {reason}: {n}, {WHY[reason]}'
                for (topic, reason), n in dropped.items()) + ')')
        return line

    def period_counters(self):
        """Return the counters of the period's rate."""
        return dict(written=sum(self.written.values()))

    def status_rules(self, now, seconds, increases):
        """Return the drops and the wait steps."""
        return ((increases['rejected'], WARN,
                 f'{increases["rejected"]} message(s) dropped in the last '
                 'period'),
                (not any(self.received.values()), OK,
                 'waiting for messages'))

    def values(self, now, seconds, increases):
        """Return the rate and the counts of messages written and dropped."""
        return [('write rate (Hz)', increases['written'] / seconds),
                ('messages written', sum(self.written.values())),
                ('messages dropped', sum(self.rejected.values()))]
