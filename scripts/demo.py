"""
Demo: the feedforward node on the paper's trajectory, eq. (6), live.

Starts the ``feedforward`` node and the ``setpoint_publisher`` (eq. (6) in
real time) as two processes, records here everything the node publishes and
the setpoints it was sent, stops both with SIGINT, then checks every output
against :func:`mechanics.solve` of its setpoint and prints a summary. Writes
figures 3-8 of the paper (actuator displacements and powers: the node's
samples as points, eq. (6) through :func:`mechanics.solve_batch` as lines)
to a PNG, the robot moving along the run with the node's forces to a GIF
next to it, and optionally the samples to a CSV.

Run it through ``bash scripts/demo.sh`` (sets up .venv, keeps DDS on this
host, picks a ROS_DOMAIN_ID); ``scripts/demo.py --help`` for the options.
Exit code 0 on success, 1 if the node never answered, a process failed or
a check failed, 2 on a usage error.
"""

import argparse
from contextlib import ExitStack
import os
from pathlib import Path
import re
import subprocess
import sys
import tempfile
import threading
import time

# DDS stays on this host whoever starts the demo; a domain of its own.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(1 + os.getpid() % 232))

ROOT = Path(__file__).resolve().parents[1]

import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.executors import ExternalShutdownException  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import (HistoryPolicy, QoSProfile,  # noqa: E402
                       ReliabilityPolicy)

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import (AccelStamped, PoseStamped,  # noqa: E402
                               TwistStamped)
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import Float64MultiArray  # noqa: E402
from trajectory_msgs.msg import MultiDOFJointTrajectory  # noqa: E402

from orthoglide_ros.model import trajectory  # noqa: E402
from orthoglide_ros.model import mechanics  # noqa: E402
from orthoglide_ros.tools import drawing  # noqa: E402
from orthoglide_ros.tools.cli import CSV_COLUMNS  # noqa: E402
from orthoglide_ros.formats.params_file import load_robot  # noqa: E402
from orthoglide_testing import use_checkout  # noqa: E402
from orthoglide_testing.load import (add_load_options, REALTIME,  # noqa: E402
                                     busy_loops, check_load_options,
                                     realtime_args, realtime_client)
from orthoglide_testing.processes import interrupt  # noqa: E402
from orthoglide_testing.verdicts import stream_spoiled_by  # noqa: E402

use_checkout(ROOT)

BIN = Path(sys.executable).parent
PARAMS = ROOT / 'config' / 'orthoglide.yaml'
# Deep enough that a slow recorder loses nothing the node publishes.
QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                 reliability=ReliabilityPolicy.RELIABLE)
START_TIMEOUT = 15.0    # s the publisher waits for its two subscribers
DRAIN = 5.0             # s at most for the last outputs and diagnostics
DRAIN_IDLE = 1.5        # s without an output that end the drain early
STOP_TIMEOUT = 5.0      # s a process gets to exit after SIGINT
TOLERANCE = 1e-9        # largest accepted |node - mechanics.solve|
CURVE_SAMPLES = 401
# The animation of the run: frames at most, size (pixels).
ANIMATION_FRAMES = 30
ANIMATION_SIZE = (480, 480)
LEVELS = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}


class DemoError(Exception):
    """A failure reported as ``demo: error: ...`` with exit code 1."""


