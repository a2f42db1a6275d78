"""
The hypothesis profiles of the suite, and :func:`examples` to scale by them.

- ``default``: a quarter of each test's weight, no deadline (a verdict that
  does not depend on the machine's load): the inner loop;
- ``ci``: each test's weight, derandomized (``.ci/run``);
- ``thorough``: 2.5 times each test's weight, no deadline: loaded by
  ``test/conftest.py`` for the soak run (``-m soak`` or
  ``ORTHOGLIDE_SOAK=1``), or named with ``--hypothesis-profile thorough``.

A test states its weight, the examples it runs at hypothesis' own default
of 100:
``@settings(max_examples=examples(400))``. A decorator's ``max_examples``
overrides any profile, hence this helper instead of a number.
"""

from hypothesis import settings

# hypothesis' own max_examples, the scale at which a weight is a count.
BASE = 100
settings.register_profile('default', max_examples=25, deadline=None)
settings.register_profile('ci', max_examples=BASE, deadline=None,
                          derandomize=True, database=None)
settings.register_profile('thorough', max_examples=250, deadline=None)
# Loaded here: hypothesis' plugin loads --hypothesis-profile after this.
settings.load_profile('default')


def examples(weight):
    """Return ``weight`` scaled by the loaded profile (at least 1)."""
    return max(1, round(weight * settings.default.max_examples / BASE))
