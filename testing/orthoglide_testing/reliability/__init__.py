"""
Cross-process reliability runs of the feedforward node.

Shared by the tests (``test_flood.py``, ``test_restarts.py``) and by
``scripts/reliability_report.py``, which runs the same functions longer:

- :func:`flood`: a producer publishes setpoints as fast as it can;
- :func:`reliable_stream`: a producer publishes at a steady rate over
  reliable QoS and every setpoint is matched to its output;
- :func:`kill_restart`: the node is SIGKILLed mid-stream and started again;
- :func:`producer_restart`: the producer is killed or stopped and another
  one starts with later or earlier stamps;
- :func:`big_messages`: a peer sends 3-16 MB messages on the same input
  while a reliable 500 Hz stream goes on.

Each run is four processes, so that no two share a GIL: the node (its
console script, as a user starts it), a producer and a recorder
(:mod:`.roles` run as a script: ``produce`` / ``record``) and this process, which
orchestrates them, watches ``/diagnostics``, asks the node for a parameter
and reads its memory and CPU time from ``/proc``. The producer publishes
with :class:`messages.Producer` (messages built once)
on the paper trajectory: the setpoint of stamp ``s`` ns is eq. (6) at
``t = (s mod 2 s)``, so an output can be checked from its stamp alone
(:func:`sample_at`). Stamps are grouped in epochs of 1000 s
(``stamp // EPOCH_NS``): each warm-up and each stream has its own, and the
recorder says on its standard output when a new epoch first shows up, when
outputs resume after a gap and when they stop.

The runs are :mod:`.cases`, their processes :mod:`.runs`, their checks
:mod:`.checks`. Every function returns a dict of figures (see
:func:`checks.summary_lines`); the
callers assert on them or print them. Every child process is stopped in a
``finally`` (SIGINT, wait, SIGKILL) and every wait is bounded.
"""

from orthoglide_testing.reliability.cases import (  # noqa: F401
    attack_payloads, ATTACKS, big_messages, flood, kill_restart,
    lossless_args, producer_restart, reliable_stream, stop_mid_stream)
from orthoglide_testing.reliability.checks import (  # noqa: F401
    check_outputs, in_epoch, match_stamps, problems, stalled_by,
    summary_lines)
from orthoglide_testing.reliability.runs import *  # noqa: F401,F403
