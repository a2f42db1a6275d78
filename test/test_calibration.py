"""
Calibration of every leg's geometry from measured positions, without ROS.

The machine is simulated by the independent model of
``mechanics_reference`` (each leg's rows on their own, scipy's
``Rotation``, forward kinematics by least squares on the spheres) or, for
many positions, by ``mechanics.forward_kinematics``; robots as built of a
built Orthoglide's errors (``robots_as_built``). Checked:

- the readings' Jacobian against central differences of the model;
- what the readings separate, found by the pivoted QR: 18 values from x,
  y, z on enough positions, and the reasons by construction: per leg the
  axis point's move along the axis moves the readings as the joint offset
  does, each attachment component as minus the axis point's (the leg
  frame's entries); on a nominal robot already off the drawing too; with
  an instrument in its own frame, the six rigid motions of the whole robot
  against it in the Jacobian's null space, held, 18 in all;
- noise-free measurements give back the machine exactly, for a built
  robot and one ten times further off, and name no blunder at 8, 12 or 30
  positions (the implied noise at its 1 nm floor);
- with 10 um of noise: each identified value within 4.5 of its standard
  errors of the noise-free fit's, the noise the residuals imply within
  the chi-square spread of 10 um, and the calibrated inverse kinematics
  within the accuracy the covariance predicts;
- blunders: a 5 mm one named by its row and the result exactly the fit
  without it; three at once; none named in pure noise; the threshold,
  scipy's F quantile at the probability of six normal sigmas;
- fewer readings: what they separate, and a note; too few: refused;
- the positions worth measuring: a better conditioned Jacobian and a
  smaller predicted error than random positions', in the workspace.
"""

import math

import numpy as np
import pytest

from mechanics_reference import platform_position
from orthoglide_testing.robots_as_built import BUILT, FAR, random_built
from orthoglide_ros.model import mechanics
from orthoglide_ros.model.robot import ParameterError, Robot
from orthoglide_ros.tools import calibration
from orthoglide_ros.tools.calibration import estimate, geometry, poses
from orthoglide_ros.tools.calibration.estimate import CalibrationError

NOMINAL = Robot()
NOISE = 10e-6       # m, each coordinate


def workspace(count, seed, robot=NOMINAL):
    """Return ``count`` random positions of the cube within the margin."""
    return poses._workspace(robot, np.random.default_rng(seed), count)


def readings_of(robot, positions, nominal=NOMINAL):
    """Return the joint readings of ``nominal``'s IK, ``robot``'s FK there."""
    lam = mechanics.solve_batch(nominal, positions).lambda_
    return lam, mechanics.forward_kinematics(robot, lam)


def data(lam, readings):
    """Wrap readings as measurements of lines 2, 3, ..."""
    return calibration.Measurements(
        np.asarray(lam), np.asarray(readings, dtype=float),
        list(range(2, len(lam) + 2)), 'test')


def names(params, indices):
    return [params[j].name for j in indices]


def ik_error(commanded, true, targets):
    """RMS and largest |FK_true(IK_commanded(t)) - t| (m)."""
    lam = mechanics.solve_batch(commanded, targets).lambda_
    error = np.linalg.norm(mechanics.forward_kinematics(true, lam) - targets,
                           axis=1)
    return math.sqrt(float(np.mean(error ** 2))), float(error.max())


@pytest.mark.parametrize('instrument', [False, True])
def test_the_jacobian_is_the_models_derivative(instrument):
    lam = mechanics.solve_batch(NOMINAL, workspace(20, 1)).lambda_
    rng = np.random.default_rng(2)
    deviation = rng.normal(0.0, 3e-4, 36)
    start = geometry.Frame(geometry.rotation((0.4, -0.3, 1.2)),
                           np.array([1.0, -2.0, 0.5])) if instrument \
        else None
    columns = geometry.jacobian(NOMINAL.legs, lam, deviation, start)
    assert columns.shape == (20, 3, 36 if instrument else 30)
    step = 1e-6
    for k in range(columns.shape[2]):
        e = np.zeros(36)
        e[k] = step
        numeric = (geometry.measured(NOMINAL.legs, lam, deviation + e,
                                     start)[0]
                   - geometry.measured(NOMINAL.legs, lam, deviation - e,
                                       start)[0]) / (2.0 * step)
        assert np.abs(columns[:, :, k] - numeric).max() < 1e-7, k


