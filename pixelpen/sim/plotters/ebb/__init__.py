"""The EiBotBoard (AxiDraw) simulator: command table, motion and parameters."""
