"""
What ``orthoglide identify`` and ``orthoglide validate`` print and draw.

Text lines and figures (measured against predicted forces, the residual
against time, speed and position per actuator) drawn into a matplotlib
Figure the caller makes; no matplotlib import of its own (doc/cli.md).
"""

from __future__ import annotations

from typing import Any, Optional, TYPE_CHECKING

import numpy as np

from orthoglide_ros.model.terms import RIPPLE
from orthoglide_ros.tools import identification
from orthoglide_ros.model.types import Array

if TYPE_CHECKING:   # annotations only: no import cycle at run time
    from orthoglide_ros.formats.logs import Log
    from orthoglide_ros.tools.identification.estimate import Identification
    from orthoglide_ros.tools.identification.motion import Coverage
    from orthoglide_ros.tools.identification.validate import Validation

ACTUATORS = 'ABC'


def coverage_line(coverage: Coverage) -> str:
    """Describe what of a log was used (a :class:`identification.Coverage`)."""
    share = 100.0 * coverage.used_s / coverage.log_s if coverage.log_s else 0
    parts = [f'used {coverage.used_s:.4g} s of {coverage.log_s:.4g} s '
             f'({share:.3g} %) in {coverage.segments} segment(s)']
    if coverage.gaps:
        parts.append(f'{coverage.gaps} gap(s) split the log (the longest '
                     f'{coverage.longest_gap_s:.3g} s)')
    if coverage.short_pieces:
        parts.append(f'{coverage.short_pieces} piece(s) between gaps too '
                     'short to filter, dropped')
    parts.append(f'{coverage.missing} missing sample(s) interpolated')
    return '; '.join(parts)


def lag_text(lag: float, estimated: bool) -> str:
    """Describe the force lag (s) and where it came from."""
    return (f'force lag {lag * 1e3:.4g} ms '
            + ('(estimated: the least residual)' if estimated
               else '(given)'))


def identification_lines(source: str, log: Log, window: tuple[float, float],
                         result: Identification, cutoff: float) -> list[str]:
    """
    Return the report's lines: samples, lag, law, base parameters, fit.

    ``log``: the whole log read from ``source``, ``window``: the part
    identified from.
    """
    samples = result.samples
    lines = [
        f'Identification from {source}: {len(log.times)} samples over '
        f'{span(log.times)}; {len(window.times)} in the window '
        f'{span(window.times)}; {len(samples.times)} used over '
        f'{span(samples.times)} (low-pass {cutoff:g} Hz, decimated to '
        f'{samples.rate:.4g} Hz)',
        coverage_line(samples.coverage),
        lag_text(result.force_lag, result.lag_estimated),
        'friction law, RMS error on held-out parts of the log (N): '
        + ', '.join(f'{identification.law_name(c.law)} '
                    f'{c.held_out_rms:.4g}'
                    + (f' (v_b {c.stribeck_velocity:.3g} m/s)'
                       if c.stribeck_velocity is not None else '')
                    for c in result.candidates),
        f'friction law chosen: {result.law_chosen}'
        + (f'; Stribeck velocity {result.stribeck_velocity:.4g} m/s'
           if result.stribeck_velocity is not None else ''),
        f'{"base parameter":<28}{"identified":>12}{"nominal":>12}'
        f'{"rel. std (%)":>14}  meaning']
    names = identification.standard_names(result.law)
    for name, meaning, carrier, value, nominal, relative in zip(
            result.base.names, result.base.meanings,
            result.base.independent, result.values, result.nominal,
            result.relative_std):
        label = f'{name} ({identification.UNITS[names[carrier]]})'
        lines.append(f'{label:<28}{value:12.6g}{nominal:12.6g}'
                     f'{relative:14.3g}  {meaning}')
    if RIPPLE in result.law:
        robot = result.robot
        lines.append('screw ripple found, amplitude sqrt(s^2 + c^2) (N): '
                     + ', '.join(
                         f'{leg} {np.hypot(s, c):.4g}' if lead else
                         f'{leg} - (no lead)' for leg, s, c, lead in zip(
                             ACTUATORS, robot.ripple_sine,
                             robot.ripple_cosine, robot.screw_lead))
                     + ' (screw lead ' + ', '.join(
                         f'{1e3 * lead:g}' for lead in robot.screw_lead)
                     + ' mm)')
    lines.append(f'condition number of the base regressor: '
                 f'{result.condition:.4g} (unit-norm columns)')
    lines.append('RMS residual per actuator (N): ' + ', '.join(
        f'{leg} {r:.4g}' for leg, r in zip(ACTUATORS, result.residual_rms))
        + ' (RMS force: ' + ', '.join(
            f'{leg} {r:.4g}' for leg, r in zip(ACTUATORS, result.force_rms))
        + ')')
    lines += [f'bounded: {note}' for note in result.bounded]
    return lines


