"""``python -m pixelpen``: the same command line as ``pixelpen``."""

import sys

from pixelpen.cli import main

sys.exit(main())