class Recorder(Node):
    """Record the node's outputs and the setpoints, with reception times."""

    def __init__(self, input_kind):
        super().__init__('orthoglide_demo_recorder')
        self._input = input_kind
        self.joints, self.forces, self.power = [], [], []
        self.diagnostics = []
        self.setpoints = {}             # stamp (ns) -> (p, v, a)
        self.node_seen = None           # the node was in the graph
        self._parts = ({}, {}, {})      # pose, twist, accel by stamp
        sub = self.create_subscription
        self._outputs = (
            sub(JointState, 'feedforward/joint_states', self._on_joints,
                QOS),
            sub(Float64MultiArray, 'feedforward/forces',
                lambda m: self.forces.append(tuple(m.data)), QOS),
            sub(Float64MultiArray, 'feedforward/power',
                lambda m: self.power.append(tuple(m.data)), QOS))
        sub(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)
        self.watching = False

    def watch_setpoints(self):
        """
        Subscribe to the setpoints once the node's outputs are matched.

        The publisher waits for this subscription (and the node's): so no
        setpoint flows before the node can answer here. Returns whether
        it subscribed now or earlier.
        """
        if self.watching or not all(
                s.get_publisher_count() for s in self._outputs):
            return self.watching
        self.watching = True
        sub = self.create_subscription
        if self._input == 'trajectory':
            sub(MultiDOFJointTrajectory, 'setpoint/trajectory',
                self._on_trajectory, QOS)
        else:
            for slot, (kind, name, part) in enumerate((
                    (PoseStamped, 'pose', lambda m: m.pose.position),
                    (TwistStamped, 'twist', lambda m: m.twist.linear),
                    (AccelStamped, 'accel', lambda m: m.accel.linear))):
                sub(kind, f'setpoint/{name}',
                    self._part_callback(slot, part), QOS)
        return True

    def outputs(self):
        """Return the fewest messages recorded on one of the outputs."""
        return min(len(self.joints), len(self.forces), len(self.power))

    def _on_joints(self, msg, info):
        # DDS's own timestamps (ns): the node's publication and the arrival
        # here, so a busy recorder does not inflate the latency.
        self.joints.append((_ns(msg.header.stamp), info['source_timestamp'],
                            info['received_timestamp'], tuple(msg.position),
                            tuple(msg.velocity), tuple(msg.effort)))

    def _on_diagnostics(self, msg):
        for status in msg.status:
            if status.hardware_id == 'orthoglide':
                level = LEVELS.get(ord(status.level), str(status.level))
                self.diagnostics.append((level, status.message, {
                    kv.key: kv.value for kv in status.values}))

    def _on_trajectory(self, msg):
        point = msg.points[0]
        stamp = _ns(msg.header.stamp) + _ns(point.time_from_start)
        self.setpoints[stamp] = tuple(_xyz(v) for v in (
            point.transforms[0].translation, point.velocities[0].linear,
            point.accelerations[0].linear))

    def _part_callback(self, slot, part):
        def callback(msg):
            stamp = _ns(msg.header.stamp)
            self._parts[slot][stamp] = _xyz(part(msg))
            if all(stamp in parts for parts in self._parts):
                self.setpoints[stamp] = tuple(
                    parts.pop(stamp) for parts in self._parts)
        return callback


def _ns(time_msg):
    return time_msg.sec * 10**9 + time_msg.nanosec


def _xyz(vector):
    return (vector.x, vector.y, vector.z)


