"""
Identification of a robot that is not the model , without ROS.

A synthetic robot with what real Orthoglides have (each common on
ball-screw or belt guideways and current-controlled drives), its log made
here from the package's rigid dynamics and friction laws written in this
file:

- a Coulomb level per direction and a Stribeck rise at low speed (laws
  the package's model can hold);
- a ripple periodic in each slider's position (a screw's pitch: no rigid
  model holds it);
- forces that lag the encoders by LAG;
- noise on the forces, ``lambda`` quantised to 1 um, jittered stamps,
  dropped samples and a logger stall.

``identify`` then ``validate`` on another motion. Checked: the friction
law chosen holds both terms; the lag found is within 0.2 ms of LAG; the
validation's RMS error per actuator is within 10 % of the best the
chosen law can reach (identified from the same motion without noise,
lag, jitter or gaps) and at least 30 % below the plain law (viscous +
Coulomb) identified from the same log; what of the log was
used is reported. A robot with ball-screw drives of unequal armature
per axis, logged carrying a payload, the same guideways: plain
``identify`` (told the payload) chooses the law with the armature, finds
the robot's own platform and the drives, holds what the log cannot see
(``m1 + m2``, seen only through gravity) at its nominal value, and
predicts another motion, without the payload, within 10 % of the best the
law reaches on the same motion without noise. A simulator's log (the force held over each step)
comes out with a lag near half a step. A friction no robot has (a drive
pushing along the motion) is held at its bound by the bounded least
squares, and said; an actuator without force is explained by NaN.

Plain ``orthoglide identify``, then ``orthoglide batch`` on another
motion, against the forces the robot needs there: each actuator within
1.55 and the mean within 1.30 times the floor no model goes below (the
ripple's RMS), for this robot over several seeds and for robots of the
kind drawn at random (masses, friction, ripple, lag, noise, drops,
stall, rate). A Stribeck speed from 1.5 to 300 mm/s is found; a law is
scored by the robot it would give, never by a negative armature. Robots
of the kind on ball screws (a 0.5-0.7 N ripple at a 5 mm lead, a second
harmonic beside it): with the lead in ``--params`` each actuator within
0.35 N and the mean within 0.30 N, where plain identify is above.
"""

import math

import numpy as np
import pytest

from orthoglide_ros.model import mechanics, trajectory
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.tools import identification
from orthoglide_ros.tools.identification import Log, parse_law, PLAIN

NOMINAL = Robot()
# The robot as the package's model can hold it ...
TRUE = Robot(m5=18.75, m3=2.875, friction_viscous=(30.0, 40.0, 50.0),
             friction_coulomb=(5.0, 3.0, 4.0),
             friction_coulomb_negative=(8.0, 1.5, 6.0),
             friction_stribeck=(6.0, 4.0, 5.0),
             friction_stribeck_velocity=0.02)
# ... and what it cannot: a force ripple of RIPPLE N, periodic in each
# slider's position with the period PITCH (m), phases apart.
RIPPLE = 0.5
PITCH = 0.02
PHASES = (0.0, 2.0, 4.0)
LAG = 0.0013            # s: the forces lag the encoders
RATE = 1000.0           # Hz
PERIOD = 6.0            # s, of the excitations
NOISE = 0.3             # N, standard deviation of the measured forces
QUANTUM = 1e-6          # m, of the measured lambda
JITTER = 5e-5           # s, standard deviation of the stamps
DROPPED = 0.02          # share of the samples lost
STALL = (14.0, 14.4)    # s: the logger stalled
CLOSE = 0.10            # the validation error within 10 % of the best
BETTER = 0.30           # and 30 % below the plain law's


def true_forces(robot, times, motion):
    """Return the robot's forces along ``motion`` at ``times``, ripple too."""
    solution = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times))
    ripple = RIPPLE * np.sin(2.0 * math.pi * solution.lambda_ / PITCH
                             + np.array(PHASES))
    return solution.lambda_, solution.force + ripple


