"""Subcommands of the ``pixelpen`` command line, one module per group; each registers its argparse parsers."""
