"""Simulated pen plotters: the shared paper sheet and one simulator per command language."""
