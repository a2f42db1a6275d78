"""
The proving ground of orthoglide_ros: what its tests, demos, benchmarks share.

Not part of the product, not installed by ``pip install .`` nor colcon:
``scripts/setup_venv.sh`` installs it editable into the checkout's venv.
It starts the installed console scripts as processes (:mod:`.processes`),
feeds and records them over real DDS (:mod:`.messages`, :mod:`.probe`),
loads the machine and sets the real-time priorities (:mod:`.load`), and
runs the cases the suite checks and the scripts report: the closed loop
(:mod:`.closed_loop`), floods and restarts (:mod:`.reliability`), hostile
peers and stalls (:mod:`.hostile`), a live graph and several hosts in
network namespaces (:mod:`.live_graph`, :mod:`.netns`); :mod:`.verdicts`
says when the machine spoiled a run. It reads the checkout's ``config/``:
whoever knows the checkout names it once with :func:`use_checkout`
(``test/conftest.py``, each script and benchmark).
"""

from orthoglide_testing.checkout import (  # noqa: F401
    checkout, CheckoutError, config_file, params_file, use_checkout)
