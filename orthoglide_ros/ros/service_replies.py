"""
When a service reply may be handed to rmw: the rule, per client, without ROS.

:meth:`ReplyRoutes.decide` says ``SEND``, ``WAIT`` or ``DROP`` for a
reply, from the graph as last polled, for the requesting client's own
reply reader (``request_id.writer_guid``, the reader's gid); the rules
and why (rmw_fastrtps waits for an unmatched reader with the GIL held):
doc/robustness.md#services. A requester unknown (a header rclpy did not
let us read) gets ``SEND``, as rclpy itself would. It goes with
:mod:`reply_guard`'s workaround, once rmw_fastrtps sends a reply to an
unmatched reader at once (``benchmarks/upstream_checks.py``,
``reply_stall``).

>>> routes = ReplyRoutes()
>>> a_writer, a_reader = bytes(12) + b'wwww', bytes(12) + b'rrrr'
>>> routes.poll(0.0, writers=[a_writer], readers=[(a_reader, True)])
>>> routes.decide(a_reader, now=0.0, begin=0.0)
'wait'
>>> routes.poll(0.06, writers=[a_writer], readers=[(a_reader, True)])
>>> routes.decide(a_reader, now=0.06, begin=0.0)
'send'
>>> routes.poll(0.5, writers=[], readers=[])              # a left
>>> routes.decide(a_reader, now=0.5, begin=0.5)
'drop'
"""

# Bytes of an endpoint's gid that name its participant (the GUID prefix).
PREFIX = 12
# How long a reply waits for its client's reader at most, and how often the
# graph is polled meanwhile (s).
REPLY_WAIT, REPLY_POLL = 0.1, 0.005
# How long a reader must have been on the graph before a reply goes to it
# (s): the reply writer matches it meanwhile.
REPLY_MATCH = 0.05
# A reply that took this long timed out in rmw (its wait is 100 ms).
REPLY_TIMED_OUT = 0.09
# Replies to one reader that must time out in a row before it is stale,
# and how often a stale reader is tried again (s).
STALE_AFTER, STALE_RETRY = 3, 5.0
# How long a reply waits, in all, for the reader of a client whose request
# writer is listed (s): discovery brings a new client's reader later on a
# loaded machine.
REPLY_DISCOVERY = 2.0
# Seconds a reader that left is remembered (its replies dropped at once).
GONE_KEPT = 60.0

SEND, WAIT, DROP = 'send', 'wait', 'drop'


def participant(gid):
    """Return the GUID prefix (the participant) of an endpoint's gid."""
    return bytes(gid)[:PREFIX]


class ReplyRoutes:
    """The reply readers of one service as its replies saw them, and the rule."""

    def __init__(self):
        self._listed = {}       # reader gid -> (monotonic s first listed,
        #                                        whether the writer can match)
        self._writers = frozenset()     # participants with a request writer
        self._gone = {}         # reader gid -> monotonic s it was found gone
        self._timeouts = {}     # reader gid -> (replies timed out in a row,
        #                                      monotonic s of the last)

    def poll(self, now, writers, readers):
        """
        Record a look at the graph at monotonic ``now`` (s).

        ``writers``: the gids of the service's request writers; ``readers``:
        ``(gid, can_match)`` of its reply readers.
        """
        listed = {}
        for gid, can_match in readers:
            gid = bytes(gid)
            listed[gid] = (self._listed.get(gid, (now,))[0], can_match)
        for gid in self._listed.keys() - listed.keys():
            self._left(gid, now)
        self._gone = {gid: left for gid, left in self._gone.items()
                      if left >= now - GONE_KEPT and gid not in listed}
        self._listed = listed
        self._writers = frozenset(map(participant, writers))

    def decide(self, reader, now, begin):
        """
        ``SEND``, ``WAIT`` or ``DROP`` a reply to ``reader`` (its gid).

        After the latest :meth:`poll`; ``now`` and ``begin`` (monotonic s):
        now, and when the reply began waiting. ``reader`` None: unknown.
        """
        if reader is None:
            return SEND
        if reader in self._gone:
            return DROP
        listed = self._listed.get(reader)
        if listed is not None:
            first, can_match = listed
            timeouts, last = self._timeouts.get(reader, (0, None))
            if not can_match or (timeouts >= STALE_AFTER
                                 and now - last < STALE_RETRY):
                return DROP
            if now - first >= REPLY_MATCH or now - begin >= REPLY_WAIT:
                return SEND
            return WAIT
        patience = REPLY_DISCOVERY if participant(reader) in self._writers \
            else REPLY_WAIT
        if now - begin >= patience:
            self._left(reader, now)
            return DROP
        return WAIT

    def sent(self, reader, now, seconds):
        """Record that a reply to ``reader`` took ``seconds`` until ``now``."""
        if reader is None:
            return
        if seconds >= REPLY_TIMED_OUT:
            timeouts = self._timeouts.get(reader, (0, now))[0]
            self._timeouts[reader] = (timeouts + 1, now)
        else:
            self._timeouts.pop(reader, None)

    def _left(self, reader, now):
        self._gone[reader] = now
        self._timeouts.pop(reader, None)
