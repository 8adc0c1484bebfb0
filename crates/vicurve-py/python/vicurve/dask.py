"""Measure or track collections of images on a Dask cluster.

Needs ``dask[distributed]`` (an optional dependency). Each image (for
``measure``) or each sequence (for ``track``) is one task on the given
``distributed.Client``; the workers run ``vicurve.measure`` and
``vicurve.track`` (the same engine, the GIL released), and the results come
back as tables: a pandas DataFrame when pandas is installed, else a dict of
NumPy arrays, in the order of the collection, whichever worker finished
first. A sequence is never split (each frame starts from the one before).

Inputs travel to the workers: give paths (read on the workers, which must
see the files) rather than arrays when the images are large. Starting
curves are sent as plain data and rebuilt on the worker.

Example::

    from distributed import Client
    import vicurve.dask
    client = Client("scheduler:8786")
    table = vicurve.dask.track(["run1/*.png", "run2/*.png"],
                               vicurve.Circle(320, 240, 100), client)
"""

import numpy as np

import vicurve

#: The columns of ``measure``'s table, after ``image`` (its index in the
#: collection) and ``name``.
MEASURE_COLUMNS = ("outcome", "reason", "iterations", "residual", "length", "area")


def _portable(init):
    """A starting curve as plain data (vicurve's classes do not pickle)."""
    if isinstance(init, vicurve.Circle):
        return ("circle", (init.cx, init.cy, init.r))
    if isinstance(init, vicurve.Segment):
        return ("segment", (init.x0, init.y0, init.x1, init.y1))
    if isinstance(init, vicurve.Polyline):
        return ("polyline", (np.asarray(init.points), init.closed))
    return ("as_is", init)


def _rebuild(portable):
    kind, value = portable
    if kind == "circle":
        return vicurve.Circle(*value)
    if kind == "segment":
        return vicurve.Segment(*value)
    if kind == "polyline":
        return vicurve.Polyline(value[0], closed=value[1])
    return value


def _name(image, index):
    return str(image) if isinstance(image, (str, bytes)) or hasattr(image, "__fspath__") \
        else f"image_{index:04}"


def measure_row(index, image, portable_init, options):
    """One image measured: a row of ``measure``'s table (a failure is a row
    with outcome "failed" and its reason, not an exception)."""
    row = {"image": index, "name": _name(image, index)}
    try:
        r = vicurve.measure(image, _rebuild(portable_init), **options)
        row.update(outcome=r.outcome, reason="", iterations=r.iterations,
                   residual=float(r.history[-1]["residual_rms"]) if r.history else np.nan,
                   length=r.length, area=np.nan if r.area is None else r.area)
    except vicurve.FitError as e:
        row.update(outcome="diverged", reason=str(e), iterations=-1,
                   residual=np.nan, length=np.nan, area=np.nan)
    except (ValueError, OSError) as e:
        row.update(outcome="failed", reason=str(e), iterations=-1,
                   residual=np.nan, length=np.nan, area=np.nan)
    return row


def track_table(index, frames, portable_init, options):
    """One sequence tracked: ``Tracker.summary`` as a dict of arrays, with
    the sequence's index."""
    tracker = vicurve.track(frames, _rebuild(portable_init), progress=False, **options)
    for _ in tracker:
        pass
    table = tracker.summary(pandas=False)
    table = {"sequence": np.full(len(table["frame"]), index), **table}
    return table


def _table(columns):
    try:
        import pandas
    except ImportError:
        return columns
    return pandas.DataFrame(columns)


def _rows_to_columns(rows):
    keys = ("image", "name") + MEASURE_COLUMNS
    return {k: np.array([r[k] for r in rows]) for k in keys}


def _concat(tables):
    if not tables:
        return {}
    return {k: np.concatenate([t[k] for t in tables]) for k in tables[0]}


def measure(images, init, client, **options):
    """Measure every image of ``images`` (paths or 2-D arrays) from
    ``init`` on ``client``; ``options`` as for ``vicurve.measure``.
    Returns one row per image: image, name, outcome, reason, iterations,
    residual, length, area."""
    portable = _portable(init)
    futures = [client.submit(measure_row, k, img, portable, options, pure=False)
               for k, img in enumerate(images)]
    return _table(_rows_to_columns(client.gather(futures)))


def measure_serial(images, init, **options):
    """``measure`` in this process, for comparison and small collections."""
    portable = _portable(init)
    return _table(_rows_to_columns(
        [measure_row(k, img, portable, options) for k, img in enumerate(images)]))


def track(sequences, init, client, **options):
    """Track a curve through every sequence of ``sequences`` (each what
    ``vicurve.track`` takes: a glob, a multi-page TIFF, a list of paths, a
    3-D array) from ``init``, one task per sequence. Returns the sequences'
    summaries one after the other, with a ``sequence`` column."""
    portable = _portable(init)
    futures = [client.submit(track_table, k, s, portable, options, pure=False)
               for k, s in enumerate(sequences)]
    return _table(_concat(client.gather(futures)))


def track_serial(sequences, init, **options):
    """``track`` in this process."""
    portable = _portable(init)
    return _table(_concat([track_table(k, s, portable, options)
                           for k, s in enumerate(sequences)]))