def robot_log(seed, duration, noise_seed, defects=True, robot=TRUE):
    """
    Return a log of ``robot`` along excitation ``seed``: every defect, or none.

    The encoders are read at the stamps' true instants; the forces are
    those of LAG s before; the stamps carry JITTER; DROPPED of the samples
    and the STALL are missing.
    """
    motion = trajectory.excitation(seed, PERIOD)
    times = np.arange(0.0, duration, 1.0 / RATE)
    lambdas, _ = true_forces(robot, times, motion)
    if not defects:
        return Log(times, lambdas, true_forces(robot, times, motion)[1],
                   f'seed {seed}, clean')
    _, forces = true_forces(robot, times - LAG, motion)
    rng = np.random.default_rng(noise_seed)
    stamps = times + rng.normal(0.0, JITTER, len(times))
    keep = (rng.uniform(size=len(times)) > DROPPED) \
        & ~((times >= STALL[0]) & (times < STALL[1]))
    keep &= np.r_[True, np.diff(stamps) > 0.0]
    return Log(stamps[keep],
               np.round(lambdas[keep] / QUANTUM) * QUANTUM,
               forces[keep] + rng.normal(0.0, NOISE, (keep.sum(), 3)),
               f'seed {seed}')


@pytest.fixture(scope='module')
def logs():
    return {'identify': robot_log(0, 30.0, 1),
            'clean': robot_log(0, 30.0, 1, defects=False),
            'validate': robot_log(1, 12.0, 2)}


@pytest.fixture(scope='module')
def found(logs):
    """Identify with every choice left to the tool."""
    return identification.identify(NOMINAL, logs['identify'])


def test_the_law_chosen_holds_both_terms(found):
    for candidate in found.candidates:
        print(f'{identification.law_name(candidate.law)}: held-out RMS '
              f'{candidate.held_out_rms:.4f} N, v_b '
              f'{candidate.stribeck_velocity}')
    print(found.law_chosen)
    assert found.law == parse_law('coulomb+direction+stribeck')
    assert found.stribeck_velocity == pytest.approx(
        TRUE.friction_stribeck_velocity, rel=0.5)


@pytest.mark.parametrize('speed', [0.0015, 0.15, 0.3])
def test_the_stribeck_speed_is_found_from_the_smoothing_to_the_top_speed(
        speed):
    """
    A Stribeck speed of 1.5 mm/s, 150 or 300 mm/s, found within 5 %.

    The search runs from the Coulomb smoothing speed (1 mm/s) to the log's
    largest slider speed (388 mm/s here), and its refinement may end
    anywhere inside.
    """
    robot = TRUE.replace(friction_stribeck_velocity=speed)
    motion = trajectory.excitation(0, PERIOD)
    times = np.arange(0.0, 20.0, 1.0 / RATE)
    solution = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times))
    rng = np.random.default_rng(3)
    log = Log(times, np.round(solution.lambda_ / QUANTUM) * QUANTUM,
              solution.force + rng.normal(0.0, NOISE, solution.force.shape),
              f'v_b {speed}')
    found = identification.identify(NOMINAL, log)
    print(f'v_b {speed} m/s: found {found.stribeck_velocity:.5g} m/s, '
          f'{identification.law_name(found.law)}')
    assert found.law == parse_law('coulomb+direction+stribeck')
    assert found.stribeck_velocity == pytest.approx(speed, rel=0.05)