def separable(robot, instrument=False, count=30):
    """Find what x, y, z readings at ``count`` positions separate."""
    lam = mechanics.solve_batch(robot, workspace(count, 3, robot)).lambda_
    start = geometry.IDENTITY if instrument else None
    params = geometry.parameters(instrument)
    columns = geometry.jacobian(robot.legs, lam, np.zeros(len(params)),
                                start).reshape(-1, len(params))
    return params, calibration.identifiable(columns, params), columns


@pytest.mark.parametrize('nominal', [NOMINAL, Robot(**BUILT)],
                         ids=['drawing', 'built'])
def test_xyz_readings_separate_18_values_and_hold_the_rest_for_a_reason(
        nominal):
    params, found, _ = separable(nominal)
    assert found.separable == len(found.identified) == 18
    held = names(params, found.held)
    per_leg = ['axis_point_a[x]', 'axis_point_b[y]', 'axis_point_c[z]']
    assert sorted(held) == sorted(per_leg + [
        f'attachment_{leg}[{axis}]' for leg in 'abc' for axis in 'xyz'])
    assert all(found.explained)
    identified = list(found.identified)
    for k, j in enumerate(found.held):
        p = params[j]
        leg = nominal.legs[p.leg]
        frame = np.asarray(leg.frame)
        expected = np.zeros(len(identified))
        suffix = 'abc'[p.leg]
        # The leg's offset, then its point across the axis: leg frame order.
        carriers = [params.index(next(q for q in params if q.kind == kind
                                      and q.leg == p.leg and (
                                          q.index == index or kind ==
                                          'offset')))
                    for kind, index in (('offset', 0), ('point', 1),
                                        ('point', 2))]
        if p.kind == 'point':       # along the axis: the reading's zero
            assert p.index == 0 and p.name.startswith(f'axis_point_{suffix}')
            expected[identified.index(carriers[0])] = 1.0
        else:                       # r_i only enters as r_i - a_i
            assert p.kind == 'attachment'
            for c, carrier in zip(frame[p.index], carriers):
                expected[identified.index(carrier)] = -c
        assert np.allclose(found.combinations[k], expected, atol=1e-8), \
            (p.name, found.combinations[k])


def rigid_motions(nominal):
    """
    Return the six rigid motions of the whole robot against the instrument.

    36-vectors of the calibration's parameters: the legs' points,
    directions and attachments moved by a small translation or rotation of
    the robot, the instrument's map moved back by it.
    """
    out = []
    for kind in ('translation', 'rotation'):
        for axis in np.eye(3):
            v = np.zeros(36)
            for i, leg in enumerate(nominal.legs):
                frame = np.asarray(leg.frame)
                if kind == 'translation':
                    move_point, turn_u, move_r = axis, np.zeros(3), np.zeros(3)
                else:
                    move_point = np.cross(axis, leg.point)
                    turn_u = np.cross(axis, leg.direction)
                    move_r = np.cross(axis, leg.attachment)
                v[10 * i:10 * i + 3] = frame.T @ move_point
                v[10 * i + 3:10 * i + 5] = (frame.T @ turn_u)[1:]
                v[10 * i + 7:10 * i + 10] = move_r
            # m = Q G + t stays: Q turned back (Q exp(-w) = exp(-Q w) Q).
            if kind == 'translation':
                v[30:33] = -axis
            else:
                v[33:36] = -axis
            out.append(v)
    return np.array(out)