def main(argv=None):
    """Run the demo; return the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    check_load_options(parser, args)
    started = time.monotonic()
    timing = None
    try:
        robot = load_robot(str(PARAMS))
        with busy_loops(args.load):
            record, logs, failures, timing = _run(args)
        try:
            _report(args, robot, record, logs)
        except DemoError as error:
            failures.insert(0, str(error))
    except DemoError as error:
        failures = [str(error)]
    except (KeyboardInterrupt, ExternalShutdownException):
        print('demo: interrupted', file=sys.stderr)
        return 130
    if timing is not None:
        startup, streamed, stopped = timing
        now = time.monotonic()
        print(f'took       {now - started:.1f} s: first setpoint '
              f'{startup:.1f} s after the launch, pass ended at '
              f'{streamed - started:.1f} s, drain and stop '
              f'{stopped - streamed:.1f} s, checks and plot '
              f'{now - stopped:.1f} s')
    for failure in failures:
        print(f'demo: error: {failure}', file=sys.stderr)
    if failures:
        print('verdict    FAILED (see above)', file=sys.stderr)
    return 1 if failures else 0


def _parser():
    parser = argparse.ArgumentParser(
        prog='demo.py', description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('--input', choices=('trajectory', 'topics'),
                        default='trajectory', help=(
                            "the node's input: one MultiDOFJointTrajectory "
                            'per setpoint (default) or pose, twist and '
                            'accel topics of equal stamp'))
    parser.add_argument('--rate', type=_rate, default=500.0, metavar='HZ',
                        help='setpoints per second, in [1, 10000] (default '
                        '500)')
    parser.add_argument('--duration', type=_duration, default=2.0,
                        metavar='S', help=(
                            'seconds of eq. (6) to stream, in (0, 2] '
                            "(default 2, the paper's)"))
    parser.add_argument('--plot', default=str(ROOT / 'out' / 'demo.png'),
                        metavar='FILE', help=(
                            'PNG of figures 3-8 (default out/demo.png in '
                            'the repository)'))
    parser.add_argument('--animation', metavar='FILE', help=(
        'GIF of the robot along the run, with the forces the node '
        'published (default: the plot\'s name with .gif)'))
    add_load_options(parser, realtime_default=REALTIME)
    parser.add_argument('--csv', metavar='FILE', help=(
        'write the recorded samples: ' + ','.join(CSV_COLUMNS) + ' (SI '
        'units; t in s since the first setpoint; lambdaddot is not '
        'published by the node and comes from mechanics.solve)'))
    return parser


def _rate(text):
    value = float(text)
    if not 1.0 <= value <= 10000.0:
        raise argparse.ArgumentTypeError(
            f'must lie in [1, 10000] Hz, got {text}')
    return value


def _duration(text):
    value = float(text)
    if not 0.0 < value <= trajectory.PAPER_DURATION:
        raise argparse.ArgumentTypeError(
            f'must lie in (0, {trajectory.PAPER_DURATION:g}] s, got {text}')
    return value


def _run(args):
    """
    Start the node and the publisher, record, stop both.

    Returns the :class:`Recorder`, the processes' output by name, the
    failures (messages) and the timing: (s from the launch to the first
    setpoint, monotonic end of the pass, monotonic end of the stop).
    """
    rclpy.init()
    processes, logs = {}, {}
    elevated = ExitStack()
    try:
        recorder = Recorder(args.input)
        # Not the EventsExecutor: it cannot pass the message info.
        executor = rclpy.executors.SingleThreadedExecutor()
        executor.add_node(recorder)
        elevated.enter_context(realtime_client(args.realtime))

        def spin(seconds, until=lambda: False):
            deadline = time.monotonic() + seconds
            while not until() and time.monotonic() < deadline:
                executor.spin_once(timeout_sec=0.02)
            return until()

        launched = time.time_ns()
        # Both at once; the publisher waits (at most START_TIMEOUT) for two
        # subscribers per setpoint topic: the node and this recorder, which
        # subscribes once it has matched the node's outputs.
        processes['feedforward'] = _start(logs, 'feedforward', [
            str(BIN / 'feedforward'), '--ros-args',
            '--params-file', str(PARAMS), *realtime_args(args.realtime)])
        publisher = processes['setpoint_publisher'] = _start(
            logs, 'setpoint_publisher', [
                str(BIN / 'setpoint_publisher'), '--ros-args',
                '-p', f'rate_hz:={args.rate!r}', '-p', f'input:={args.input}',
                '-p', f'duration:={args.duration!r}',
                '-p', 'min_subscribers:=2',
                '-p', f'start_delay:={START_TIMEOUT!r}',
                *realtime_args(args.realtime)])
        # matplotlib takes seconds to import on a busy machine: meanwhile.
        threading.Thread(target=_import_matplotlib, daemon=True).start()

        def pass_over():
            recorder.watch_setpoints()
            return _exited(processes)

        if not spin(START_TIMEOUT + args.duration + 10.0, pass_over):
            raise DemoError('the setpoint_publisher did not finish in time'
                            + _tail(logs, 'setpoint_publisher'))
        if publisher.poll() is None:
            raise DemoError(
                'the feedforward node exited early with code '
                f'{processes["feedforward"].returncode}'
                + _tail(logs, 'feedforward'))
        streamed = time.monotonic()
        recorder.node_seen = recorder.count_publishers(
            'feedforward/joint_states') > 0
        # Drain: one diagnostics message after the pass, and every output
        # it counts; or until no output comes for DRAIN_IDLE s.
        seen = len(recorder.diagnostics)
        deadline = time.monotonic() + DRAIN
        progress = (None, 0.0)
        while time.monotonic() < deadline and not (
                len(recorder.diagnostics) > seen and recorder.outputs()
                >= int(recorder.diagnostics[-1][2].get(
                    'outputs published', 0))):
            executor.spin_once(timeout_sec=0.02)
            count = recorder.outputs()
            if count != progress[0]:
                progress = (count, time.monotonic())
            elif time.monotonic() - progress[1] > DRAIN_IDLE:
                break
        killed = not interrupt(processes['feedforward'], STOP_TIMEOUT)
        first = min(recorder.setpoints, default=launched)
        timing = ((first - launched) / 1e9, streamed, time.monotonic())
        recorder.destroy_node()
        failures = [
            f'{name} exited with code {process.returncode}'
            + (f' (ignored SIGINT for {STOP_TIMEOUT:g} s, killed)'
               if killed and name == 'feedforward' else '')
            + _tail(logs, name)
            for name, process in processes.items() if process.returncode]
        return recorder, {name: log.read_text(errors='replace')
                          for name, log in logs.items()}, failures, timing
    finally:
        elevated.close()
        for process in processes.values():
            interrupt(process, STOP_TIMEOUT)
        rclpy.try_shutdown()
        for log in logs.values():
            log.unlink(missing_ok=True)


def _import_matplotlib():
    import matplotlib.backends.backend_agg  # noqa: F401
    import matplotlib.figure  # noqa: F401


def _start(logs, name, command):
    handle, path = tempfile.mkstemp(prefix=f'orthoglide-demo-{name}-',
                                    suffix='.log')
    logs[name] = Path(path)
    with os.fdopen(handle, 'wb') as log:
        return subprocess.Popen(command, stdin=subprocess.DEVNULL,
                                stdout=log, stderr=subprocess.STDOUT)


def _exited(processes):
    return any(p.poll() is not None for p in processes.values())


def _tail(logs, name, lines=20):
    text = logs[name].read_text(errors='replace').strip().splitlines()
    return '; its output:\n' + '\n'.join(text[-lines:]) if text else ''


def _report(args, robot, record, logs):
    """Check, summarise, plot; raise DemoError on a failed check."""
    match = re.search(r'published (\d+) setpoints.*: (mean .* gap '
                      r'([0-9.]+) ms)', logs['setpoint_publisher'])
    sent, pace, gap_ms = (int(match.group(1)), f' ({match.group(2)})',
                          float(match.group(3))) if match \
        else (None, '', None)
    joints = record.joints
    if not joints:
        raise DemoError(
            f'the feedforward node never answered: no output for '
            f'{sent if sent is not None else "the"} setpoints sent'
            + ('' if record.node_seen else
               ' (nothing publishes feedforward/joint_states)')
            + _diagnosis(record.diagnostics)
            + (f'; its output:\n{logs["feedforward"].strip()}'
               if logs['feedforward'].strip() else ''))
    setpoints = record.setpoints
    first = min(setpoints) if setpoints else joints[0][0]
    rows, worst, unmatched = [], 0.0, 0
    for i, (stamp, _, _, lam, lamd, force) in enumerate(joints):
        setpoint = setpoints.get(stamp)
        if setpoint is None:
            unmatched += 1
            continue
        s = mechanics.solve(robot, *setpoint)
        measured = [lam, lamd, force]
        expected = [s.lambda_, s.lambdadot, s.force]
        if len(record.forces) == len(joints):
            measured.append(record.forces[i])
            expected.append(s.force)
        if len(record.power) == len(joints):
            measured.append(record.power[i])
            expected.append(s.power)
        worst = max(worst, float(np.max(np.abs(
            np.subtract(measured, expected)))))
        power = record.power[i] if len(record.power) == len(joints) \
            else s.power
        rows.append(((stamp - first) / 1e9, *setpoint[0], *lam, *lamd,
                     *s.lambdaddot, *force, *power))
    table = np.array(rows).reshape(-1, len(CSV_COLUMNS))
    eq6 = max((float(np.max(np.abs(np.subtract(
        trajectory.paper_sample((stamp - first) / 1e9), value))))
        for stamp, value in setpoints.items()), default=float('nan'))

    diagnostics = record.diagnostics
    final = diagnostics[-1][2] if diagnostics else {}
    live = [d for d in diagnostics if d[2].get('stale') == 'false']
    shown = live[-1] if live else (diagnostics[-1] if diagnostics else None)
    received = sum(int(final.get(f'received {k}', 0)) for k in (
        ('trajectory',) if args.input == 'trajectory' else ('pose',)))
    rejected = sum(int(v) for k, v in final.items()
                   if k.startswith('rejected '))
    stamps = np.array([j[0] for j in joints])
    published = (np.array([j[1] for j in joints]) - stamps) / 1e6
    latency = (np.array([j[2] for j in joints]) - stamps) / 1e6
    lost = (sent - len(joints)) if sent is not None else None
    where = ''
    if lost and diagnostics:
        output = int(final.get('outputs published', 0))
        where = (f' ({sent - received} on the way to the node, '
                 f'{received - output} rejected or unpaired there, '
                 f'{output - len(joints)} on the way here)')

    print(f'Orthoglide feedforward demo: eq. (6) for {args.duration:g} s at '
          f'{args.rate:g} Hz, input {args.input} (ROS_DOMAIN_ID '
          f'{os.environ["ROS_DOMAIN_ID"]}, localhost only)')
    print(f'setpoints  sent {_n(sent)}{pace}, received by the node '
          f'{received if diagnostics else "?"}, recorded here '
          f'{len(setpoints)}')
    print(f'outputs    received {len(joints)} joint_states, '
          f'{len(record.forces)} forces, {len(record.power)} power; '
          f'lost {_n(lost)}{where}')
    print(f'latency    setpoint stamp -> reception here: p50 '
          f'{np.percentile(latency, 50):.2f} ms, p99 '
          f'{np.percentile(latency, 99):.2f} ms, max {latency.max():.2f} ms '
          f'(-> node publishes: p50 {np.percentile(published, 50):.2f} ms, '
          f'p99 {np.percentile(published, 99):.2f} ms)')
    print(f'check      max |node - mechanics.solve| {worst:.3g} over '
          f'{len(rows)} samples ({unmatched} without setpoint); max '
          f'|setpoint - eq. (6)| {eq6:.3g} m')
    print(f'{"":24}{"A":>10}{"B":>10}{"C":>10}')
    for label, column in (('peak |lambda| (mm)', 4), ('peak |force| (N)', 13),
                          ('peak |power| (W)', 16)):
        peak = np.abs(table[:, column:column + 3]).max(0) * (
            1e3 if column == 4 else 1.0)
        print(f'{label:24}' + ''.join(f'{v:10.2f}' for v in peak))
    if shown is not None:
        level, message, values = shown
        print(f'node       {level} {message!r}: tick rate '
              f'{float(values["tick rate (Hz)"]):.1f} Hz, compute mean '
              f'{float(values["compute time mean (us)"]):.1f} us, max '
              f'{float(values["compute time max (us)"]):.1f} us; '
              f'computed {final.get("setpoints computed")}, published '
              f'{final.get("outputs published")}, rejected {rejected}')
    else:
        print('node       no diagnostics received')

    _write(args.plot, _plot_png(robot, table))
    print(f'plot       {_shown(args.plot)}')
    animation = args.animation or str(Path(args.plot).with_suffix('.gif'))
    rows = drawing.frame_rows(len(table), ANIMATION_FRAMES)
    span = table[rows[-1], 0] - table[rows[0], 0]
    fps = min(50.0, max(1.0, (len(rows) - 1) / span)) if span > 0 else 1.0
    _write(animation, drawing.animate(
        robot, table[rows, 0], table[rows, 1:4], table[rows, 13:16],
        ANIMATION_SIZE, fps, 'Orthoglide feedforward node'))
    print(f'animation  {_shown(animation)} ({len(rows)} frames, the '
          'forces the node published)')
    if args.csv:
        _write(args.csv, _csv_text(table))
        print(f'csv        {_shown(args.csv)} (lambdaddot from '
              'mechanics.solve)')
    if worst > TOLERANCE:
        raise DemoError(f'the node differs from mechanics.solve by '
                        f'{worst:.3g} (tolerance {TOLERANCE:g})')
    # A run the machine spoiled (load, a stall) is FAILED, not OK.
    spoiled = stream_spoiled_by(args.duration, args.rate, sent, gap_ms,
                                lost)
    if spoiled:
        raise DemoError('the run was spoiled, its figures do not show the '
                        'node: ' + '; '.join(spoiled) + ' (another load on '
                        'this machine? see --realtime)')
    print('verdict    OK: every output matches mechanics.solve, the stream '
          'kept its rate')


def _diagnosis(diagnostics):
    """Return the node's last diagnostics as '; node: ...', or ''."""
    if not diagnostics:
        return '; no diagnostics from the node either'
    level, message, values = diagnostics[-1]
    counts = ', '.join(
        f'{k} {v}' for k, v in values.items()
        if k.startswith(('received ', 'rejected ')) and v != '0')
    return f'; node diagnostics: {level} {message!r}; {counts or "no counts"}'


