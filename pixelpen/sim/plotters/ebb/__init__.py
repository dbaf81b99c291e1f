"""The EiBotBoard (AxiDraw) simulator: ``board.EbbSimulator``; the module docstring of ``board`` maps the rest."""
