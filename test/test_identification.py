"""
Identification of the masses and the slider friction from logs, without ROS.

Synthetic logs: 30 s at 1 kHz of an excitation motion, the forces of a
"true" robot that the nominal (paper's) robot does not know (a 25 %
heavier platform, heavier bars, friction on every slider), the measured
``lambda`` quantised to 1 um, Gaussian noise of 0.5 N on every force
(seeded generators). Checked:

- the regressor reproduces the inverse dynamics (``W theta = f``);
- the base parameters found numerically are those of a hand argument:
  the slider (body 1) and the rod it carries (body 2, whose origin A2 is
  its centre) translate together along the slider's axis, so only ``m1 +
  m2`` matters; the two bars of a parallelogram (bodies 3 and 6) move
  alike, ``m3 + m6``; body 4's centre is A5, which translates with the
  platform (the rod turns only about its own axis), so the three rods 4
  weigh as ``3 m4`` of platform, ``m5 + 3 m4``; the friction coefficients
  each alone. Each combination is carried by its largest nominal member;
- every base parameter is identified within four of its standard
  deviations, and those deviations are honest: over several noise
  realisations the spread of the estimates is of their size;
- on another motion the identified robot predicts the forces as well as
  the true robot does, and far better than the nominal one;
- the split rule keeps nominal values where it can;
- the log readers: CSV and rosbag2 bags (MCAP and sqlite3) written here by
  the rosbags library, joint names in any order, big-endian messages too.
"""

import math

from mechanics_reference import OTHER_ROBOT_VALUES
import numpy as np
from orthoglide_ros import identification, mechanics, trajectory
from orthoglide_ros.identification import (
    IdentificationError, Log, LogError, STANDARD)
from orthoglide_ros.robot import Robot
import pytest

NOMINAL = Robot()
TRUE = Robot(m5=18.75, m3=2.875, friction_viscous=(30.0, 40.0, 50.0),
             friction_coulomb=(5.0, 3.0, 4.0))
RATE = 1000.0           # Hz
DURATION = 30.0         # s
QUANTUM = 1e-6          # m, of the measured lambda
NOISE = 0.5             # N, standard deviation of the measured forces
SIGMAS = 4.0


def synthetic_log(robot, seed, period, noise_seed, duration=DURATION,
                  rate=RATE, noise=NOISE):
    """Return an excitation's log: quantised lambda, noisy forces."""
    motion = trajectory.excitation(seed, period)
    times = np.arange(0.0, duration, 1.0 / rate)
    solution = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times))
    rng = np.random.default_rng(noise_seed)
    return Log(times, np.round(solution.lambda_ / QUANTUM) * QUANTUM,
               solution.force + rng.normal(0.0, noise, (len(times), 3)),
               f'synthetic seed {seed}')


@pytest.fixture(scope='module')
def base():
    return identification.base_parameters(NOMINAL)


@pytest.fixture(scope='module')
def result(base):
    return identification.identify(
        NOMINAL, synthetic_log(TRUE, 0, 10.0, 1), base=base)


def random_states(seed, n):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-0.25, 0.25, (n, 3)), rng.uniform(-1.0, 1.0, (n, 3)),
            rng.uniform(-10.0, 10.0, (n, 3)))


@pytest.mark.parametrize('values', [
    TRUE.as_parameters(), OTHER_ROBOT_VALUES | {
        'friction_viscous': (3.0, 0.0, 7.0),
        'friction_coulomb': (0.5, 9.0, 0.0), 'friction_velocity': 0.003}],
    ids=['true', 'other'])
def test_regressor_times_parameters_is_the_inverse_dynamics(values):
    robot = Robot(**values)
    states = random_states(1, 300)
    w = identification.regressor(robot, *states)
    assert w.shape == (300, 3, len(STANDARD))
    expected = mechanics.solve_batch(robot, *states).force
    got = w @ identification.standard_parameters(robot)
    assert np.abs(got - expected).max() <= 1e-12 * np.abs(expected).max()


def hand_combinations(robot):
    """Return the module docstring's combinations, carried by the largest."""
    rows = []
    for members in ({'m1': 1.0, 'm2': 1.0}, {'m3': 1.0, 'm6': 1.0},
                    {'m5': 1.0, 'm4': 3.0}):
        carrier = max(members, key=lambda m: members[m] * getattr(robot, m))
        row = np.zeros(len(STANDARD))
        for name, factor in members.items():
            row[STANDARD.index(name)] = factor / members[carrier]
        rows.append(row)
    for k in range(6, 12):
        rows.append(np.eye(len(STANDARD))[k])
    return np.array(rows)


