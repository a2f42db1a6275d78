"""
Identify the Orthoglide's masses, drives and friction from a log, no ROS.

``f = W(r_G, rdot_G, rddot_G) theta``; scipy is imported where used
(doc/identification.md).
"""

from orthoglide_ros.formats.logs import (  # noqa: F401
    check_log, crop, DEFAULT_TOPIC, Log, LogError, read_bag, read_csv,
    read_log)
from orthoglide_ros.tools.identification.estimate import (  # noqa: F401
    bounds, Candidate, FOLDS, identify, Identification, IdentificationError,
    MAX_RELATIVE_STD, RESOLUTION, SELECTION_MARGIN, split,
    STRIBECK_STEP, stribeck_velocities)
from orthoglide_ros.tools.identification.laws import (  # noqa: F401
    Law, LAWS, law_name, MASSES, MEANINGS, OPTIONAL, parse_law, PLAIN,
    STANDARD, standard_names, standard_parameters, term_columns, UNITS,
    with_parameters)
from orthoglide_ros.tools.identification.motion import (  # noqa: F401
    Coverage, DEFAULT_CUTOFF, estimate_lag, LAG_SEARCH, Motion, prepare,
    Samples, STATE_CUTOFF_FACTOR)
from orthoglide_ros.tools.identification.regressor import (  # noqa: F401
    Base, base_parameters, condition_number, design_law, regressor)
from orthoglide_ros.tools.identification.validate import (  # noqa: F401
    predict, validate, Validation)
