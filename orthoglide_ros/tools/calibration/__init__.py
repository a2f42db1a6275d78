"""
Calibrate the Orthoglide's legs from measured positions, without ROS.

Each leg's geometry (doc/model.md#the-machine-as-built) from joint
readings and the platform centre an instrument measured: what the data
separate (:mod:`identifiability`), the least squares (:mod:`estimate`),
the positions worth measuring (:mod:`poses`); scipy is imported where used
(doc/calibration.md).
"""

from orthoglide_ros.tools.calibration.estimate import (  # noqa: F401
    calibrate, Calibration, CalibrationError, MAX_DEVIATION, MAX_NOISE,
    SIGMA_FLOOR)
from orthoglide_ros.tools.calibration.geometry import (  # noqa: F401
    Frame, IDENTITY, parameters, Parameter)
from orthoglide_ros.tools.calibration.identifiability import (  # noqa: F401
    BLUNDER_REDUNDANCY, combination_text, identifiable, Identifiability,
    MIN_REDUNDANCY,
    RANK_TOLERANCE)
from orthoglide_ros.tools.calibration.measurements import (  # noqa: F401
    COLUMNS, MAX_MEASUREMENTS, MeasurementError, Measurements, read)