def test_a_law_is_scored_by_the_robot_it_would_give():
    """
    Forces less 0.5 kg times each slider's acceleration: no drive gives that.

    The armature's column fits it with a negative armature, which no robot
    has and the identified one cannot keep (it is bounded at 0): the law
    with the armature would win the held-out error by 7 % so, and the robot
    written would have none. Each fold's prediction is the bounded
    estimate, so a law with the armature scores as the law without it.
    """
    motion = trajectory.excitation(0, PERIOD)
    times = np.arange(0.0, 20.0, 1.0 / RATE)
    solution = mechanics.solve_batch(
        TRUE, *trajectory.excitation_batch(motion, times))
    rng = np.random.default_rng(3)
    forces = solution.force - 0.5 * solution.lambdaddot
    log = Log(times, np.round(solution.lambda_ / QUANTUM) * QUANTUM,
              forces + rng.normal(0.0, NOISE, forces.shape), 'pulling')
    found = identification.identify(NOMINAL, log, force_lag=0.0)
    scores = {c.law: c.held_out_rms for c in found.candidates}
    print(found.law_chosen, scores)
    assert found.law == parse_law('coulomb+direction+stribeck')
    for law, score in scores.items():
        if 'armature' in law.name:
            without = parse_law(law.name.replace('+armature', ''))
            assert score >= scores[without] * (1.0 - 1e-6), law


def validation_rms(log, force_lag, **results):
    """Return (and print) each result's RMS error (N) predicting ``log``."""
    rms = {name: identification.validate(result.robot, log,
                                         force_lag=force_lag).rms
           for name, result in results.items()}
    for name, values in rms.items():
        print(f'{name}: validation RMS error (N) '
              + ', '.join(f'{v:.4f}' for v in values))
    return rms


def test_the_lag_is_found_within_0_2_ms(found, logs):
    print(f'lag found {found.force_lag * 1e3:.4f} ms (true {LAG * 1e3} ms)')
    assert found.lag_estimated
    assert abs(found.force_lag - LAG) <= 2e-4


def test_validation_is_near_the_best_and_beats_the_plain_law(found, logs):
    """
    Validated with the drive's lag, the one identify found.

    The plain law leaves so much unexplained that the tool refuses its
    estimate (m1 + m2's relative deviation near 1000 %): taken all the
    same, for its forces.
    """
    plain = identification.identify(NOMINAL, logs['identify'],
                                    friction=PLAIN,
                                    max_relative_std=math.inf)
    best = identification.identify(NOMINAL, logs['clean'], friction=found.law,
                                   force_lag=0.0,
                                   stribeck_velocity=found.stribeck_velocity)
    rms = validation_rms(logs['validate'], found.force_lag, found=found,
                         plain=plain, best=best)
    assert (rms['found'] <= (1.0 + CLOSE) * rms['best']).all(), rms
    assert (rms['found'] <= (1.0 - BETTER) * rms['plain']).all(), rms


def test_the_report_says_what_was_used(found, logs):
    coverage = found.samples.coverage
    print(coverage)
    span = logs['identify'].times[-1] - logs['identify'].times[0]
    assert coverage.log_s == pytest.approx(span)
    assert coverage.gaps == 1
    assert coverage.longest_gap_s == pytest.approx(STALL[1] - STALL[0],
                                                   abs=0.01)
    assert coverage.segments == 2
    # Dropped samples (about DROPPED of them) are interpolated.
    expected = DROPPED * len(logs['identify'].times)
    assert 0.5 * expected <= coverage.missing <= 1.5 * expected
    assert 0.8 * span <= coverage.used_s < span - 0.4


def test_a_simulator_log_lags_half_a_step():
    """The force held over each step: applied half a step before its state."""
    from synthetic_logs import closed_loop, excitation_sample
    log, _ = closed_loop(NOMINAL, excitation_sample, 12.0)
    result = identification.identify(NOMINAL, log, friction=PLAIN)
    step = 1.0 / 500.0
    print(f'lag found {result.force_lag * 1e3:.4f} ms, half a step '
          f'{0.5 * step * 1e3} ms')
    assert abs(result.force_lag - 0.5 * step) <= 0.1 * step