def test_an_instrument_frame_holds_the_robots_rigid_motion_against_it():
    params, found, columns = separable(NOMINAL, instrument=True)
    assert found.separable == len(found.identified) == 18
    # The gauge: every rigid motion of the robot, the instrument following.
    gauge = rigid_motions(NOMINAL)
    assert np.abs(columns @ gauge.T).max() < 1e-12 * np.abs(columns).max()
    assert np.linalg.matrix_rank(gauge) == 6
    identified = names(params, found.identified)
    assert all(f'instrument.{c}' in identified
               for c in ('tx', 'ty', 'tz', 'rx', 'ry', 'rz'))
    # Six leg values held for the gauge: their combinations need the
    # instrument's; the twelve of the robot frame's reasons besides.
    by_gauge = [params[j].name for k, j in enumerate(found.held)
                if any(c != 0.0 and params[i].leg is None for c, i in zip(
                    found.combinations[k], found.identified))]
    assert len(by_gauge) == 6 + 3   # and three attachments along with them
    assert len(found.held) == 18 == 36 - 18


@pytest.mark.parametrize('size', ['built', 'far'])
def test_noise_free_readings_give_the_machine_back(size):
    machine = Robot(**(BUILT if size == 'built' else FAR))
    positions = workspace(30, 4)
    lam = mechanics.solve_batch(NOMINAL, positions).lambda_
    # The machine as the independent model puts it.
    measured = np.array([platform_position(machine, row, position)
                         for row, position in zip(lam, positions)])
    result = calibration.calibrate(NOMINAL, data(lam, measured))
    assert result.rms_after < 1e-9
    assert not result.left_out
    targets = workspace(300, 5)
    rms, worst = ik_error(result.robot, machine, targets)
    assert worst < 1e-8
    assert ik_error(NOMINAL, machine, targets)[0] > 1e-3


@pytest.mark.parametrize('count', [8, 12, 30])
def test_exact_readings_are_calibrated_with_no_blunder(count):
    """Noise-free readings: no made-up blunder, the noise at its floor."""
    for seed in range(3):
        machine = Robot(**random_built(np.random.default_rng(seed)))
        lam, exact = readings_of(machine, workspace(count, 50 + seed))
        result = calibration.calibrate(NOMINAL, data(lam, exact))
        assert not result.left_out
        assert result.rms_after < 1e-9
        assert result.sigma == estimate.SIGMA_FLOOR
        assert ik_error(result.robot, machine, workspace(100, 5))[1] < 1e-7


@pytest.fixture(scope='module')
def noisy():
    """Measure a built machine at 30 positions: (truth fit, noisy fits)."""
    machine = Robot(**random_built(np.random.default_rng(11)))
    lam, exact = readings_of(machine, workspace(30, 6))
    truth = calibration.calibrate(NOMINAL, data(lam, exact))
    noises = [np.random.default_rng(seed).normal(0.0, NOISE, exact.shape)
              for seed in range(8)]
    fits = [calibration.calibrate(NOMINAL, data(lam, exact + noise))
            for noise in noises]
    return machine, lam, truth, fits


def test_noise_gives_values_within_their_standard_errors(noisy):
    _, _, truth, fits = noisy
    for fit in fits:
        free = list(fit.identifiability.identified)
        assert free == list(truth.identifiability.identified)
        error = (fit.deviation - truth.deviation)[free] / fit.std[free]
        assert np.abs(error).max() < 4.5
        # sigma^2 (n - k) / noise^2 is chi-square of n - k = 72: within
        # five of its standard deviations.
        assert abs(fit.sigma / NOISE - 1.0) < 5.0 / math.sqrt(2 * 72)
        assert not fit.left_out
    # The standard errors are honest: the estimates' spread is their size.
    spread = np.std([f.deviation for f in fits], axis=0)[free]
    ratio = spread / fits[0].std[free]
    assert 0.4 < float(np.median(ratio)) < 1.6


