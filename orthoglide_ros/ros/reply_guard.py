"""
Service callbacks and replies that can neither end nor stall a node.

:class:`ReplyGuard`, owned by every node, wraps each of its services
(:meth:`ReplyGuard.guard`) against two upstream behaviours
(doc/robustness.md#services): rclpy raising on a set-parameters request
whose value type does not exist, and rmw_fastrtps holding a reply for an
unmatched reader with the GIL held. It reads the DDS service topics
(``rq<service>Request``, ``rr<service>Reply``: rmw_fastrtps's naming) and
the requester from the request's header memory (:func:`requester`:
rclpy 7.1 does not expose ``request_id.writer_guid``).

Removal (``benchmarks/upstream_checks.py``, on plain rclpy): the request
check when rclpy answers a value of type 99 (``parameter_type``); the
reply rule when rmw_fastrtps sends to an unmatched reader at once
(``reply_stall``); the header read when rclpy exposes the requester
(``writer_guid``). If :func:`requester` stops finding the reader,
``test_service_replies.py`` fails and replies go as plain rclpy sends them.
"""

import ctypes
import time

from rclpy.qos import qos_check_compatible, QoSCompatibility

from rcl_interfaces.msg import ParameterType, SetParametersResult
from rcl_interfaces.srv import SetParameters, SetParametersAtomically

from orthoglide_ros.ros.service_replies import (DROP, REPLY_POLL,
                                                ReplyRoutes, SEND)
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

        A set-parameters request naming a value type that does not exist is
        refused whole with the reason; any other exception is a defect,
        answered with the default response. The reply waits, without the
        GIL, until :class:`~orthoglide_ros.ros.service_replies.ReplyRoutes`
        says it may go; one it drops is counted in :attr:`replies_dropped`.
        Returns ``service``.
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
            reader = requester(header)
            begin = time.monotonic()
            while True:
                now = time.monotonic()
                routes.poll(now, [
                    info.endpoint_gid for info in
                    node.get_publishers_info_by_topic(
                        request_topic, no_mangle=True)],
                    _reply_readers(node, reply_topic))
                decision = routes.decide(reader, now, begin)
                if decision == SEND:
                    break
                if decision == DROP:
                    self.replies_dropped += 1
                    return
                time.sleep(REPLY_POLL)
            start = time.monotonic()
            send(response, header)
            end = time.monotonic()
            routes.sent(reader, end, end - start)

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


def _reply_readers(node, reply_topic):
    """
    Return ``(gid, can_match)`` of each reader of a service's replies.

    ``can_match``: whether the node's own reply writer (as the graph lists
    it: the node's name and namespace) can match the reader's QoS (a
    TRANSIENT_LOCAL reader never matches the VOLATILE writer).
    """
    writers = [info.qos_profile for info in node.get_publishers_info_by_topic(
        reply_topic, no_mangle=True)
        if info.node_name == node.get_name()
        and info.node_namespace == node.get_namespace()]
    return [(info.endpoint_gid, not writers or qos_check_compatible(
        writers[0], info.qos_profile)[0] != QoSCompatibility.ERROR)
        for info in node.get_subscriptions_info_by_topic(
            reply_topic, no_mangle=True)]


# rmw_service_info_t as rclpy 7.1's pybind11 object holds it: the source and
# received timestamps (int64 ns), request_id's writer_guid (16 bytes) and
# sequence_number (int64).
class _ServiceInfo(ctypes.Structure):
    _fields_ = [('source_timestamp', ctypes.c_int64),
                ('received_timestamp', ctypes.c_int64),
                ('writer_guid', ctypes.c_uint8 * 16),
                ('sequence_number', ctypes.c_int64)]


# Where a pybind11 instance keeps the pointer to its C++ value: just after
# the object header (refcount and type).
_VALUE_POINTER = ctypes.sizeof(ctypes.c_ssize_t) + ctypes.sizeof(
    ctypes.c_void_p)


def requester(header):
    """
    Return the gid of the reply reader that made a request (bytes), or None.

    ``header``: the ``rmw_service_info_t`` rclpy hands to
    ``send_response``. Its ``request_id.writer_guid`` is not exposed by
    rclpy 7.1; it is read from the object's memory, and trusted only if
    the three fields rclpy does expose read the same there. None when they
    do not (another layout) or for any other header.
    """
    if type(header).__name__ != 'rmw_service_info_t':
        return None
    value = ctypes.c_void_p.from_address(id(header) + _VALUE_POINTER).value
    if not value:
        return None
    info = _ServiceInfo.from_address(value)
    if (info.source_timestamp, info.received_timestamp,
            info.sequence_number) != (header.source_timestamp,
                                      header.received_timestamp,
                                      header.request_id.sequence_number):
        return None
    return bytes(info.writer_guid)
