"""
What ``orthoglide calibrate`` prints, writes as comments and draws.

Text lines (what was identified with its standard error, what was held
and why, what was left out, the residuals against the noise they imply)
and a figure (every measurement's residuals before and after, the
identified deviations with their standard errors) drawn into a matplotlib
Figure the caller makes; no matplotlib import of its own.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from orthoglide_ros.tools.calibration.estimate import (
    Calibration, SIGMA_FLOOR)
from orthoglide_ros.tools.calibration.geometry import rotation_vector
from orthoglide_ros.tools.calibration.identifiability import (
    combination_text, RANK_TOLERANCE)
from orthoglide_ros.tools.calibration.measurements import (
    COORDINATES, Measurements)

# Printed units: (factor from SI, name) by a parameter's unit.
UNITS = {'m': (1e3, 'mm'), 'rad': (1e3, 'mrad')}


def lines(data: Measurements, result: Calibration) -> list[str]:
    """Return the report's lines: data, identifiability, values, fit."""
    found = result.identifiability
    params = result.params
    counts = ', '.join(f'{c} {int(n)}' for c, n in zip(
        COORDINATES, (~np.isnan(data.readings)).sum(0)))
    frame = ('the instrument\'s own frame (its pose identified)'
             if len(params) > 30 else 'the robot\'s base frame')
    out = [f'Calibration from {data.source}: {len(data.lines)} '
           f'measurements, {found.readings} readings ({counts}) in {frame}',
           f'identifiability: these readings separate {found.separable} of '
           f'the {len(params)} values (QR pivots above {RANK_TOLERANCE:g} '
           f'of the first); {len(found.identified)} identified, '
           f'{len(found.held)} held at their nominal values',
           f'{"identified":<24}{"deviation":>14}{"std error":>12}  unit']
    for j in found.identified:
        p = params[j]
        factor, unit = UNITS[p.unit]
        out.append(f'{p.name:<24}{factor * result.deviation[j]:+14.5f}'
                   f'{factor * result.std[j]:12.5f}  {unit}')
    out.append('held at the nominal value (what it moves the readings '
               'as, in the identified values):')
    out += [f'  {params[j].name:<22}{combination_text(params, found, k)}'
            for k, j in enumerate(found.held)]
    if len(params) > 30:
        out.append(instrument_line(result))
    for row, residual, column in result.left_out:
        out.append(f'left out: line {data.lines[row]} (a blunder: its '
                   f'{COORDINATES[column]} reading {1e3 * residual:+.4g} mm '
                   'from the calibrated robot\'s, '
                   f'{abs(residual) / result.sigma:.3g} times the noise)')
    out.append(
        f'residual RMS: {1e3 * result.rms_before:.4g} mm with the nominal '
        f'robot, {1e6 * result.rms_after:.4g} um calibrated, over '
        f'{result.readings} readings; the noise it implies, sqrt(RSS / '
        f'(n - k)) = {1e6 * result.sigma:.4g} um per reading '
        f'(n = {result.readings}, k = {len(found.identified)})'
        + (' (its floor: the readings are exact to the nanometre)'
           if result.sigma <= SIGMA_FLOOR else ''))
    out += [f'note: {note}' for note in result.notes]
    return out


def instrument_line(result: Calibration) -> str:
    """Describe the instrument's pose: its map from the base frame."""
    frame = result.frame
    origin = -frame.rotation.T @ frame.translation
    turn = np.degrees(rotation_vector(frame.rotation))
    std = result.std[30:]
    return ('instrument: reads m = R G + t, t = ['
            + ', '.join(f'{v:.6g}' for v in frame.translation)
            + '] m (std ' + ', '.join(f'{1e6 * s:.3g}' for s in std[:3])
            + ' um), R of rotation vector [' + ', '.join(
                f'{v:.5g}' for v in turn) + '] deg (std ' + ', '.join(
                f'{np.degrees(s) * 3600:.3g}' for s in std[3:])
            + ' arcsec); its origin at [' + ', '.join(
                f'{v:.6g}' for v in origin) + '] m in the base frame')


def draw(figure: Any, data: Measurements, result: Calibration) -> None:
    """
    Draw the residuals before and after, and the identified deviations.

    Top: every reading's residual (measured less modelled) against its
    file line, the nominal robot's (mm) and the calibrated one's (um,
    +-3 sigma shaded, the rows left out marked); bottom: the identified
    lengths (mm) and angles (mrad) with error bars of two standard errors.
    """
    axes = figure.subplots(2, 2)
    lines_ = np.asarray(data.lines)
    kept = result.kept
    for ax, table, rms, factor, unit, when in (
            (axes[0, 0], result.before, result.rms_before, 1e3, 'mm',
             'nominal robot'),
            (axes[0, 1], result.after, result.rms_after, 1e6, 'um',
             'calibrated robot')):
        for k, (coordinate, colour) in enumerate(zip(
                COORDINATES, ('tab:red', 'tab:green', 'tab:blue'))):
            ax.plot(lines_[kept], factor * table[kept, k], 'o',
                    markersize=3, color=colour, label=coordinate)
        ax.set_xlabel('line of the measurements file')
        ax.set_ylabel(f'measured - modelled ({unit})')
        ax.grid(True, alpha=0.4)
        ax.set_title(f'{when}: RMS {factor * rms:.3g} {unit}')
    axes[0, 1].axhspan(-3e6 * result.sigma, 3e6 * result.sigma,
                       color='0.85', zorder=0, label='+-3 sigma')
    for row, residual, _ in result.left_out:
        for ax in axes[0]:
            ax.axvline(lines_[row], color='tab:purple', linestyle=':',
                       label=f'left out: line {lines_[row]} '
                       f'({1e3 * residual:+.3g} mm)')
    axes[0, 0].legend(fontsize=8)
    axes[0, 1].legend(fontsize=8)
    found = result.identifiability
    for ax, unit in ((axes[1, 0], 'm'), (axes[1, 1], 'rad')):
        shown = [j for j in found.identified
                 if result.params[j].unit == unit
                 and result.params[j].leg is not None]
        factor, name = UNITS[unit]
        y = np.arange(len(shown))
        ax.errorbar(factor * result.deviation[shown], y,
                    xerr=2.0 * factor * result.std[shown], fmt='o',
                    capsize=3)
        ax.set_yticks(y, [result.params[j].name for j in shown], fontsize=8)
        ax.axvline(0.0, color='k', linewidth=0.8)
        ax.invert_yaxis()
        ax.set_xlabel(f'deviation from the nominal robot ({name}), '
                      '+-2 standard errors')
        ax.grid(True, alpha=0.4)
    axes[1, 0].set_title('identified lengths and positions')
    axes[1, 1].set_title('identified tilts')
    figure.suptitle(f'Calibration from {data.source}: '
                    f'{len(data.lines)} measurements, '
                    f'{len(found.identified)} values identified')
