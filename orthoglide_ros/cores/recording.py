"""
The recorder's logic without ROS: which message goes into the bag.

:class:`Recording` is the core (:mod:`orthoglide_ros.cores.core`) of the
node behind ``orthoglide record``: one input per topic recorded, each
message's serialized bytes returned unchanged to be written, and counted
per topic; a message refused before it was read (longer than its byte
limit) is counted by reason and written nowhere.
"""

from orthoglide_ros.cores.core import Core
from orthoglide_ros.cores.status import OK, WARN


class Recording(Core):
    """What was recorded, per topic (``received``), and what was refused."""

    REASONS = ('oversize', 'malformed')
    INACTIVE = 'inactive: messages counted, not recorded'

    def __init__(self, topics, now=0.0):
        """Record ``topics`` (their resolved names)."""
        self.INPUTS = tuple(topics)
        super().__init__(None, now)
        self.written = 0

    def message(self, topic, data, now):
        """Take one message of ``topic``; return ``(topic, data)`` to write."""
        self.received[topic] += 1
        if not self.active:
            return None
        self.written += 1
        return topic, data

    def period_counters(self):
        """Return the counters of the period's rate."""
        return dict(written=self.written)

    def ladder(self, now, seconds, new):
        """Return the rejections and the wait steps."""
        return ((new['rejected'], WARN,
                 f'{new["rejected"]} message(s) refused in the last period'),
                (self.written == 0, OK, 'waiting for messages'))

    def values(self, now, seconds, new):
        """Return the rate and the count of messages written."""
        return [('write rate (Hz)', new['written'] / seconds),
                ('messages written', self.written)]
