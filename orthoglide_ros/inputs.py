"""
Rules every node applies to what it receives, without ROS.

- :class:`Rejected`: the one exception a core raises when an input breaks
  a rule; its ``reason`` is the key the node counts it under (and reports
  in ``/diagnostics`` as ``rejected <reason>``).
- :func:`check_stamp`: the one rule for a ``builtin_interfaces/Time``
  stamp, applied to every stamped input.
"""

# Largest stamp seconds an output can carry (builtin_interfaces/Time: int32).
STAMP_SEC_MAX = 2**31 - 1


class Rejected(ValueError):
    """An input refused by a rule; ``reason`` says which rule."""

    def __init__(self, reason, message):
        super().__init__(message)
        self.reason = reason


def check_stamp(stamp):
    """
    Refuse a stamp ``(sec, nanosec)`` that cannot pair or be published.

    Raises :class:`Rejected` (``stamp``) for a zero or negative stamp (it
    cannot tell one setpoint from another) and seconds beyond int32.

    >>> check_stamp((12, 5))
    >>> try:
    ...     check_stamp((0, 0))
    ... except Rejected as error:
    ...     print(error.reason)
    stamp
    """
    sec, nanosec = stamp
    if sec < 0 or stamp == (0, 0):
        raise Rejected('stamp', (
            f'stamp {sec}.{nanosec:09d} cannot pair pose, twist and '
            'accel: stamp setpoints with their time'))
    if sec > STAMP_SEC_MAX:
        raise Rejected('stamp', (
            f'stamp {sec}.{nanosec:09d} is beyond the int32 seconds '
            'of builtin_interfaces/Time'))
