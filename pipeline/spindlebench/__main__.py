"""``python -m spindlebench``: the same command line as the ``spindlebench`` script."""

import sys

from spindlebench.commands.main import main

sys.exit(main())
