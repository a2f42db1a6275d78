"""
The tolerances on identified base parameters, shared by the tests.

Each base mass combination within 3 % of the truth, the lightest within
10 %, each friction coefficient within 25 %: the figures set for
a synthetic log, applied to the DDS loop's log too (whose least-squares
standard deviations are optimistic: its residuals are not white).
"""

import numpy as np

BASE_TOLERANCE = 0.03
LIGHTEST_TOLERANCE = 0.10
FRICTION_TOLERANCE = 0.25


def assert_within_tolerances(base, values, truth, robot, true_robot):
    """Check identified ``values`` (and ``robot``'s friction) against truth."""
    error = np.abs(values - truth) / truth
    masses = [i for i, j in enumerate(base.independent) if j < 6]
    lightest = min(masses, key=lambda i: truth[i])
    assert base.names[lightest] == 'm1 + m2'
    tolerance = np.full(len(truth), BASE_TOLERANCE)
    tolerance[lightest] = LIGHTEST_TOLERANCE
    assert (error <= tolerance).all(), dict(zip(base.names, error))
    for found, true in ((robot.friction_viscous, true_robot.friction_viscous),
                        (robot.friction_coulomb, true_robot.friction_coulomb)):
        assert np.allclose(found, true, rtol=FRICTION_TOLERANCE, atol=0.0)
