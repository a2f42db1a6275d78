"""
Service callbacks and replies that can neither end nor stall a node.

:class:`ReplyGuard`, owned by a node
(:class:`~orthoglide_ros.ros.managed_node.ManagedNode`), wraps every
service of the node: the parameter and lifecycle services as it is made,
each later one as the node creates it (:meth:`ReplyGuard.guard`).

Upstream behaviour it works around:

- rclpy raises, outside its own error handling, on a set-parameters
  request whose ``ParameterValue.type`` is not a ParameterType: the
  exception left the executor and ended the node. Such a request is
  refused whole with the reason.
- rmw_fastrtps holds a reply, up to 100 ms with the GIL held, while the
  requesting client's reply reader is not matched: a client that sent
  requests and left stalled every thread of the process (100 requests,
  6.3 s). A reply therefore waits, without the GIL, polling the graph,
  until :class:`~orthoglide_ros.ros.service_replies.ReplyRoutes` says it
  may go to rmw, and is dropped once its requester has gone. This reads
  the DDS service topics (``rq<service>Request``, ``rr<service>Reply``:
  rmw_fastrtps's naming) and the request's receive time from rclpy's
  private ``_rclpy`` header.

How to tell when it can go: when rclpy validates a request's parameter
types (test_hostile_peers.py's malformed requests then pass without it),
and when rmw_fastrtps drops a reply to a departed client at once
(``benchmarks/bench_replies.py`` on a plain rclpy node shows no stall).
"""

import time

from rcl_interfaces.msg import ParameterType, SetParametersResult
from rcl_interfaces.srv import SetParameters, SetParametersAtomically

from orthoglide_ros.ros.service_replies import (DROP, REPLY_POLL,
                                                REPLY_TIMED_OUT, ReplyRoutes,
                                                SEND)
from orthoglide_ros.formats.text import clip

# Parameter value types a request may carry (ParameterType's constants).
_PARAMETER_TYPES = frozenset(range(ParameterType.PARAMETER_NOT_SET,
                                   ParameterType.PARAMETER_STRING_ARRAY + 1))


class ReplyGuard:
    """
    Every service of a node guarded: its callback and its reply.

    Made once the node's parameter and lifecycle services exist, which it
    guards; the node's ``warn_throttled`` and ``report_defect`` report
    what it refuses.
    """

    def __init__(self, node):
        self._node = node
        self.replies_dropped = 0
        for service in node.services:
            self.guard(service)

    def guard(self, service):
        """
        Keep a service from ending or stalling the node.

        The callback: a set-parameters request naming a value type that
        does not exist (rclpy raises on it, outside its own error handling)
        is refused whole with the reason; any other exception is a defect,
        answered with the default response.

        The reply waits, without the GIL, polling the graph, until
        :class:`~orthoglide_ros.ros.service_replies.ReplyRoutes` (the rule)
        says it may go to rmw, which would otherwise wait for a departed
        client's reader up to 100 ms with the GIL held; a reply the rule
        drops is counted in :attr:`replies_dropped`. Returns ``service``.
        """
        node = self._node
        callback, send = service.callback, service.send_response
        reply_topic = f'rr{service.service_name}Reply'
        request_topic = f'rq{service.service_name}Request'
        srv_type = service.srv_type
        routes = ReplyRoutes()

        def guarded_callback(request, response):
            try:
                refusal = _malformed_parameters(srv_type, request)
                if refusal is None:
                    return callback(request, response)
            except Exception:   # a defect: answer, keep the node
                node.report_defect(f'in the service {service.service_name}')
                return srv_type.Response()
            node.warn_throttled('malformed request', refusal)
            result = SetParametersResult(successful=False, reason=refusal)
            if srv_type is SetParameters:
                response.results = [result] * len(request.parameters)
            else:
                response.result = result
            return response

        def guarded_send(response, header):
            # An rmw_service_info_t says when the request was received.
            received = getattr(header, 'received_timestamp', 0) * 1e-9 \
                or None
            begin = time.monotonic()
            while True:
                now = time.monotonic()
                routes.poll(
                    time.time(), now,
                    [info.endpoint_gid for info in
                     node.get_publishers_info_by_topic(
                         request_topic, no_mangle=True)],
                    [info.endpoint_gid for info in
                     node.get_subscriptions_info_by_topic(
                         reply_topic, no_mangle=True)])
                decision = routes.decide(received, now, begin)
                if decision == SEND:
                    break
                if decision == DROP:
                    self.replies_dropped += 1
                    return
                time.sleep(REPLY_POLL)
            start = time.monotonic()
            send(response, header)
            if time.monotonic() - start >= REPLY_TIMED_OUT:
                routes.timed_out(received)

        service.callback = guarded_callback
        service.send_response = guarded_send
        return service


def _malformed_parameters(srv_type, request):
    """Return why a set-parameters request is malformed, or None."""
    if srv_type not in (SetParameters, SetParametersAtomically):
        return None
    for parameter in request.parameters:
        if parameter.value.type not in _PARAMETER_TYPES:
            return (f'malformed request: parameter {clip(parameter.name, 100)}'
                    f' has value type {parameter.value.type}, which is not '
                    'a ParameterType; nothing set')
    return None
