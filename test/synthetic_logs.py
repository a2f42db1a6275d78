"""
Logs of robots for the identification tests: synthetic, closed-loop, files.

- :func:`synthetic_log`: an excitation's log of a robot, ``lambda``
  quantised, forces with noise; :func:`one_actuator_log`: slider A alone
  moves; :func:`spoiled`: one sample of a log set to a value;
- :func:`closed_loop`: PD + a feedforward on TRUE's plant without DDS,
  logged as the simulator publishes;
- :func:`write_csv`, :func:`write_bag`, :func:`storage_file`: a log as a
  CSV file or a rosbag2 bag (rosbags, no ROS).
"""

import numpy as np

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools.identification import Log

TRUE = Robot(m5=18.75, m3=2.875, friction_viscous=(30.0, 40.0, 50.0),
             friction_coulomb=(5.0, 3.0, 4.0))
RATE = 1000.0           # Hz
DURATION = 30.0         # s
PERIOD = 6.0            # s, of the excitation
QUANTUM = 1e-6          # m, of the measured lambda
NOISE = 0.5             # N, standard deviation of the measured forces


def synthetic_log(robot, seed, period, noise_seed, duration=DURATION,
                  rate=RATE, noise=NOISE, velocities=False):
    """Return an excitation's log: quantised lambda, noisy forces."""
    motion = trajectory.excitation(seed, period)
    times = np.arange(0.0, duration, 1.0 / rate)
    solution = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times))
    rng = np.random.default_rng(noise_seed)
    return Log(times, np.round(solution.lambda_ / QUANTUM) * QUANTUM,
               solution.force + rng.normal(0.0, noise, (len(times), 3)),
               f'synthetic seed {seed}',
               lambdadots=solution.lambdadot if velocities else None)


def write_csv(path, log, order=(2, 0, 1)):
    """Write a log as CSV, columns shuffled (actuators in ``order``)."""
    quantities = [('lambda', log.lambdas), ('force', log.forces)]
    if log.lambdadots is not None:
        quantities.append(('lambdadot', log.lambdadots))
    header = ['note'] + [f'{q}_{"abc"[j]}' for q, _ in quantities
                         for j in order] + ['t']
    table = np.column_stack([values[:, list(order)]
                             for _, values in quantities] + [log.times])
    path.write_text(','.join(header) + '\n' + ''.join(
        'x,' + ','.join(map(repr, row)) + '\n' for row in table.tolist()))
    return path


def write_bag(path, log, storage, names=('slider_a', 'slider_b', 'slider_c'),
              topic='/joint_states', little_endian=True):
    """Write a log as JointState messages with rosbags (no ROS)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores
    store = get_typestore(Stores.ROS2_JAZZY)
    kind = 'sensor_msgs/msg/JointState'
    JointState = store.types[kind]
    Header = store.types['std_msgs/msg/Header']
    Time = store.types['builtin_interfaces/msg/Time']
    sliders = ('slider_a', 'slider_b', 'slider_c')
    order = [sliders.index(n) if n in sliders else i
             for i, n in enumerate(names)]
    plugin = {'mcap': StoragePlugin.MCAP,
              'sqlite3': StoragePlugin.SQLITE3}[storage]
    start = 1_700_000_000 * 10**9
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection(topic, kind, typestore=store)
        for t, lam, force in zip(log.times, log.lambdas, log.forces):
            stamp = start + round(t * 1e9)
            msg = JointState(
                header=Header(stamp=Time(sec=stamp // 10**9,
                                         nanosec=stamp % 10**9),
                              frame_id=''),
                name=list(names), position=lam[order].copy(),
                velocity=np.zeros(len(names)), effort=force[order].copy())
            writer.write(connection, stamp, store.serialize_cdr(
                msg, kind, little_endian=little_endian))


def storage_file(bag):
    (path,) = [p for p in bag.iterdir() if p.suffix in ('.mcap', '.db3')]
    return path


def spoiled(log, quantity, k, j, value):
    """Return ``log`` with ``quantity``'s sample k, column j set to value."""
    arrays = {'times': log.times.copy(), 'lambdas': log.lambdas.copy(),
              'forces': log.forces.copy(),
              'lambdadots': None if log.lambdadots is None
              else log.lambdadots.copy()}
    if quantity == 'times':
        arrays['times'][k] = value
    else:
        arrays[quantity][k, j] = value
    return log._replace(**arrays)


def one_actuator_log(seed=8):
    """Slider A follows an excitation's lambda_A; B and C stay at home."""
    times = np.arange(0.0, 20.0, 1e-3)
    lam = mechanics.solve_batch(TRUE, *trajectory.excitation_batch(
        trajectory.excitation(0, 5.0), times)).lambda_
    home = mechanics.solve(TRUE, (0.0, 0.0, 0.0)).lambda_
    lam[:, 1:] = home[1:]
    position = mechanics.forward_kinematics(TRUE, lam)
    velocity = np.gradient(position, 1e-3, axis=0)
    force = mechanics.solve_batch(TRUE, position, velocity, np.gradient(
        velocity, 1e-3, axis=0)).force
    rng = np.random.default_rng(seed)
    return Log(times, lam, force + rng.normal(0.0, NOISE, force.shape),
               'slider A only')


def closed_loop(model, sample, duration, loop_rate=250.0, plant_rate=500.0,
                gains=(20000.0, 1200.0)):
    """
    Run PD + ``model``'s feedforward on TRUE's plant, without DDS.

    The tracking controller's law at ``loop_rate`` (each command from the
    state at its tick, applied from the next tick on, as a drive does) on
    the simulator's plant (RK4, the command held over each step) at
    ``plant_rate``, following ``sample(t)`` (position, velocity,
    acceleration). Returns ``(log, rms)``: the log of each state with the
    force held over the step that led to it (as the simulator publishes
    them; ``lambda`` quantised to 1 um) and the RMS position error (m).
    """
    from orthoglide_ros.model.plant import Plant
    plant = Plant(TRUE)
    kp, kd = gains
    steps = round(plant_rate / loop_rate)
    times, lambdas, forces, errors = [], [], [], []
    force = (0.0, 0.0, 0.0)
    for k in range(round(duration * loop_rate)):
        p, v, a = sample(k / loop_rate)
        errors.append(np.subtract(plant.position, p))
        desired = mechanics.solve(model, p, v, a)
        now = mechanics.solve(TRUE, plant.position, plant.velocity)
        command = tuple(np.add(desired.force, kp * np.subtract(
            desired.lambda_, now.lambda_) + kd * np.subtract(
            desired.lambdadot, now.lambdadot)))
        for _ in range(steps):
            plant.step(force, 1.0 / plant_rate)
            times.append(plant.time)
            lambdas.append(mechanics.solve(TRUE, plant.position).lambda_)
            forces.append(force)
        force = command
    log = Log(np.array(times), np.round(np.array(lambdas) / QUANTUM)
              * QUANTUM, np.array(forces), 'closed loop')
    return log, float(np.sqrt(np.mean(np.sum(np.square(errors), axis=1))))


def excitation_sample(t, motion=trajectory.excitation(0, PERIOD)):
    return trajectory.excitation_sample(motion, t % PERIOD)
