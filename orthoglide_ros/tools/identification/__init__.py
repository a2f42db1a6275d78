"""
Identify the Orthoglide's masses, drives and friction from a log, no ROS.

The actuator forces are linear in the masses, the drives' armature and the
friction coefficients: ``f = W(r_G, rdot_G, rddot_G) theta``, with the
standard parameters ``theta`` of a :class:`Law` (kg, N s/m, N). The
geometry, gravity and the Coulomb smoothing speed are known (the nominal
robot's). One module per job:

- :mod:`.laws`: the laws and their standard parameters (viscous + Coulomb,
  and optionally a Coulomb level per direction, a Stribeck excess, the
  drives' armature), read off a :class:`Robot` and written back;
- :mod:`.regressor`: ``W`` from the package's own inverse dynamics, the
  base parameters a log can identify (a pivoted QR), the condition number
  of a motion;
- :mod:`.motion`: a log on uniform grids, its motion and regressor
  through zero-phase low-passes (parallel filtering), the forces' lag;
- :mod:`.estimate`: :func:`identify`, the law by held-out error, the
  least squares, what a log does not excite, the split into a robot;
- :mod:`.validate`: a robot's forces against another log's;
- :mod:`.report`: what ``orthoglide identify`` and ``validate`` print and
  draw.

The logs (CSV files, rosbag2 bags) are read by
:mod:`orthoglide_ros.formats.logs`. ``doc/identification.md`` states the
method, its choices and its figures. Units: m, m/s, m/s^2, N, kg, s. scipy
and rosbags are imported by the functions that use them, so that importing
this package (as the ``orthoglide`` tool does for every command) costs
neither.
"""

from orthoglide_ros.formats.logs import (  # noqa: F401
    check_log, crop, DEFAULT_TOPIC, Log, LogError, read_bag, read_csv,
    read_log)
from orthoglide_ros.tools.identification.estimate import (  # noqa: F401
    bounds, Candidate, FOLDS, identify, Identification, IdentificationError,
    MAX_RELATIVE_STD, RESOLUTION, SELECTION_MARGIN, split,
    STRIBECK_STEP, stribeck_velocities)
from orthoglide_ros.tools.identification.laws import (  # noqa: F401
    ARMATURES, friction_columns, Law, LAWS, law_name, MASSES, MEANINGS,
    parse_law, PLAIN, STANDARD, standard_names, standard_parameters, UNITS,
    with_parameters)
from orthoglide_ros.tools.identification.motion import (  # noqa: F401
    Coverage, DEFAULT_CUTOFF, estimate_lag, LAG_SEARCH, Motion, prepare,
    Samples, STATE_CUTOFF_FACTOR)
from orthoglide_ros.tools.identification.regressor import (  # noqa: F401
    Base, base_parameters, condition_number, design_law, regressor)
from orthoglide_ros.tools.identification.validate import (  # noqa: F401
    predict, validate, Validation)
