"""
The rule that decides when a service reply goes to rmw, per client.

Each case is a sequence of graph polls, as ``reply_guard`` makes them while
a reply waits, and the decision expected from the rule of
``orthoglide_ros.ros.service_replies`` for the reply reader that made the
request. The last case checks, on real rclpy and Fast DDS, that the
requesting reader is read from a request's header at all: the rule is
only as good as that (``reply_guard.requester``).
"""

import threading
import time

import pytest

from orthoglide_ros.ros.service_replies import (DROP, REPLY_DISCOVERY,
                                                REPLY_MATCH, REPLY_TIMED_OUT,
                                                REPLY_WAIT, ReplyRoutes, SEND,
                                                STALE_AFTER, STALE_RETRY, WAIT)


def gid(client, entity):
    """Return a 16-byte gid: participant ``client``, entity ``entity``."""
    return bytes([client]) * 12 + bytes([entity]) * 4


WRITER, READER = 3, 4
A_W, A_R, B_W, B_R = gid(1, WRITER), gid(1, READER), gid(2, WRITER), \
    gid(2, READER)


def poll(routes, t, writers, readers, unmatched=()):
    """Look at the graph at ``t``: readers in ``unmatched`` cannot match."""
    routes.poll(t, writers, [(r, r not in unmatched) for r in readers])


def test_a_listening_client_gets_its_reply_once_its_reader_is_matched():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [A_R])
    assert routes.decide(A_R, 0.0, 0.0) == WAIT
    poll(routes, REPLY_MATCH, [A_W], [A_R])
    assert routes.decide(A_R, REPLY_MATCH, 0.0) == SEND


def test_a_reply_to_a_departed_client_is_dropped_at_once_whoever_listens():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [A_R])         # A's requests arrive
    poll(routes, 1.0, [B_W], [B_R])         # A has left, B came
    # A reply to A never goes to rmw: rmw would wait 100 ms for A's reader
    # with the GIL held.
    assert routes.decide(A_R, 1.0, 1.0) == DROP
    # B's own request is answered once B's reader has been listed for
    # REPLY_MATCH.
    assert routes.decide(B_R, 1.0, 1.0) == WAIT
    poll(routes, 1.0 + REPLY_MATCH, [B_W], [B_R])
    assert routes.decide(B_R, 1.0 + REPLY_MATCH, 1.0) == SEND


def test_the_reply_waits_for_a_new_clients_reader_still_being_discovered():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W], [])            # A's writer listed, no reader
    assert routes.decide(A_R, 0.0, 0.0) == WAIT
    poll(routes, 1.5, [A_W], [])            # beyond REPLY_WAIT: still waits
    assert routes.decide(A_R, 1.5, 0.0) == WAIT
    poll(routes, 1.6, [A_W], [A_R])         # discovered
    poll(routes, 1.6 + REPLY_MATCH, [A_W], [A_R])
    assert routes.decide(A_R, 1.6 + REPLY_MATCH, 0.0) == SEND


def test_an_undiscovered_reader_is_waited_for_up_to_reply_discovery():
    routes = ReplyRoutes()
    poll(routes, REPLY_DISCOVERY, [A_W], [])
    assert routes.decide(A_R, REPLY_DISCOVERY, 0.0) == DROP
    # Counted as gone: its next reply is dropped at once.
    poll(routes, REPLY_DISCOVERY + 0.01, [A_W], [])
    assert routes.decide(A_R, REPLY_DISCOVERY + 0.01,
                         REPLY_DISCOVERY + 0.01) == DROP


def test_without_writer_or_reader_the_reply_is_dropped_after_reply_wait():
    routes = ReplyRoutes()
    poll(routes, 0.0, [], [])
    assert routes.decide(A_R, 0.0, 0.0) == WAIT
    poll(routes, REPLY_WAIT, [], [])
    assert routes.decide(A_R, REPLY_WAIT, 0.0) == DROP


def test_a_reader_that_cannot_match_costs_only_its_own_replies():
    """A TRANSIENT_LOCAL client beside a fresh one: only its reply dropped."""
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W, B_W], [A_R, B_R], unmatched=[A_R])
    assert routes.decide(A_R, 0.0, 0.0) == DROP      # at once, no wait
    poll(routes, REPLY_MATCH, [A_W, B_W], [A_R, B_R], unmatched=[A_R])
    assert routes.decide(B_R, REPLY_MATCH, REPLY_MATCH) == SEND
    for t in (1.0, 10.0, 100.0):          # and so on, as long as A stays
        poll(routes, t, [A_W, B_W], [A_R, B_R], unmatched=[A_R])
        assert routes.decide(A_R, t, t) == DROP
        assert routes.decide(B_R, t, t) == SEND


