"""``python -m pixelpen``: the same command line as ``pixelpen``."""

import sys

from .cli import main

sys.exit(main())