@pytest.mark.parametrize('values', [{}, OTHER_ROBOT_VALUES],
                         ids=['paper', 'other'])
def test_base_parameters_are_the_hand_combinations(values):
    robot = Robot(**values)
    found = identification.base_parameters(robot)
    expected = hand_combinations(robot)
    order = np.lexsort(found.matrix.T[::-1])
    assert np.allclose(found.matrix[order],
                       expected[np.lexsort(expected.T[::-1])],
                       rtol=0.0, atol=1e-9)
    for row, carrier in zip(found.matrix, found.independent):
        assert row[carrier] == 1.0
    # On fresh states, W theta = W[:, independent] (P theta), any theta.
    states = random_states(2, 200)
    w = identification.regressor(robot, *states)
    theta = np.random.default_rng(3).uniform(0.1, 20.0, len(STANDARD))
    assert np.allclose(w @ theta, w[:, :, list(found.independent)]
                       @ (found.matrix @ theta), rtol=1e-12, atol=1e-9)


def test_base_names_read_as_combinations(base):
    assert base.names == ('m1 + m2', 'm3 + m6', 'm5 + 3 m4', 'viscous_a',
                          'viscous_b', 'viscous_c', 'coulomb_a', 'coulomb_b',
                          'coulomb_c')


def test_every_base_parameter_is_found_within_four_deviations(base, result):
    truth = base.matrix @ identification.standard_parameters(TRUE)
    error = result.values - truth
    assert (np.abs(error) <= SIGMAS * result.std).all(), (
        dict(zip(base.names, error / result.std)))
    # The excitation excites every one of them.
    assert (result.relative_std < 5.0).all(), result.relative_std
    assert result.condition < 1e3
    assert result.notes == []
    # The residual is what the filtered noise and the filter leave.
    assert (result.residual_rms < NOISE).all()
    assert len(result.samples.times) >= 500


def test_standard_deviations_are_those_of_the_estimates(base):
    """Over six noise realisations the spread is of the reported size."""
    runs = [identification.identify(NOMINAL, synthetic_log(
        TRUE, 0, 10.0, seed, duration=20.0), base=base) for seed in range(6)]
    spread = np.std([r.values for r in runs], axis=0, ddof=1)
    reported = np.mean([r.std for r in runs], axis=0)
    ratio = spread / reported
    assert ((ratio > 0.3) & (ratio < 3.0)).all(), dict(
        zip(base.names, ratio))


def test_identified_robot_predicts_another_motion(result):
    validation = identification.prepare(
        NOMINAL, synthetic_log(TRUE, 7, 4.0, 99, duration=8.0))
    rms = {name: np.sqrt(np.mean((validation.forces - identification.predict(
        robot, validation)) ** 2, axis=0))
        for name, robot in (('nominal', NOMINAL), ('true', TRUE),
                            ('identified', result.robot))}
    assert (rms['identified'] <= 1.1 * rms['true'] + 0.02).all(), rms
    assert (rms['nominal'] >= 20.0 * rms['identified']).all(), rms


def test_split_keeps_nominal_values_where_it_can(base, result):
    robot = result.robot
    # m2, m6 and m4 keep their nominal values; m1, m3 and m5 carry the
    # combinations (their nominal shares are the larger ones).
    assert (robot.m2, robot.m4) == (NOMINAL.m2, NOMINAL.m4)
    assert robot.m6 == NOMINAL.m6
    values = dict(zip(base.names, result.values))
    assert robot.m1 + robot.m2 == pytest.approx(values['m1 + m2'])
    assert robot.m3 + robot.m6 == pytest.approx(values['m3 + m6'])
    assert robot.m5 + 3 * robot.m4 == pytest.approx(values['m5 + 3 m4'])
    assert robot.friction_viscous == tuple(result.values[3:6])
    assert robot.friction_velocity == NOMINAL.friction_velocity