def test_validate_explains_nothing_where_there_is_no_force():
    """A log without force on an actuator: NaN explained, no warning."""
    import warnings
    times = np.arange(0.0, 4.0, 1e-3)
    lambdas = np.tile(mechanics.solve(NOMINAL, (0.0, 0.0, 0.0)).lambda_,
                      (len(times), 1))
    log = Log(times, lambdas, np.zeros((len(times), 3)), 'no force')
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        validation = identification.validate(NOMINAL, log, force_lag=0.0)
    assert np.isnan(validation.explained).all()
    # At home only C carries the weight the model predicts.
    assert validation.rms[2] == pytest.approx(
        mechanics.solve(NOMINAL, (0.0, 0.0, 0.0)).force[2], rel=1e-9)


def test_a_friction_no_robot_has_is_held_at_zero_and_said():
    """A drive that pushes along C's motion: the bounded least squares."""
    robot = Robot(m5=18.75, friction_viscous=(30.0, 40.0, 50.0),
                  friction_coulomb=(5.0, 3.0, 0.0))
    motion = trajectory.excitation(0, PERIOD)
    times = np.arange(0.0, 20.0, 1.0 / RATE)
    solution = mechanics.solve_batch(
        robot, *trajectory.excitation_batch(motion, times))
    forces = solution.force.copy()
    forces[:, 2] -= 0.5 * np.tanh(solution.lambdadot[:, 2]
                                  / robot.friction_velocity)
    result = identification.identify(
        NOMINAL, Log(times, solution.lambda_, forces, 'pushing drive'),
        friction=PLAIN, force_lag=0.0)
    i = result.base.names.index('coulomb_c')
    base = result.samples.regressor[:, :, list(result.base.independent)]
    ordinary = np.linalg.lstsq(base.reshape(-1, len(result.values)),
                               result.samples.forces.reshape(-1),
                               rcond=None)[0]
    print(result.bounded, f'ordinary coulomb_c {ordinary[i]:.4f} N')
    assert ordinary[i] == pytest.approx(-0.5, abs=0.02)
    assert result.values[i] == 0.0
    assert result.robot.friction_coulomb[2] == 0.0
    (note,) = result.bounded
    assert note.startswith('coulomb_c was found -0.5') and 'held at 0 N' in note
    others = [k for k in range(len(ordinary)) if k != i]
    assert np.allclose(result.values[others], ordinary[others], rtol=0.05)


# A robot with drives: a ball screw per axis with its motor's inertia
# reflected onto the slider (kg), unequal; logged carrying PAYLOAD.
DRIVES = TRUE.replace(armature=(3.2, 1.1, 0.45))
PAYLOAD = 5.0
DRIVES_BETTER = 0.20    # the validation 20 % below a law without drives


@pytest.fixture(scope='module')
def drives():
    carried = DRIVES.replace(payload=PAYLOAD)
    logs = {'identify': robot_log(0, 30.0, 1, robot=carried),
            'clean': robot_log(0, 30.0, 1, defects=False, robot=carried),
            'validate': robot_log(1, 12.0, 2, robot=DRIVES)}
    found = identification.identify(NOMINAL, logs['identify'],
                                    payload=PAYLOAD)
    return logs, found


def test_drives_are_found_and_the_platform_is_the_robots_own(drives):
    logs, found = drives
    print(found.law_chosen, *found.held, sep='\n')
    assert found.law == parse_law('coulomb+direction+stribeck+armature')
    assert found.payload == PAYLOAD and found.robot.payload == 0.0
    assert found.robot.m5 + 3 * found.robot.m4 == pytest.approx(
        DRIVES.m5 + 3 * DRIVES.m4, rel=0.02)
    assert np.allclose(found.robot.armature, DRIVES.armature, rtol=0.2,
                       atol=0.1)
    # m1 + m2 is seen through gravity alone (on C): held at nominal.
    held = [found.base.names[i] for i in found.held.indices]
    assert 'm1 + m2' in held
    assert found.robot.m1 + found.robot.m2 == pytest.approx(
        NOMINAL.m1 + NOMINAL.m2, rel=1e-12)


