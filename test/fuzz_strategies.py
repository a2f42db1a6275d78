"""
Hypothesis strategies for fuzzing the mechanics and the feedforward node.

Platform positions inside the tested cube, on the edge of reach of a leg
(``y^2 + z^2`` close to ``l3^2`` for leg A, cyclically, on both sides),
far outside, near the singularities of J2 (along ``x = y = z`` at
``l3/sqrt(3)`` and ``-l3/sqrt(6)``) or anything at all; velocities and
accelerations from zero to 1e308; NaN and infinities poked into any of
the nine components; singularity margins in [0, 0.99].

Import it with the test directory on ``sys.path`` (pytest puts it there).
"""

import math

from hypothesis import strategies as st

CUBE = 0.3      # m: the paper's tested workspace |x|, |y|, |z| <= CUBE
NON_FINITE = (math.nan, math.inf, -math.inf)

any_float = st.floats(allow_nan=True, allow_infinity=True, width=64)
finite_float = st.floats(allow_nan=False, allow_infinity=False, width=64)
margins = st.one_of(st.sampled_from([0.0, 0.2, 0.99]),
                    st.floats(0.0, 0.99))


def _signed(low, high):
    """Return a float whose magnitude lies in [low, high], either sign."""
    return st.tuples(st.floats(low, high), st.booleans()).map(
        lambda t: -t[0] if t[1] else t[0])


def inside():
    """Return a point of the cube |x|, |y|, |z| <= CUBE."""
    c = st.floats(-CUBE, CUBE)
    return st.tuples(c, c, c)


def edge_of_reach(l3):
    """
    Return a point whose distance from one leg's axis is close to l3.

    Leg A's axis is x (distance ``sqrt(y^2 + z^2)``), B's is y, C's is z.
    The distance is l3 times a factor just below, at or just above 1, or
    ``sqrt(1 - m^2)`` for a margin m (the margin's own edge).
    """
    factor = st.one_of(
        st.sampled_from([1.0, math.nextafter(1.0, 0.0),
                         math.nextafter(1.0, 2.0)]),
        st.floats(1.0 - 1e-3, 1.0 + 1e-3),
        st.floats(1.0 - 1e-12, 1.0 + 1e-12),
        margins.map(lambda m: math.sqrt(1.0 - m * m)))

    def build(args):
        leg, theta, f, along = args
        r = l3 * f
        a, b = r * math.cos(theta), r * math.sin(theta)
        return ((along, a, b), (b, along, a), (a, b, along))[leg]

    return st.tuples(st.integers(0, 2), st.floats(0.0, 2.0 * math.pi),
                     factor, st.floats(-0.6, 0.6)).map(build)


def far_outside():
    """Return a finite point at least one metre out, up to 1e308."""
    big = _signed(1.0, 1.7e308)
    return st.tuples(big, finite_float, finite_float,
                     st.permutations([0, 1, 2])).map(
        lambda t: tuple(t[i] for i in t[3]))


def near_singularity(l3):
    """
    Return a point near x = y = z = l3/sqrt(3) or -l3/sqrt(6).

    There J2 = [[alpha, y, z], [x, alpha, z], [x, y, alpha]] is singular
    (its rows are equal, or sum to zero).
    """
    centre = st.sampled_from([l3 / math.sqrt(3.0), -l3 / math.sqrt(6.0)])
    scale = st.one_of(st.just(1.0), st.floats(1.0 - 1e-2, 1.0 + 1e-2),
                      st.floats(1.0 - 1e-12, 1.0 + 1e-12))
    nudge = st.one_of(st.just(0.0), st.floats(-1e-9, 1e-9),
                      st.floats(-1e-3, 1e-3))
    return st.tuples(centre, scale, nudge, nudge, nudge).map(
        lambda t: (t[0] * t[1] + t[2], t[0] * t[1] + t[3],
                   t[0] * t[1] + t[4]))


def positions(l3):
    """Return a platform position (m) of any of the kinds above."""
    return st.one_of(inside(), edge_of_reach(l3), far_outside(),
                     near_singularity(l3),
                     st.tuples(any_float, any_float, any_float))


def rates():
    """Return a velocity or acceleration: zero, moderate, huge or anything."""
    return st.one_of(
        st.just((0.0, 0.0, 0.0)),
        st.tuples(*[st.floats(-10.0, 10.0)] * 3),
        st.tuples(*[st.floats(-1e4, 1e4)] * 3),
        st.tuples(*[_signed(1e150, 1.7e308)] * 3),
        st.tuples(_signed(1e150, 1.7e308), st.just(0.0), st.just(0.0)),
        st.tuples(any_float, any_float, any_float))


def poisoned(sample):
    """
    Return ``(position, velocity, acceleration)`` with maybe one bad value.

    ``sample``: a strategy of such triples; with some probability one of
    the nine components becomes NaN, +inf or -inf.
    """
    def poke(args):
        (p, v, a), where, value = args
        if where is None:
            return p, v, a
        flat = list(p) + list(v) + list(a)
        flat[where] = value
        return tuple(flat[:3]), tuple(flat[3:6]), tuple(flat[6:])

    return st.tuples(sample, st.one_of(st.none(), st.integers(0, 8)),
                     st.sampled_from(NON_FINITE)).map(poke)


def states(l3):
    """Return (position, velocity, acceleration) of every kind above."""
    return poisoned(st.tuples(positions(l3), rates(), rates()))
