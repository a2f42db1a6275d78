"""
When the machine spoiled a run: the one rule the demos and tests judge by.

A run whose figures show the machine (a process stalled, a stream that
did not keep its rate: another load on two cores), not the nodes, is run
again or ends FAILED naming why, never judged on those figures:
:func:`pass_spoiled_by` for a pass of the closed loop
(:meth:`closed_loop.ClosedLoop.run_unspoiled`, the loop demos),
:func:`stream_spoiled_by` for the feedforward demo's setpoint stream
(``scripts/demo.py``).
"""

import numpy as np

from orthoglide_ros.cores.tracking_controller import PARAMETERS

# The controller's path tolerance (m, per actuator): a joint error beyond
# it made the controller stop following and hold.
PATH_TOLERANCE = np.array(next(s.default for s in PARAMETERS.specs
                               if s.name == 'path_tolerance'))
# A pass is spoiled when the plant skipped more simulated time than this
# (s): the simulator's default command timeout, the stall the loop's other
# processes are held to.
SKIP_LIMIT = 0.1
# A pass is spoiled when the plant applied one unchanged force for longer
# than this (s): half the command timeout, a stall the plant did not brake
# for. The loop changes it every period (4 ms at 250 Hz); one pass alone
# held one for 8-18 ms, beside a second loop of real-time nodes up to 74 ms
# (2026-12-06, test/test_closed_loop.py).
SAME_COMMAND_LIMIT = 0.05
# Passes run before giving up on an unspoiled one: on a fresh clone alone
# three in a row were once braked (2026-12-06).
ATTEMPTS = 5
# A stream is spoiled when fewer setpoints were sent than SENT_SHARE of
# duration x rate, two were more than GAP_PERIODS periods apart, or more
# outputs than LOSS_SHARE of those sent were lost.
SENT_SHARE = 0.95
GAP_PERIODS = 10.0
LOSS_SHARE = 0.005


def first_unspoiled(make, spoiled_by, heard=None, attempts=ATTEMPTS):
    """
    Return ``make()``'s first result nothing spoiled, else its last.

    The one home of the rule that a run the machine spoiled is run again:
    ``make()`` runs once, ``spoiled_by(result)`` names what spoiled it
    (None: nothing), ``attempts`` runs at most; ``heard(result, spoiled,
    attempt)`` (optional) hears about every spoiled run.
    """
    for attempt in range(1, attempts + 1):
        result = make()
        spoiled = spoiled_by(result)
        if spoiled is None:
            break
        if heard:
            heard(result, spoiled, attempt)
    return result


def pass_spoiled_by(run):
    """
    Return what spoiled a pass of the closed loop (text), None if nothing.

    ``run``: a :class:`closed_loop.Run` (its ``braked``, ``joint_error``,
    ``skipped_s`` and ``same_command_s``). Spoiled: the plant was braked in
    it, a joint error beyond the path tolerance (the controller held), the
    plant skipped more than SKIP_LIMIT of simulated time in all, or applied
    one force longer than SAME_COMMAND_LIMIT.
    """
    if run.braked:
        return f'the plant was braked for {run.braked} states'
    if run.same_command_s > SAME_COMMAND_LIMIT:
        return (f'the plant applied one force for '
                f'{run.same_command_s * 1e3:.0f} ms')
    if (np.abs(run.joint_error) > PATH_TOLERANCE).any():
        return 'a joint error beyond the path tolerance stopped the controller'
    if run.skipped_s > SKIP_LIMIT:
        return f'the plant skipped {run.skipped_s:.3f} s of simulated time'
    return None


def stream_spoiled_by(duration, rate, sent, gap_ms, lost):
    """
    Return why a setpoint stream did not keep its rate (empty: it did).

    ``duration`` (s) and ``rate`` (Hz) asked; ``sent``: setpoints the
    publisher said it sent, ``gap_ms``: the longest gap between two,
    ``lost``: outputs missing (each None if unknown).
    """
    expected = duration * rate
    period_ms = 1e3 / rate
    reasons = []
    if sent is None:
        reasons.append('the setpoint publisher did not say what it sent')
    elif sent < SENT_SHARE * expected:
        reasons.append(f'{sent} of {expected:.0f} setpoints sent '
                       f'({sent / duration:.0f} of {rate:g} Hz)')
    if gap_ms is not None and gap_ms > GAP_PERIODS * period_ms:
        reasons.append(f'a gap of {gap_ms:.1f} ms between two setpoints '
                       f'({gap_ms / period_ms:.0f} periods)')
    if sent and lost is not None and lost > LOSS_SHARE * sent:
        reasons.append(f'{lost} of {sent} outputs lost')
    return reasons