def test_the_calibrated_ik_reaches_what_the_noise_allows(noisy):
    machine, lam, truth, fits = noisy
    targets = workspace(300, 7)
    for fit in fits:
        # The covariance's prediction of the error at the targets: the
        # position's change per identified value times their covariance.
        t_lam = mechanics.solve_batch(fit.robot, targets).lambda_
        free = list(fit.identifiability.identified)
        jac = geometry.jacobian(NOMINAL.legs, t_lam,
                                fit.deviation)[:, :, free]
        m = geometry.jacobian(NOMINAL.legs, lam, fit.deviation)[:, :, free]
        covariance = fit.sigma ** 2 * np.linalg.inv(
            np.einsum('nki,nkj->ij', m, m))
        predicted = math.sqrt(float(np.mean(np.einsum(
            'nki,ij,nkj->n', jac, covariance, jac))))
        rms, worst = ik_error(fit.robot, machine, targets)
        assert rms < 2.0 * predicted
        assert predicted < 15e-6
    assert ik_error(truth.robot, machine, targets)[1] < 1e-9


def test_a_blunder_is_named_and_changes_nothing(noisy):
    machine, lam, _, _ = noisy
    readings = mechanics.forward_kinematics(machine, lam) + \
        np.random.default_rng(0).normal(0.0, NOISE, (30, 3))
    spoiled = readings.copy()
    spoiled[17, 1] += 5e-3
    result = calibration.calibrate(NOMINAL, data(lam, spoiled))
    assert [row for row, _, _ in result.left_out] == [17]
    row, residual, column = result.left_out[0]
    assert column == 1 and abs(residual - 5e-3) < 1e-4
    keep = np.arange(30) != 17
    without = calibration.calibrate(NOMINAL, data(lam[keep], readings[keep]))
    assert np.abs(result.deviation - without.deviation).max() < 1e-10
    assert result.sigma == pytest.approx(without.sigma, rel=1e-6)


def test_several_blunders_are_named():
    machine = Robot(**random_built(np.random.default_rng(12)))
    lam, exact = readings_of(machine, workspace(40, 8))
    readings = exact + np.random.default_rng(1).normal(0.0, NOISE,
                                                       exact.shape)
    for row, column, size in ((3, 0, 5e-3), (11, 2, -2e-3), (29, 1, 0.4e-3)):
        readings[row, column] += size
    result = calibration.calibrate(NOMINAL, data(lam, readings))
    assert sorted(row for row, _, _ in result.left_out) == [3, 11, 29]
    assert result.sigma < 1.5 * NOISE


@pytest.mark.parametrize('count', [12, 30])
def test_noise_alone_names_no_blunder(count):
    for seed in range(5):
        machine = Robot(**random_built(np.random.default_rng(20 + seed)))
        lam, exact = readings_of(machine, workspace(count, 30 + seed))
        readings = exact + np.random.default_rng(seed).normal(
            0.0, NOISE, exact.shape)
        assert not calibration.calibrate(NOMINAL, data(lam,
                                                       readings)).left_out


@pytest.mark.parametrize('count, spare', [(9, 9), (11, 15), (12, None),
                                          (30, None)])
def test_too_few_readings_to_spare_to_find_a_blunder_are_said(count, spare):
    machine = Robot(**random_built(np.random.default_rng(count)))
    lam, exact = readings_of(machine, workspace(count, 70 + count))
    readings = exact + np.random.default_rng(count).normal(0.0, NOISE,
                                                           exact.shape)
    notes = calibration.calibrate(NOMINAL, data(lam, readings)).notes
    said = [n for n in notes if 'too few to find a blunder' in n]
    if spare is None:
        assert not said
    else:
        more = calibration.BLUNDER_REDUNDANCY - spare
        assert said == [f'{spare} readings to spare: too few to find a '
                        'blunder reliably '
                        f'({calibration.BLUNDER_REDUNDANCY} or more do); '
                        f'measure {more} more coordinates '
                        f'({math.ceil(more / 3)} more positions in x, y and '
                        'z)']


