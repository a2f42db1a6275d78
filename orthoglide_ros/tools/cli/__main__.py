"""``python -m orthoglide_ros.tools.cli``: the ``orthoglide`` tool."""

import sys

from orthoglide_ros.tools.cli import main

sys.exit(main())