def test_split_scales_or_keeps_what_its_carrier_cannot_take(base):
    values = base.matrix @ identification.standard_parameters(NOMINAL)
    values[0] = 0.1                     # m1 + m2 below the nominal m2
    values[3] = -0.2                    # a viscous coefficient below zero
    robot, notes = identification.split(NOMINAL, base, values)
    assert robot.m1 == pytest.approx(NOMINAL.m1 * 0.1 / 0.55)
    assert robot.m2 == pytest.approx(NOMINAL.m2 * 0.1 / 0.55)
    assert robot.friction_viscous[0] == 0.0
    assert len(notes) == 2 and 'scaled' in notes[0] and '0' in notes[1]
    values[2] = -1.0                    # no platform can weigh that
    robot, notes = identification.split(NOMINAL, base, values)
    assert (robot.m4, robot.m5) == (NOMINAL.m4, NOMINAL.m5)
    assert len(notes) == 3
    assert 'm5 + 3 m4' in notes[1] and 'nominal value 15.6 kg' in notes[1]
    values[2] = 2e6                     # beyond the robot's bounds
    with pytest.raises(IdentificationError, match='robot.m5'):
        identification.split(NOMINAL, base, values)


def test_prepare_splits_at_gaps_and_refuses_what_it_cannot_use():
    log = synthetic_log(TRUE, 0, 10.0, 4, duration=6.0)
    keep = (log.times < 2.5) | (log.times > 3.0)     # a 0.5 s gap
    gappy = Log(log.times[keep], log.lambdas[keep], log.forces[keep], 'gap')
    samples = identification.prepare(NOMINAL, gappy)
    assert samples.segments == 2
    assert not ((samples.times > 2.5 - 0.1) & (samples.times < 3.0 + 0.1)
                ).any()
    assert samples.rate == pytest.approx(1000.0 / 50)
    # Jittered stamps in any order give nearly the same samples (without
    # noise, and a cutoff that keeps every sample, to compare them).
    smooth = synthetic_log(TRUE, 0, 10.0, 4, duration=2.0, noise=0.0)
    rng = np.random.default_rng(5)
    jitter = smooth.times + rng.uniform(-1e-5, 1e-5, len(smooth.times))
    jitter[0] = 0.0
    order = rng.permutation(len(smooth.times))
    shuffled = Log(jitter[order], smooth.lambdas[order], smooth.forces[order],
                   'shuffled')
    a = identification.prepare(NOMINAL, smooth, 300.0)
    b = identification.prepare(NOMINAL, shuffled, 300.0)
    assert a.rate == pytest.approx(1000.0)
    inside = (a.times >= b.times[0]) & (a.times <= b.times[-1])
    assert inside.sum() >= len(a.times) - 2
    for j in range(3):
        moved = np.interp(a.times[inside], b.times, b.forces[:, j])
        assert np.abs(moved - a.forces[inside, j]).max() < 0.01
    for bad, word in (
            (Log(log.times, log.lambdas, log.forces, 'x'), 'cutoff'),
            (Log(log.times[:100], log.lambdas[:100], log.forces[:100], 'x'),
             'no piece'),
            (Log(log.times, log.lambdas * np.nan, log.forces, 'x'),
             'finite')):
        with pytest.raises(LogError, match=word):
            identification.prepare(NOMINAL, bad,
                                   600.0 if word == 'cutoff' else 10.0)


def test_identify_refuses_a_log_without_motion(base):
    times = np.arange(0.0, 5.0, 1e-3)
    rest = mechanics.solve(TRUE, (0.0, 0.0, 0.0)).force
    log = Log(times, np.zeros((len(times), 3)), np.tile(rest, (len(times), 1)),
              'at rest')
    with pytest.raises(IdentificationError, match='excite'):
        identification.identify(NOMINAL, log, base=base)


# Logs -------------------------------------------------------------------

def test_crop_keeps_a_window_counted_from_the_first_sample():
    log = synthetic_log(TRUE, 0, 5.0, 6, duration=1.0)
    shifted = Log(log.times + 100.0, log.lambdas, log.forces, 'shifted')
    window = identification.crop(shifted, 0.25, 0.5)
    assert window.times[0] == pytest.approx(100.25)
    assert window.times[-1] == pytest.approx(100.5)
    assert len(window.times) == 251
    assert np.array_equal(window.forces, log.forces[250:501])
    assert identification.crop(log).times.tolist() == log.times.tolist()
    with pytest.raises(LogError, match='no sample'):
        identification.crop(log, 2.0)


