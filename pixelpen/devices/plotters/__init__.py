"""Pen plotters: the shared plotter display and job, and one driver per command language (HP-GL, GRBL, EBB)."""
