"""File displays: PNG images and SVG drawings written like any other device."""
