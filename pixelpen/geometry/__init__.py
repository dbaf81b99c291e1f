"""Device-independent 2D/3D geometry: homogeneous transforms, viewing, clipping, curves. Imports nothing of pixelpen but its errors.

Bad arguments raise ``InvalidArgument`` (a PixelpenError and a ValueError) or ``InvalidArgumentType``
(a PixelpenError and a TypeError), so callers may catch either family.
"""

from pixelpen.geometry.clip import (
    BOTTOM,
    LEFT,
    RIGHT,
    TOP,
    as_convex_window,
    as_segments,
    clip_polygon,
    clip_polygon_convex,
    clip_polylines,
    clip_segments,
    clip_segments_convex,
    outcodes,
)
from pixelpen.geometry.curves import (
    BEZIER_BASIS,
    BSPLINE_BASIS,
    DEFAULT_TOLERANCE,
    basis_to_bezier,
    bernstein,
    bezier_point,
    bspline_basis,
    bspline_point,
    eval_basis,
    flatten_arc,
    flatten_bezier,
    flatten_beziers,
    flatten_bspline,
    open_uniform_knots,
    uniform_knots,
)
from pixelpen.geometry.dashes import as_pattern, dash_polylines
from pixelpen.geometry.transforms import (
    apply,
    as_matrix,
    as_number,
    as_pair,
    as_points,
    compose,
    identity,
    invert,
    reflect,
    rotate,
    scale,
    scale_factor,
    shear,
    translate,
)
from pixelpen.geometry.viewing import Rect, ViewingPipeline, as_rect, window_to_viewport

__all__ = [
    "BEZIER_BASIS", "BOTTOM", "BSPLINE_BASIS", "DEFAULT_TOLERANCE", "LEFT", "RIGHT", "Rect", "TOP",
    "ViewingPipeline", "apply", "as_convex_window", "as_matrix", "as_number", "as_pair", "as_pattern",
    "as_points", "as_rect", "as_segments", "basis_to_bezier", "bernstein", "bezier_point", "bspline_basis",
    "bspline_point", "clip_polygon", "clip_polygon_convex", "clip_polylines", "clip_segments",
    "clip_segments_convex", "compose", "dash_polylines", "eval_basis", "flatten_arc", "flatten_bezier",
    "flatten_beziers", "flatten_bspline", "identity", "invert", "open_uniform_knots", "outcodes", "reflect",
    "rotate", "scale", "scale_factor", "shear", "translate", "uniform_knots", "window_to_viewport",
]
