"""Device-independent 2D/3D geometry: homogeneous transforms, viewing, clipping, curves. Imports nothing of pixelpen."""
