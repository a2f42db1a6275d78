"""
What the demos, benchmarks and tests share to run the nodes as a user does.

Not part of the nodes or of the ``orthoglide`` tool: the harness starts
the installed console scripts as processes (:mod:`.processes`), feeds and
records them over real DDS (:mod:`.messages`, :mod:`.probe`), loads the
machine and sets the real-time priorities (:mod:`.load`), and runs the
cases the suite checks and the scripts report: the closed loop
(:mod:`.closed_loop`), floods and restarts (:mod:`.reliability`), hostile
peers and stalls (:mod:`.hostile`), a live graph and several hosts in
network namespaces (:mod:`.live_graph`, :mod:`.netns`). It imports rclpy
and reads the checkout's ``config/``: run it from a source tree with the
package installed (``scripts/setup_venv.sh``).
"""

from pathlib import Path

# The checkout the harness runs from: its config files and scripts.
ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / 'config'
PARAMS = str(CONFIG / 'orthoglide.yaml')
