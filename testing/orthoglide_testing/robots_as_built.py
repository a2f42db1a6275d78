"""
Robots as built: every leg's geometry off the drawing, for tests and benchmarks.

Keyword arguments of ``Robot`` (doc/model.md#the-machine-as-built). BUILT:
every per-leg row off the drawing by about a built Orthoglide's largest
errors (about 1 mm, 0.3 deg; the directions not quite unit vectors, as a
user types them); FAR: ten times more (about 1 cm, 3 deg).
"""

BUILT = {
    'axis_point_a': (0.0, 6e-4, -8e-4), 'axis_point_b': (-5e-4, 0.0, 9e-4),
    'axis_point_c': (7e-4, -4e-4, 0.0),
    'axis_direction_a': (1.0, 0.004, -0.0034),
    'axis_direction_b': (-0.0029, 1.0, 0.0041),
    'axis_direction_c': (0.0038, 0.0025, 1.0),
    'joint_offset': (9e-4, -6e-4, 3e-4), 'bar_length': (0.8507, 0.8494, 0.8509),
    'attachment_a': (2e-4, -3e-4, 5e-4), 'attachment_b': (-6e-4, 1e-4, 2e-4),
    'attachment_c': (4e-4, 5e-4, -7e-4),
}
FAR = {
    'axis_point_a': (0.0, 0.006, -0.008), 'axis_point_b': (-0.005, 0.0, 0.009),
    'axis_point_c': (0.007, -0.004, 0.0),
    'axis_direction_a': (0.9986, 0.04, -0.034),
    'axis_direction_b': (-0.029, 0.9988, 0.041),
    'axis_direction_c': (0.038, 0.025, 0.9989),
    'joint_offset': (0.009, -0.006, 0.003), 'bar_length': (0.857, 0.844, 0.859),
    'attachment_a': (0.002, -0.003, 0.005),
    'attachment_b': (-0.006, 0.001, 0.002),
    'attachment_c': (0.004, 0.005, -0.007),
}

# A built Orthoglide's errors (doc/calibration.md): lengths 0.1-1 mm,
# angles 0.05-0.3 deg.
BUILT_LENGTHS = (1e-4, 1e-3)
BUILT_TILTS = (0.05, 0.3)


def random_built(rng, l3=0.85, lengths=BUILT_LENGTHS, tilts=BUILT_TILTS):
    """
    Return a random robot as built: ``Robot`` keyword arguments.

    ``rng``: a numpy Generator. Every axis point and attachment off by a
    vector of length uniform in ``lengths`` (m), any direction; every
    axis tilted by an angle uniform in ``tilts`` (deg) towards any side;
    every joint offset and bar length (about ``l3``) off by a length in
    ``lengths`` either way.
    """
    import numpy as np

    def vector():
        v = rng.normal(size=3)
        return tuple(rng.uniform(*lengths) * v / np.linalg.norm(v))

    def signed():
        return float(rng.uniform(*lengths) * rng.choice((-1.0, 1.0)))

    out = {}
    for leg, axis in zip('abc', np.eye(3)):
        out[f'axis_point_{leg}'] = vector()
        out[f'attachment_{leg}'] = vector()
        side = rng.normal(size=3)
        side -= (side @ axis) * axis
        side /= np.linalg.norm(side)
        angle = np.radians(rng.uniform(*tilts))
        out[f'axis_direction_{leg}'] = tuple(np.cos(angle) * axis
                                             + np.sin(angle) * side)
    out['joint_offset'] = tuple(signed() for _ in range(3))
    out['bar_length'] = tuple(l3 + signed() for _ in range(3))
    return out
