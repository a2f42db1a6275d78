"""
The rule that decides when a service reply goes to rmw (no ROS needed).

Each case is a sequence of graph polls, as ``node_runtime`` makes them while
a reply waits, and the decision expected from the rule of
``orthoglide_ros.ros.service_replies``.
"""

from orthoglide_ros.ros.service_replies import (DROP, REPLY_DISCOVERY,
                                                REPLY_MATCH, REPLY_WAIT,
                                                ReplyRoutes, SEND, WAIT)


def gid(client, entity):
    """Return a 16-byte gid: participant ``client``, entity ``entity``."""
    return bytes([client]) * 12 + bytes([entity]) * 4


WRITER, READER = 3, 4
A_W, A_R, B_W, B_R = gid(1, WRITER), gid(1, READER), gid(2, WRITER), \
    gid(2, READER)
WALL = 1000.0   # wall clock (s) at monotonic 0


def poll(routes, t, writers, readers):
    routes.poll(WALL + t, t, writers, readers)


def test_a_listening_client_gets_its_reply_once_its_reader_is_matched():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [A_R])
    assert routes.decide(WALL - 0.001, 0.0, 0.0) == WAIT
    poll(routes, REPLY_MATCH, [A_W], [A_R])
    assert routes.decide(WALL - 0.001, REPLY_MATCH, 0.0) == SEND


def test_a_reply_to_a_departed_client_is_dropped_at_once_whoever_listens():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [A_R])         # A's requests arrive
    poll(routes, 1.0, [B_W], [B_R])         # A has left, B came
    # A reply to A (received before B came) never goes to rmw: rmw would
    # wait 100 ms for A's reader with the GIL held.
    assert routes.decide(WALL - 0.001, 1.0, 1.0) == DROP
    # B's own request, received after B came, is answered once B's reader
    # has been listed for REPLY_MATCH.
    assert routes.decide(WALL + 1.0, 1.0, 1.0) == WAIT
    poll(routes, 1.0 + REPLY_MATCH, [B_W], [B_R])
    assert routes.decide(WALL + 1.0, 1.0 + REPLY_MATCH, 1.0) == SEND


def test_the_reply_waits_for_a_new_clients_reader_still_being_discovered():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [])            # A's writer listed, no reader
    received = WALL - 0.001
    assert routes.decide(received, 0.0, 0.0) == WAIT
    poll(routes, 1.5, [A_W], [])            # beyond REPLY_WAIT: still waits
    assert routes.decide(received, 1.5, 0.0) == WAIT
    poll(routes, 1.6, [A_W], [A_R])         # discovered
    assert routes.decide(received, 1.6, 0.0) == SEND


def test_an_undiscovered_reader_is_waited_for_up_to_reply_discovery():
    routes = ReplyRoutes()
    poll(routes, REPLY_DISCOVERY, [A_W], [])
    assert routes.decide(WALL - 1.0, REPLY_DISCOVERY, 0.0) == DROP


def test_without_writer_or_reader_the_reply_is_dropped_after_reply_wait():
    routes = ReplyRoutes()
    poll(routes, 0.0, [], [])
    assert routes.decide(None, 0.0, 0.0) == WAIT
    poll(routes, REPLY_WAIT, [], [])
    assert routes.decide(None, REPLY_WAIT, 0.0) == DROP


def test_a_reader_listed_when_rmw_timed_out_gets_no_reply_until_it_leaves():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [A_R])
    routes.timed_out(WALL - 0.001)          # A had left: the graph lagged
    poll(routes, 0.2, [A_W], [A_R])
    assert routes.decide(WALL + 0.1, 0.2, 0.2) == WAIT
    poll(routes, 0.2 + REPLY_WAIT, [A_W], [A_R])
    assert routes.decide(WALL + 0.1, 0.2 + REPLY_WAIT, 0.2) == DROP
    # Once A is off the graph, a new client is answered again.
    poll(routes, 1.0, [B_W], [B_R])
    poll(routes, 1.0 + REPLY_MATCH, [B_W], [B_R])
    assert routes.decide(WALL + 0.95, 1.0 + REPLY_MATCH, 1.0) == SEND


def test_requesters_are_the_writers_of_the_first_poll_after_receipt():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [A_R])
    poll(routes, 0.5, [A_W], [A_R])
    poll(routes, 1.0, [A_W, B_W], [A_R, B_R])
    assert routes.requesters(WALL + 0.2) == {A_W[:12]}
    assert routes.requesters(WALL + 0.7) == {A_W[:12], B_W[:12]}
    assert routes.requesters(WALL + 2.0) is None     # not polled since
    assert routes.requesters(None) is None