def test_csv_log_reads_the_tools_columns(tmp_path):
    log = synthetic_log(TRUE, 0, 5.0, 6, duration=0.5)
    path = tmp_path / 'log.csv'
    header = ('note,force_c,t,lambda_a,lambda_b,lambda_c,force_a,force_b')
    rows = [','.join(['x', *map(repr, (f[2], t, *lam, f[0], f[1]))])
            for t, lam, f in zip(log.times.tolist(), log.lambdas.tolist(),
                                 log.forces.tolist())]
    path.write_text(header + '\n' + '\n'.join(rows) + '\n')
    read = identification.read_log(path)
    assert np.array_equal(read.times, log.times)
    assert np.array_equal(read.lambdas, log.lambdas)
    assert np.array_equal(read.forces, log.forces)
    path.write_text('t,lambda_a,lambda_b,force_a,force_b,force_c\n')
    with pytest.raises(LogError, match="'lambda_c'"):
        identification.read_csv(path)


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
                velocity=np.zeros(3), effort=force[order].copy())
            writer.write(connection, stamp, store.serialize_cdr(
                msg, kind, little_endian=little_endian))


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_bag_log_reads_joint_states(tmp_path, storage):
    log = synthetic_log(TRUE, 0, 5.0, 7, duration=0.3)
    write_bag(tmp_path / 'bag', log, storage,
              names=('slider_c', 'slider_a', 'slider_b'))
    read = identification.read_log(tmp_path / 'bag')
    # Header stamps, from the first (write_bag starts at 1.7e9 s).
    assert read.origin == 1_700_000_000 * 10**9
    assert np.allclose(read.times, log.times, rtol=0.0, atol=1e-9)
    assert np.array_equal(read.lambdas, log.lambdas)
    assert np.array_equal(read.forces, log.forces)
    (storage_file,) = (tmp_path / 'bag').glob(
        '*.mcap' if storage == 'mcap' else '*.db3')
    again = identification.read_log(storage_file)
    assert np.array_equal(again.forces, log.forces)


def test_big_endian_joint_states_are_read_too(tmp_path):
    log = synthetic_log(TRUE, 0, 5.0, 8, duration=0.05)
    write_bag(tmp_path / 'bag', log, 'mcap', little_endian=False)
    read = identification.read_bag(tmp_path / 'bag')
    assert np.array_equal(read.lambdas, log.lambdas)


def test_bag_errors_name_the_problem(tmp_path):
    log = synthetic_log(TRUE, 0, 5.0, 9, duration=0.02)
    write_bag(tmp_path / 'bag', log, 'mcap', names=('a', 'b', 'c'))
    with pytest.raises(LogError, match='slider_a'):
        identification.read_bag(tmp_path / 'bag')
    assert identification.read_bag(tmp_path / 'bag', joint_names=(
        'a', 'b', 'c')).lambdas.shape == (len(log.times), 3)
    with pytest.raises(LogError, match='no topic /states'):
        identification.read_bag(tmp_path / 'bag', topic='states')
    with pytest.raises(LogError, match='cannot read'):
        identification.read_bag(tmp_path / 'missing')


def test_identification_from_a_bag_equals_the_one_from_arrays(tmp_path,
                                                              base):
    log = synthetic_log(TRUE, 2, 5.0, 10, duration=10.0)
    write_bag(tmp_path / 'bag', log, 'mcap')
    from_bag = identification.identify(
        NOMINAL, identification.read_log(tmp_path / 'bag'), base=base)
    direct = identification.identify(NOMINAL, log, base=base)
    assert np.allclose(from_bag.values, direct.values, rtol=1e-9)
    assert math.isfinite(from_bag.condition)


def test_force_lag_realigns_forces_reported_late(base):
    """Forces stamped 2 ms late: the lag puts them back where they were."""
    log = synthetic_log(TRUE, 0, 10.0, 12, duration=20.0, noise=0.0)
    moved = Log(log.times, log.lambdas, np.column_stack(
        [np.interp(log.times - 0.002, log.times, log.forces[:, j])
         for j in range(3)]), 'late forces')
    truth = base.matrix @ identification.standard_parameters(TRUE)
    aligned = identification.identify(NOMINAL, log, base=base)
    off = identification.identify(NOMINAL, moved, base=base)
    fixed = identification.identify(NOMINAL, moved, base=base,
                                    force_lag=0.002)
    error = {name: np.abs(r.values - truth) / truth
             for name, r in (('aligned', aligned), ('off', off),
                             ('fixed', fixed))}
    assert error['off'].max() > 5.0 * error['fixed'].max()
    assert error['fixed'].max() <= 2.0 * error['aligned'].max() + 1e-3
    with pytest.raises(LogError, match='force lag'):
        identification.prepare(NOMINAL, log, force_lag=0.2)