def test_drives_predict_another_motion_within_10_percent_of_the_best(
        drives):
    logs, found = drives
    best = identification.identify(
        NOMINAL, logs['clean'], friction=found.law, force_lag=0.0,
        stribeck_velocity=found.stribeck_velocity, payload=PAYLOAD)
    without = identification.identify(NOMINAL, logs['identify'],
                                      friction=parse_law('coulomb+direction+stribeck'),
                                      payload=PAYLOAD)
    rms = validation_rms(logs['validate'], found.force_lag, found=found,
                         best=best, **{'no armature': without})
    assert (rms['found'] <= (1.0 + CLOSE) * rms['best']).all(), rms
    # The drives matter: without them the masses cannot make up for them
    # (measured: 0.33, 0.28, 0.37 N against 1.33, 0.38, 0.76 N).
    assert (rms['found'] <= (1.0 - DRIVES_BETTER) * rms['no armature']).all(), rms


# Plain identify, then batch on another motion: the forces the identified
# robot gives (orthoglide batch) against those the robot needs there (its
# rigid dynamics, friction and ripple; the noise and the lag are the
# log's, not the robot's). No model holds the ripple: its RMS,
# RIPPLE / sqrt(2) = 0.354 N, is the floor no identification goes below.
# The targets 0.55 N per actuator and 0.46 N in the mean were set for a
# robot of this kind with this ripple: 1.55 and 1.30 times its floor
# (orthoglide_testing.rough_guideways: EACH, MEAN).
FLOOR = RIPPLE / math.sqrt(2.0)
SEEDS = (0, 1, 2, 3)    # (identified on excitation 2 s, validated on 2 s + 1)


def batch_forces(capsys, tmp_path, params, motion, times):
    """Return ``orthoglide batch``'s forces (N, 3) along ``motion``."""
    from cli_runs import read_csv, run, write_trajectory
    source = write_trajectory(
        tmp_path / 'motion.csv',
        ('t', 'x', 'y', 'z', 'vx', 'vy', 'vz', 'ax', 'ay', 'az'),
        np.column_stack((times, *trajectory.excitation_batch(
            motion, times))).tolist())
    out = tmp_path / 'batch.csv'
    code, _, err = run(capsys, 'batch', '--params', params, '--input',
                       source, '--output', out)
    assert code == 0, err
    _, rows = read_csv(out.read_text())
    return np.array([[float(row[f'force_{leg}']) for leg in 'abc']
                     for row in rows])


def rms(error):
    """Return the RMS (N) per actuator of an (N, 3) error."""
    return np.sqrt(np.mean(np.square(error), axis=0))


@pytest.mark.slow     # 2.4-3.2 s of CPU per seed, one process, 2026-12-06
@pytest.mark.parametrize('seed', SEEDS)
def test_plain_identify_then_batch_is_within_the_floor(
        capsys, tmp_path, seed):
    """
    `orthoglide identify`, every choice its own, then `orthoglide batch`.

    The log has every defect (lag, noise, quantisation, jitter, drops, the
    stall); another motion validates.
    """
    from cli_runs import run
    from orthoglide_testing import rough_guideways as rough
    from synthetic_logs import write_csv
    log = write_csv(tmp_path / 'log.csv', robot_log(2 * seed, 30.0,
                                                    100 + seed))
    params = tmp_path / 'identified.yaml'
    code, out, err = run(capsys, 'identify', '--input', log, '--output',
                         params)
    assert code == 0, err
    motion = trajectory.excitation(2 * seed + 1, PERIOD)
    times = np.arange(0.0, 12.0, 1.0 / RATE)
    errors = rms(batch_forces(capsys, tmp_path, params, motion, times)
                 - true_forces(TRUE, times, motion)[1])
    with capsys.disabled():
        print(f'\nseed {seed}: batch RMS error (N) {errors.round(3)}, '
              f'mean {errors.mean():.3f}, floor {FLOOR:.3f} N')
    assert (errors <= rough.EACH * FLOOR).all(), errors
    assert errors.mean() <= rough.MEAN * FLOOR, errors