def test_a_blunder_too_few_readings_hide_is_refused_by_the_noise_left():
    """A 5 mm blunder among 8 positions: the fit absorbs it, 0.26-0.9 mm."""
    for seed in (0, 2, 3):
        machine = Robot(**random_built(np.random.default_rng(seed)))
        lam, exact = readings_of(machine, workspace(8, 60 + seed))
        readings = exact + np.random.default_rng(seed).normal(0.0, NOISE,
                                                              exact.shape)
        readings[3, 1] += 5e-3
        with pytest.raises(CalibrationError) as error:
            calibration.calibrate(NOMINAL, data(lam, readings))
        assert 'beyond any instrument a calibration uses (100 um)' in \
            str(error.value)
        assert 'measure 12 more coordinates' in str(error.value)


def test_readings_noisier_than_any_instrument_are_refused():
    machine = Robot(**BUILT)
    lam, exact = readings_of(machine, workspace(30, 16))
    readings = exact + np.random.default_rng(2).normal(0.0, 0.3e-3,
                                                       exact.shape)
    with pytest.raises(CalibrationError, match=(
            r'beyond any instrument a calibration uses \(100 um\): '
            r'measurements of another robot .* the largest residual: line '
            r"\d+, column '[xyz]' \([+-]\d")):
        calibration.calibrate(NOMINAL, data(lam, readings))


def test_one_coordinate_per_reading_separates_the_same_values():
    machine = Robot(**BUILT)
    lam, exact = readings_of(machine, workspace(90, 9))
    rng = np.random.default_rng(3)
    readings = np.full(exact.shape, np.nan)
    read = rng.integers(0, 3, 90)
    readings[np.arange(90), read] = exact[np.arange(90), read] + rng.normal(
        0.0, NOISE, 90)
    result = calibration.calibrate(NOMINAL, data(lam, readings))
    assert len(result.identifiability.identified) == 18
    assert result.readings == 90
    assert np.isnan(result.after).sum() == 180
    assert ik_error(result.robot, machine, workspace(200, 10))[0] < 20e-6


def test_few_readings_identify_what_they_can_and_say_so():
    machine = Robot(**BUILT)
    lam, exact = readings_of(machine, workspace(7, 11))
    result = calibration.calibrate(NOMINAL, data(lam, exact))
    found = result.identifiability
    assert found.separable == 18 and len(found.identified) == 21 - 6
    assert 'measure 3 more coordinates' in result.notes[0]
    assert np.isnan(result.std[list(found.held)]).all()
    with pytest.raises(CalibrationError, match='too few to identify'):
        calibration.calibrate(NOMINAL, data(lam[:2], exact[:2]))


def test_the_calibrated_robot_keeps_the_nominal_robots_other_rows():
    nominal = Robot(m5=18.0, friction_viscous=(30.0, 40.0, 50.0),
                    armature=(1.0, 0.5, 0.2))
    machine = nominal.replace(**BUILT)
    lam, exact = readings_of(machine, workspace(30, 12), nominal)
    result = calibration.calibrate(nominal, data(lam, exact))
    for name in ('m5', 'friction_viscous', 'armature', 'l3', 'gravity'):
        assert getattr(result.robot, name) == getattr(nominal, name)
    assert not result.robot.as_drawn


def test_an_instrument_frame_is_found_with_the_geometry():
    machine = Robot(**BUILT)
    lam, exact = readings_of(machine, workspace(30, 13))
    real = geometry.Frame(geometry.rotation((0.3, -1.1, 2.0)),
                          np.array([1.5, -0.7, 0.2]))
    seen = exact @ real.rotation.T + real.translation
    result = calibration.calibrate(NOMINAL, data(lam, seen), True)
    assert result.rms_after < 1e-9
    # In the calibrated robot's frame the machine goes where commanded.
    targets = workspace(200, 14)
    reached = mechanics.forward_kinematics(
        machine, mechanics.solve_batch(result.robot, targets).lambda_)
    in_robot = (reached @ real.rotation.T + real.translation
                - result.frame.translation) @ result.frame.rotation
    assert np.abs(in_robot - targets).max() < 1e-8
    with pytest.raises(CalibrationError, match='--frame instrument'):
        calibration.calibrate(NOMINAL, data(lam, seen))


