"""Sub-pixel measurement of curves and edges in images.

vicurve measures a *contour* (a thin line: a fibre, a wire, a crack front) or
a *silhouette* (an edge: a part against a backlight) in a grayscale image by
Virtual Image Correlation with B-splines (Réthoré & François, 2013). The
engine is the Rust library of the same name; this package calls it with the
GIL released.

Coordinates are pixels: ``x`` is the column, ``y`` the row, and the centre of
the pixel in row ``i``, column ``j`` is at ``(x, y) = (j, i)``, so
``image[i, j]`` is the gray level at ``(j, i)``. Closed curves run
counterclockwise on screen with the normal pointing outward; open curves keep
the direction of their start, the normal on the screen-right of travel.

Functions
---------
measure(image, init, ...) -> Result
    Measure a curve from a starting curve (``Circle``, ``Segment``,
    ``Polyline``) or an automatic start (``Auto``, or ``init=None``).
synth(shape, ...) -> (image, truth)
    Render a test image of exactly known geometry (as ``vicurve synth``).
eval(points, truth) -> dict
    Bias, scatter and largest error of points against the exact curve.
basis_values(degree, n_elements, length, closed, s) -> ndarray
    The engine's uniform B-spline basis, for checks and plots.
interpolate(image, xs, ys, kind="cubic") -> ndarray
    The engine's image interpolation (cubic B-spline, bilinear, Keys).
track(frames, init, ..., out_dir=None) -> Tracker
    Track a curve through a sequence; iterate for one TrackedFrame per frame.
run(job) -> table
    Run a job file as ``vicurve run job.toml``; returns its summary.

Images are 2-D NumPy arrays (``uint8`` divided by 255, ``uint16`` by 65535,
``float32``/``float64`` taken as they are, exactly as image files are read)
or paths to PNG, TIFF or JPEG files.

Errors: ``FileNotFoundError`` for a missing file, ``ValueError`` for bad
parameters, images or curves, ``FitError`` (a ``RuntimeError``) for a fit
that diverged, with the partial result in its ``result`` attribute; a fit
that reached its iteration limit returns with a ``RuntimeWarning``.

Sequences: ``track(frames, init, ...)`` follows a curve through a 3-D array,
a list of arrays or paths, a glob or a multi-page TIFF, each frame started from
the previous result as ``vicurve track`` does, yielding one frame at a time;
with ``out_dir`` it writes the files of ``vicurve track --out-dir`` and skips
the frames an earlier run did. ``run("job.toml")`` runs a job file.

Example::

    import vicurve
    image, truth = vicurve.synth("disc", size=(400, 400), radius=150)
    result = vicurve.measure(image, vicurve.Circle(200, 200, 140))
    print(result.outcome, result.length, result.area)
    print(vicurve.eval(result.points, truth))
"""

from ._vicurve import (
    Auto,
    Circle,
    FitError,
    Polyline,
    Result,
    Segment,
    __version__,
    basis_values,
    eval,
    interpolate,
    measure,
    run,
    synth,
    track,
)
from ._vicurve import measure_all as _measure_all

__all__ = [
    "Auto",
    "Circle",
    "FitError",
    "Polyline",
    "Result",
    "Segment",
    "__version__",
    "basis_values",
    "eval",
    "interpolate",
    "measure",
    "measure_all",
    "run",
    "synth",
    "track",
]


def measure_all(image, **kwargs):
    """Measure every object of ``image``; returns ``(results, table)``.

    ``results`` has one ``Result`` per object (None when it could not be
    measured at all), numbered row-major by centroid; ``table`` one row per
    object: a pandas DataFrame when pandas is installed, else a dict of
    NumPy arrays. Keywords: ``polarity``, ``model``, ``min_length``,
    ``min_area``, ``roi``, ``include_border``, ``holes``, ``kind``
    (``"contour"``: every line), ``min_strength``, ``corners`` (see
    ``_vicurve.measure_all``).
    """
    import numpy as np

    results, columns = _measure_all(image, **kwargs)
    table = {
        k: (np.array(v, dtype=str) if k in ("outcome", "message") else v)
        for k, v in columns.items()
    }
    try:
        import pandas as pd
    except ImportError:
        return results, table
    return results, pd.DataFrame(table)
