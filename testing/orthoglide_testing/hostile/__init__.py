"""
Hostile peers and stalls against the installed nodes.

Shared by ``test_hostile_peers.py`` and ``scripts/reliability_report.py``.
Every case starts the nodes from their console scripts (as ``ros2 run``
does), plays the peer from this process or from a child process of its own
(:mod:`.services` run as a script: ``burst``), and returns a dict of figures that
the tests assert on and the report prints:

- :func:`malformed_parameters`: set-parameters requests whose value type
  is not a ParameterType, to every node;
- :func:`absurd_parameters`: ``robot.l3 = 1e200`` and friends, at run time
  and at start-up;
- :func:`stamps`: a nanosecond field >= 1e9 on every input of the
  feedforward;
- :func:`startup_signals`: SIGINT and SIGTERM while a node starts;
- :func:`log_amplification`: long text inside messages, and a flood of
  malformed ones;
- :func:`departed_clients`: 100 requests from a client that then leaves;
- :func:`isolated_clients`: a client whose reply reader can never match
  stays, fresh clients call beside it; 150 ms stalls while answering;
- :func:`fast_simulator`: the simulator at 10 kHz with commands at 500 Hz;
- :func:`stall_resume`: the closed loop, one process stopped for 2 s
  (:func:`stall_resume_one_host`: the same on the one-host profile, in a
  network namespace);
- :func:`setpoint_loop`: the looping setpoint publisher's way back;
- :func:`trajectory_flood`: a new joint trajectory every millisecond to
  the tracking controller;
- :func:`absurd_values`: finite but absurd values (1e200, 1e300, 5 m) on
  the inputs of the feedforward and the controller.

(Big messages on an input are :func:`reliability.big_messages`: they
need its producer and recorder.) Every child process is stopped in a
``finally``; every wait is bounded. The peer and the nodes' processes:
:mod:`.peer`; the cases on services and processes: :mod:`.services`; on
the streams: :mod:`.streams`.
"""

from orthoglide_testing.hostile.peer import (  # noqa: F401
    HarnessError, HOLD, LOG_LINE_LIMIT, NODES, Nodes, Peer, START_TIMEOUT)
from orthoglide_testing.hostile.services import (  # noqa: F401
    absurd_parameters, departed_clients, isolated_clients, log_amplification,
    malformed_parameters, quiet, startup_signals)
from orthoglide_testing.hostile.streams import (  # noqa: F401
    absurd_values, fast_simulator, setpoint_loop, stall_resume,
    stall_resume_one_host, stamps, trajectory_flood, trajectory_peak_speed)