@pytest.mark.slow     # 1.4-1.7 s: the design of 2000 candidates, 2026-12-06
def test_the_designed_positions_condition_the_calibration_best():
    design = poses.design(NOMINAL, 12, 'xyz')
    assert design.condition < 0.5 * design.random_condition
    assert mechanics.workspace_status(NOMINAL, design.positions).ok.all()
    assert np.abs(design.positions).max() <= poses.CUBE
    assert np.allclose(mechanics.forward_kinematics(NOMINAL, design.lambdas),
                       design.positions, atol=1e-12)
    # The error the noise leaves at the cube's targets, from the
    # covariance: smaller than random positions' (median of ten draws).
    targets = workspace(300, 15)
    t_lam = mechanics.solve_batch(NOMINAL, targets).lambda_
    free = list(design.identified)
    at = geometry.jacobian(NOMINAL.legs, t_lam, np.zeros(30))[:, :, free]

    def predicted(lam):
        m = geometry.jacobian(NOMINAL.legs, lam, np.zeros(30))[:, :, free]
        covariance = np.linalg.inv(np.einsum('nki,nkj->ij', m, m))
        return math.sqrt(float(np.mean(np.einsum('nki,ij,nkj->n', at,
                                                 covariance, at))))
    random = [predicted(mechanics.solve_batch(
        NOMINAL, workspace(12, 40 + k)).lambda_) for k in range(10)]
    assert predicted(design.lambdas) < 0.7 * float(np.median(random))


@pytest.mark.parametrize('rows', [1, 3])
def test_the_greedy_start_is_the_largest_determinant_each_step(rows):
    """The determinant lemma's choice: the full determinants' (no exchange)."""
    rng = np.random.default_rng(rows)
    blocks = rng.normal(size=(60, rows, 6))
    gram = np.einsum('nki,nkj->nij', blocks, blocks)
    chosen, spent = poses._exchange(blocks, gram, 10, 0)
    ridge = 1e-9 * np.trace(gram.mean(0)) * np.eye(6)
    picked = []
    for _ in range(10):
        logdet = [-np.inf if c in picked else np.linalg.slogdet(
            ridge + gram[picked + [c]].sum(0))[1] for c in range(60)]
        picked.append(int(np.argmax(logdet)))
    assert (chosen.tolist(), spent) == (sorted(picked), 0)


def test_gauge_positions_name_one_coordinate_each():
    design = poses.design(NOMINAL, 30, 'gauge', evaluations=5000,
                          candidates=500)
    assert design.coordinates.shape == (30,)
    assert set(design.coordinates.tolist()) <= {0, 1, 2}
    assert design.condition < design.random_condition
    with pytest.raises(ValueError, match='below 24'):
        poses.design(NOMINAL, 23, 'gauge', candidates=200)
    with pytest.raises(ValueError, match='below 8'):
        poses.design(NOMINAL, 7, 'xyz', candidates=200)


@pytest.mark.parametrize('readings, spare', [(1, 5), (3, 6), (3, 72),
                                             (1, 1000)])
def test_the_blunder_threshold_is_the_f_quantile_of_six_sigma(readings,
                                                              spare):
    from scipy import stats
    alarm = 2.0 * stats.norm.sf(estimate.BLUNDER_SIGMAS)
    assert estimate._quantile(readings, spare) == pytest.approx(
        stats.f.isf(alarm, readings, spare), rel=1e-8)


def test_calibrated_legs_the_robot_refuses_are_shown_as_numbers():
    deviation = np.zeros(30)
    deviation[5] = 0.2      # leg A's joint offset, beyond 0.1 m
    with pytest.raises(ParameterError, match=r'got \(0\.2, 0\.0, 0\.0\)$'):
        geometry.calibrated_robot(NOMINAL, deviation)
    robot = geometry.calibrated_robot(NOMINAL, np.full(30, 1e-4))
    assert all(type(v) is float for name in Robot.parameter_names()
               for value in [getattr(robot, name)]
               for v in (value if isinstance(value, tuple) else (value,)))