def validation_lines(validation: Validation,
                     reference: Optional[Validation] = None) -> list[str]:
    """
    Return the lines of a validation: lag, used, RMS, max, share explained.

    ``reference``: another :class:`identification.Validation` of the same
    log (the nominal robot's) printed beside it, or None.
    """
    rows = [('robot', validation)] if reference is None else [
        ('nominal robot', reference), ('identified robot', validation)]
    lines = [f'Validation on {validation.source}: '
             + coverage_line(validation.samples.coverage),
             lag_text(validation.force_lag, validation.lag_estimated),
             f'{"":<34}{"A":>10}{"B":>10}{"C":>10}']
    for label, v in rows:
        figures = [('force error RMS (N)', v.rms, '.4g'),
                   ('force error max (N)', v.max, '.4g'),
                   ('share of the force explained (%)', 100 * v.explained,
                    '.4g')]
        if v.ripple_left is not None:
            figures.append(('screw ripple left (N, amplitude)',
                            v.ripple_left, '.3g'))
        for what, values, form in figures:
            text = f'{label}: {what}' if reference is not None else what
            # (A cell of 10 characters or more keeps a space before it.)
            lines.append(f'{text:<34}' + ''.join(
                (' ' + (format(value, form) if np.isfinite(value) else '-')
                 ).rjust(10) for value in values))
    lines += [f'warning: {w}' for w in validation.warnings]
    return lines


def span(times: Array) -> str:
    """Describe a span of times (s): ``[0, 29.999] s (29.999 s)``."""
    return f'[{times[0]:.6g}, {times[-1]:.6g}] s ({times[-1] - times[0]:.6g} s)'


def _broken(samples, *arrays):
    """Return times and arrays with NaN at each gap (no line across it)."""
    gap = np.r_[np.diff(samples.times) > 1.5 / samples.rate, False]
    at = np.flatnonzero(gap) + 1
    return [np.insert(np.asarray(a, dtype=float), at, np.nan, axis=0)
            for a in (samples.times,) + arrays]


def draw_identification(figure: Any, source: str,
                        result: Identification) -> None:
    """Draw measured vs predicted forces and the residuals into ``figure``."""
    axes = figure.subplots(2, 3, sharex=True)
    times, measured, predicted = _broken(
        result.samples, result.samples.forces, result.predicted)
    for j, leg in enumerate(ACTUATORS):
        top, bottom = axes[0, j], axes[1, j]
        top.plot(times, measured[:, j], label='measured (filtered)')
        top.plot(times, predicted[:, j], '--', label='predicted (identified)')
        top.set_title(f'actuator {leg}')
        top.set_ylabel(f'$f_{leg}$ (N)')
        top.legend(fontsize=8)
        bottom.plot(times, measured[:, j] - predicted[:, j], color='tab:red')
        bottom.set_title(f'residual, RMS {result.residual_rms[j]:.3g} N')
        bottom.set_ylabel(f'$f_{leg}$ measured - predicted (N)')
        bottom.set_xlabel('t (s)')
        for ax in (top, bottom):
            ax.grid(True, alpha=0.4)
    figure.suptitle(f'Identification from {source}: measured and predicted '
                    f'actuator forces ({identification.law_name(result.law)}'
                    ' friction)')


def draw_validation(figure: Any, validation: Validation) -> None:
    """
    Draw a validation into ``figure``: 3 rows of 3 actuators.

    Measured and predicted forces against time; the residual against the
    slider's speed (what a friction law leaves) and against its position
    (a ripple periodic in position: a ball screw's pitch, cogging), within
    one lead of the screw where the robot has one.
    """
    samples = validation.samples
    axes = figure.subplots(3, 3)
    times, measured, predicted = _broken(samples, validation.measured,
                                         validation.predicted)
    residual = validation.measured - validation.predicted
    for j, leg in enumerate(ACTUATORS):
        top, middle, bottom = axes[:, j]
        top.plot(times, measured[:, j], label='measured (filtered)')
        top.plot(times, predicted[:, j], '--', label='predicted')
        top.set_title(f'actuator {leg}: RMS error {validation.rms[j]:.3g} N, '
                      f'{100 * validation.explained[j]:.4g} % explained',
                      fontsize=9)
        top.set_xlabel('t (s)')
        top.set_ylabel(f'$f_{leg}$ (N)')
        top.legend(fontsize=8)
        middle.plot(samples.lambdadots[:, j], residual[:, j], '.',
                    markersize=2, color='tab:red')
        middle.set_xlabel(f'$\\dot\\lambda_{leg}$ (m/s)')
        middle.set_ylabel('measured - predicted (N)')
        lead = validation.screw_lead[j]
        position = samples.lambdas[:, j] % lead if lead else \
            samples.lambdas[:, j]
        bottom.plot(position * 1e3, residual[:, j], '.',
                    markersize=2, color='tab:purple')
        bottom.set_xlabel(
            f'$\\lambda_{leg}$ modulo the screw lead {1e3 * lead:g} mm '
            '(mm)' if lead else f'$\\lambda_{leg}$ (mm)')
        bottom.set_ylabel('measured - predicted (N)')
        for ax in (top, middle, bottom):
            ax.grid(True, alpha=0.4)
    figure.suptitle(f'Validation on {validation.source}: the forces, and '
                    'what the model does not explain against speed and '
                    'position')
