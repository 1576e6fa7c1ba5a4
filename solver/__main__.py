"""``python -m solver ...``: the ``mpm`` command line."""
import sys

from solver.cli import main

sys.exit(main())