def test_one_slow_send_marks_nothing():
    """A node stalled while it sent one reply: the next replies all go."""
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W, B_W], [A_R, B_R])
    routes.sent(A_R, 1.0, 0.15)              # 150 ms: the node stalled
    routes.sent(B_R, 1.0, 0.15)
    poll(routes, 1.1, [A_W, B_W], [A_R, B_R])
    assert routes.decide(A_R, 1.1, 1.1) == SEND
    assert routes.decide(B_R, 1.1, 1.1) == SEND
    routes.sent(A_R, 1.2, 0.001)             # went through: forgotten
    for k in range(STALE_AFTER - 1):
        routes.sent(A_R, 2.0 + k, 0.2)
    routes.sent(A_R, 5.0, 0.001)
    routes.sent(A_R, 6.0, 0.2)
    poll(routes, 6.1, [A_W], [A_R])
    assert routes.decide(A_R, 6.1, 6.1) == SEND


def test_a_reader_whose_replies_keep_timing_out_is_tried_again_seldom():
    routes = ReplyRoutes()
    poll(routes, 0.0, [A_W, B_W], [A_R, B_R])
    for k in range(STALE_AFTER):
        routes.sent(A_R, 1.0 + k, REPLY_TIMED_OUT)
    last = STALE_AFTER
    poll(routes, last + 0.1, [A_W, B_W], [A_R, B_R])
    assert routes.decide(A_R, last + 0.1, last + 0.1) == DROP
    assert routes.decide(B_R, last + 0.1, last + 0.1) == SEND
    retry = last + STALE_RETRY
    poll(routes, retry, [A_W, B_W], [A_R, B_R])
    assert routes.decide(A_R, retry, retry) == SEND       # one try
    routes.sent(A_R, retry + 0.1, REPLY_TIMED_OUT)
    poll(routes, retry + 0.2, [A_W, B_W], [A_R, B_R])
    assert routes.decide(A_R, retry + 0.2, retry + 0.2) == DROP
    # Once it has left and come back under another gid, it is new.
    poll(routes, retry + 1.0, [B_W], [B_R])
    assert routes.decide(A_R, retry + 1.0, retry + 1.0) == DROP


def test_an_unknown_requester_is_answered_as_rclpy_would():
    routes = ReplyRoutes()
    poll(routes, 0.0, [], [])
    assert routes.decide(None, 0.0, 0.0) == SEND


@pytest.mark.ros
def test_the_requesting_reader_is_read_from_the_request_header(ros_context):
    """
    ``requester`` finds the client's reply reader on rclpy as installed.

    If this fails (a new rclpy or pybind11 lays the header out otherwise),
    every reply goes as plain rclpy sends it, and rmw's 100 ms stalls with
    the GIL held are back: the guard must be looked at again.
    """
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from std_srvs.srv import Trigger

    from orthoglide_ros.ros.reply_guard import requester

    server = Node('requester_server', context=ros_context)
    client_node = Node('requester_client', context=ros_context)
    found = []
    service = server.create_service(Trigger, 'requester_check',
                                    lambda request, response: response)
    send = service.send_response

    def recording_send(response, header):
        found.append(requester(header))
        send(response, header)
    service.send_response = recording_send
    client = client_node.create_client(Trigger, 'requester_check')
    executor = SingleThreadedExecutor(context=ros_context)
    for node in (server, client_node):
        executor.add_node(node)
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)
    thread = threading.Thread(target=spin)
    thread.start()
    try:
        assert client.wait_for_service(timeout_sec=10.0)
        future = client.call_async(Trigger.Request())
        deadline = time.monotonic() + 10.0
        while not future.done() and time.monotonic() < deadline:
            time.sleep(0.01)
        assert future.done()
        readers = [bytes(info.endpoint_gid) for info in
                   server.get_subscriptions_info_by_topic(
                       'rr/requester_checkReply', no_mangle=True)]
    finally:
        stop.set()
        thread.join()
        executor.shutdown()
    assert found and found[0] is not None
    assert readers == [found[0]]
    assert requester(object()) is None
