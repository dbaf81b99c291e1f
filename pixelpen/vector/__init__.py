"""Vector engine: display lists of pen strokes, hatching, stroke text, SVG import, path optimisation, motion model."""