def _shown(path):
    """Return ``path`` relative to the working directory if inside it."""
    relative = os.path.relpath(path)
    return path if relative.startswith('..') else relative


def _n(value):
    return '?' if value is None else str(value)


def _plot_png(robot, table):
    """Figures 3-8: measured samples as points, eq. (6) as lines; PNG bytes."""
    import io
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    times = trajectory.paper_times(CURVE_SAMPLES)
    curve = mechanics.solve_batch(robot, *trajectory.paper_batch(times))
    figure = Figure(figsize=(13, 7), layout='constrained')
    FigureCanvasAgg(figure)
    axes = figure.subplots(2, 3, sharex=True)
    t = table[:, 0]
    for j, leg in enumerate('ABC'):
        top, bottom = axes[0, j], axes[1, j]
        top.plot(t, table[:, 4 + j] * 1e3, '.', color='tab:blue',
                 markersize=4, alpha=0.5, label='node (received)')
        top.plot(times, curve.lambda_[:, j] * 1e3, color='k', linewidth=1,
                 label='eq. (6), mechanics.solve_batch')
        top.set_title(f'Fig. {3 + j}: displacement of actuator {leg}')
        top.set_ylabel(f'$\\lambda_{leg}$ (mm)')
        bottom.plot(t, table[:, 16 + j], '.', color='tab:red',
                    markersize=4, alpha=0.5, label='node (received)')
        bottom.plot(times, curve.power[:, j], color='k', linewidth=1,
                    label='eq. (6), mechanics.solve_batch')
        bottom.set_title(f'Fig. {6 + j}: power of actuator {leg}')
        bottom.set_ylabel(f'$p_{leg}$ (W)')
        bottom.set_xlabel('t (s since the first setpoint)')
        for ax in (top, bottom):
            ax.grid(True, alpha=0.4)
            ax.legend(loc='best', fontsize='x-small')
    figure.suptitle(f'Orthoglide feedforward node on the trajectory of eq. '
                    f'(6): Figs. 3-8 ({len(table)} samples)')
    buffer = io.BytesIO()
    figure.savefig(buffer, format='png', dpi=100)
    return buffer.getvalue()


def _csv_text(table):
    lines = [','.join(CSV_COLUMNS)]
    lines += [','.join(map(repr, row)) for row in table.tolist()]
    return ('\n'.join(lines) + '\n').encode('utf-8')


def _write(path, data):
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    except OSError as error:
        raise DemoError(f'cannot write {path}: {error.strerror}') from None


if __name__ == '__main__':
    raise SystemExit(main())
