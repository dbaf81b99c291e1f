"""Device models: what the bytes mean for each plotter, panel and file format (``display.registry`` maps schemes)."""
