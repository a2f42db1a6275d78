"""
When a service reply may be handed to rmw: the rule, without ROS.

rmw_fastrtps sends a reply only to the requesting client's reply reader
once its reply writer has matched it, and waits up to 100 ms for that match
with the Python GIL held: every thread of the node stops meanwhile. A reply
to a client that has left would stop the node 100 ms each time, so the node
(``managed_node.ManagedNode``'s ``reply_guard``) hands a reply to rmw only once
:meth:`ReplyRoutes.decide` says ``SEND``, polling the ROS graph (the
service's request writers and reply readers) while it says ``WAIT``, and
drops the reply when it says ``DROP``.

Whose reply it is. A client's request writer and reply reader belong to its
participant and share the participant's GUID prefix (the first
:data:`PREFIX` bytes of an endpoint's gid). rclpy does not give the
requesting writer's GUID, but the request's header gives the instant it was
received, and discovery lists a writer on the graph before any request of
it can arrive: the requester is among the participants whose writers the
first poll after that instant listed (:meth:`ReplyRoutes.requesters`). When
none of them is on the graph any more, the requester has gone: the reply is
dropped at once, whatever other clients are there (with "any reader listed"
instead, a client that came while a departed one's requests were still
being answered made each of those replies stop the node for 100 ms).

The rules, for the requester's participants (all listed writers when the
instant is unknown):

- its reply reader has been listed for :data:`REPLY_MATCH` s: ``SEND`` (the
  reply writer has matched it by then);
- after :data:`REPLY_WAIT` s with a reader listed: ``SEND``;
- a writer listed whose reader is not yet (a new client on a loaded
  machine: discovery brings the reader later): ``WAIT``, up to
  :data:`REPLY_DISCOVERY` s in all;
- otherwise, after REPLY_WAIT: ``DROP``;
- a reader listed when a reply timed out in rmw all the same (the graph
  still listed a client that had left: :meth:`ReplyRoutes.timed_out`) is
  *stale*: no reply goes to it (``DROP`` after REPLY_WAIT) until a stale
  reader has left the graph.

>>> routes = ReplyRoutes()
>>> a, b = bytes(12) + bytes(4), bytes([7]) * 12 + bytes(4)
>>> routes.poll(10.0, 0.0, writers=[a], readers=[a])
>>> routes.decide(received=9.99, now=0.06, begin=0.0)
'send'
>>> routes.poll(10.5, 0.5, writers=[b], readers=[b])   # a left, b came
>>> routes.decide(received=9.99, now=0.5, begin=0.5)   # a reply for a
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
# How long a reply waits, in all, for the reader of a client whose request
# writer is listed (s): discovery brings a new client's reader later on a
# loaded machine.
REPLY_DISCOVERY = 2.0
# Seconds of polls kept to name a request's requesters.
HISTORY = 60.0

SEND, WAIT, DROP = 'send', 'wait', 'drop'


def participant(gid):
    """Return the GUID prefix (the participant) of an endpoint's gid."""
    return bytes(gid)[:PREFIX]


class ReplyRoutes:
    """The graph of one service as its replies saw it, and the rule."""

    def __init__(self):
        # [first poll, last poll (wall s), participants with a writer]
        self._polls = []
        self._writers = frozenset()
        self._readers = {}      # reply reader gid -> monotonic s first seen
        self._stale = set()

    def poll(self, wall, monotonic, writers, readers):
        """Record a look at the graph: the gids of writers and readers."""
        listed = frozenset(map(participant, writers))
        if self._polls and self._polls[-1][2] == listed:
            self._polls[-1][1] = wall
        else:
            self._polls.append([wall, wall, listed])
        while len(self._polls) > 1 and self._polls[0][1] < wall - HISTORY:
            del self._polls[0]
        self._writers = listed
        self._readers = {bytes(gid): self._readers.get(bytes(gid), monotonic)
                         for gid in readers}
        if not self._stale <= self._readers.keys():
            self._stale.clear()     # a reader that had left is off the graph

    def requesters(self, received):
        """
        Return the participants a request received at ``received`` came from.

        ``received`` is wall time (s); the writers listed by the first poll
        after it. None when unknown (no instant, or that poll listed none).
        """
        if received is None:
            return None
        for _, last, listed in self._polls:
            if last >= received:
                return listed or None
        return None

    def decide(self, received, now, begin):
        """
        ``SEND``, ``WAIT`` or ``DROP`` a reply after the latest :meth:`poll`.

        ``received``: when its request arrived (wall s, None if unknown);
        ``now`` and ``begin`` (monotonic s): now, and when the reply began
        waiting.
        """
        requesters = self.requesters(received)
        clients = self._writers if requesters is None \
            else requesters & self._writers
        if requesters is not None and not clients:
            return DROP     # the requester has gone
        seen = {gid: first for gid, first in self._readers.items()
                if participant(gid) in clients}
        blocked = bool(self._stale & seen.keys())
        waited = now - begin >= REPLY_WAIT
        if seen and not blocked and (
                waited or now - max(seen.values()) >= REPLY_MATCH):
            return SEND
        discovering = bool(clients - set(map(participant, seen)))
        if waited and (blocked or not discovering
                       or now - begin >= REPLY_DISCOVERY):
            return DROP
        return WAIT

    def timed_out(self, received):
        """Mark stale the readers a reply timed out on in rmw (after SEND)."""
        requesters = self.requesters(received)
        self._stale.update(
            gid for gid in self._readers if requesters is None
            or participant(gid) in requesters)
