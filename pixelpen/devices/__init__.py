"""Device models: what the bytes mean for each plotter, panel and file format; each module registers its URL scheme."""