# Drawn robots that test the rules: 1, where keeping m1 + m2 at its nominal
# 0.55 kg instead of the bound the fit holds it at is 12.8 times the floor
# on C (the split rule); 6, where holding at the nominal 0 a viscous
# friction of 28 N s/m the log places five deviations from it is 3.7 times
# the floor on A. Two others (0, 2) as they come.
DRAWN = (0, 1, 2, 6)


@pytest.mark.parametrize('seed', DRAWN)
def test_drawn_robots_of_this_kind_are_within_their_floor(capsys, tmp_path,
                                                          seed):
    """The limits above, each robot against its own ripple's floor."""
    from orthoglide_ros.formats.params_file import robot_file_text
    from orthoglide_testing import rough_guideways as rough
    robot, defects = rough.drawn_robot(seed)
    found = identification.identify(
        NOMINAL, rough.log(robot, defects, 2 * seed, 10 + seed))
    params = tmp_path / 'identified.yaml'
    params.write_text(robot_file_text(found.robot, ['drawn']))
    motion, times = rough.validation_motion(defects, 2 * seed + 1)
    errors = rough.errors(batch_forces(capsys, tmp_path, params, motion,
                                       times), robot, defects, motion, times)
    floor = rough.floor(defects)
    with capsys.disabled():
        print(f'\ndrawn {seed}: {identification.law_name(found.law)}, '
              f'batch RMS error / floor {(errors / floor).round(2)}, mean '
              f'{errors.mean() / floor:.2f}')
    assert (errors <= rough.EACH * floor).all(), errors / floor
    assert errors.mean() <= rough.MEAN * floor, errors / floor


# Robots of the kind on ball screws (rough_guideways.screw_robot): a
# ripple of 0.5-0.7 N at a 5 mm lead and a second harmonic of up to 15 %
# of it. Plain identify leaves about 0.4-0.45 N RMS per actuator, most of
# it that ripple; with the lead in --params the ripple law is chosen and
# each actuator comes within SCREW_EACH, the mean within SCREW_MEAN.
SCREWS = (0, 3)


@pytest.mark.parametrize('seed', SCREWS)
def test_screw_robots_are_within_the_targets_once_the_lead_is_given(
        capsys, tmp_path, seed):
    from cli_runs import run
    from orthoglide_testing import rough_guideways as rough
    from synthetic_logs import write_csv
    robot, defects = rough.screw_robot(seed)
    log = rough.log(robot, defects, 2 * seed, 10 + seed)
    motion, times = rough.validation_motion(defects, 2 * seed + 1)
    before = rough.errors(mechanics.solve_batch(
        identification.identify(NOMINAL, log).robot,
        *trajectory.excitation_batch(motion, times)).force, robot, defects,
        motion, times)
    nominal = tmp_path / 'nominal.yaml'
    nominal.write_text('feedforward:\n  ros__parameters:\n'
                       f'    robot.screw_lead: {[rough.SCREW_LEAD] * 3}\n')
    params = tmp_path / 'identified.yaml'
    code, out, err = run(capsys, 'identify', '--input', write_csv(
        tmp_path / 'log.csv', log), '--params', nominal, '--output', params)
    assert code == 0, err
    after = rough.errors(batch_forces(capsys, tmp_path, params, motion,
                                      times), robot, defects, motion, times)
    with capsys.disabled():
        print(f'\nscrew robot {seed}: RMS error (N) without the lead '
              f'{before.round(3)}, with it {after.round(3)} (mean '
              f'{before.mean():.3f} -> {after.mean():.3f})')
    assert (after <= rough.SCREW_EACH).all(), after
    assert after.mean() <= rough.SCREW_MEAN, after
    assert before.mean() > rough.SCREW_MEAN, before
