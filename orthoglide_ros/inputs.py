"""
Rules every node applies to what it receives, without ROS.

- :class:`Rejected`: the one exception a core raises when an input breaks
  a rule; its ``reason`` is the key the node counts it under (and reports
  in ``/diagnostics`` as ``rejected <reason>``).
- :func:`check_stamp`: the one rule for a ``builtin_interfaces/Time``
  stamp, applied to every stamped input;
- the byte limits of the inputs: a message longer than its input's limit
  is refused (``oversize``) before any decoding, so its length cannot
  cost the node more than taking it from the middleware.
"""

# Largest stamp seconds an output can carry (builtin_interfaces/Time: int32).
STAMP_SEC_MAX = 2**31 - 1
NANOSECONDS = 10**9
# Byte limit of an input whose messages are small (a pose, a joint state of
# a few hundred joints, a command): 64 KiB, about 100 times the size of
# the largest well-formed one the package expects.
SMALL_MESSAGE_BYTES = 64 * 1024


class Rejected(ValueError):
    """An input refused by a rule; ``reason`` says which rule."""

    def __init__(self, reason, message):
        super().__init__(message)
        self.reason = reason


def check_stamp(stamp):
    """
    Refuse a stamp ``(sec, nanosec)`` that cannot pair or be published.

    Raises :class:`Rejected` (``stamp``) for nanoseconds outside [0, 1e9)
    (not a valid ``builtin_interfaces/Time``: the same instant would have
    two spellings, which never pair), a zero or negative stamp (it cannot
    tell one setpoint from another) and seconds beyond int32.

    >>> check_stamp((12, 5))
    >>> try:
    ...     check_stamp((12, 10**9))
    ... except Rejected as error:
    ...     print(error)
    stamp 12 s + 1000000000 ns: nanosec must lie in [0, 1e9)
    >>> try:
    ...     check_stamp((0, 0))
    ... except Rejected as error:
    ...     print(error.reason)
    stamp
    """
    sec, nanosec = stamp
    if not 0 <= nanosec < NANOSECONDS:
        raise Rejected('stamp', f'stamp {sec} s + {nanosec} ns: nanosec '
                       'must lie in [0, 1e9)')
    if sec < 0 or stamp == (0, 0):
        raise Rejected('stamp', (
            f'stamp {sec}.{nanosec:09d} cannot pair pose, twist and '
            'accel: stamp setpoints with their time'))
    if sec > STAMP_SEC_MAX:
        raise Rejected('stamp', (
            f'stamp {sec}.{nanosec:09d} is beyond the int32 seconds '
            'of builtin_interfaces/Time'))
