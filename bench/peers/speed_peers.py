#!/usr/bin/env python3
"""Time the silhouette peers of run_peers.py on given images, in-process.

For each image (8- or 16-bit gray PNG), read once into memory, each peer is
called as run_peers.py calls it (``peer_skimage``: plateau levels, then
scikit-image ``find_contours`` at the mid level, longest contour kept;
``peer_subpixel_edges``: subpixel-edges at 10 % of the contrast, then the
3 px filter around the Otsu contour), once as a warm-up (numba compiles
subpixel-edges on its first call), then ``--repeats`` times under
``time.perf_counter``. Decoding the image is not timed.

Prints one JSON object on stdout:
``{"versions": {...}, "results": [{"image", "tool", "median", "min", "max",
"points"}], "errors": [{"image", "tool", "error"}]}``, times in seconds.
``vicurve bench speed --peers`` runs it and prints the ratios.

Usage: python speed_peers.py [--repeats 7] [--spe-iters 0,1] IMAGE...
"""

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import run_peers  # noqa: E402  (sets np.int for subpixel-edges, imports the peers)
import cv2  # noqa: E402
import numpy as np  # noqa: E402
import skimage  # noqa: E402


def timed(fn, repeats):
    """One warm-up call, then `repeats` timed calls: (median, min, max, result)."""
    result = fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), max(times), result


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("images", nargs="+")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--spe-iters", default="0,1",
                    help="subpixel-edges iteration settings to time (comma-separated)")
    args = ap.parse_args()
    versions = {"python": sys.version.split()[0], "numpy": np.__version__,
                "scikit-image": skimage.__version__, "opencv": cv2.__version__}
    try:
        from importlib.metadata import version
        versions["subpixel-edges"] = version("subpixel-edges")
    except Exception:  # not installed: its rows are errors below
        pass
    results, errors = [], []
    for path in args.images:
        img = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if img is None:
            errors.append({"image": path, "tool": "read", "error": "cannot read"})
            continue
        if img.ndim == 3:
            img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        tools = [("skimage-find_contours", lambda: run_peers.peer_skimage(img, False))]
        for it in (int(v) for v in args.spe_iters.split(",") if v.strip()):
            tools.append((f"subpixel-edges-iters{it}",
                          lambda it=it: run_peers.peer_subpixel_edges(img, it)))
        for name, fn in tools:
            if name.startswith("subpixel") and run_peers.subpixel_edges is None:
                errors.append({"image": path, "tool": name,
                               "error": f"import failed: {run_peers.SPE_IMPORT_ERROR}"})
                continue
            try:
                med, lo, hi, xy = timed(fn, args.repeats)
                results.append({"image": path, "tool": name, "median": med, "min": lo,
                                "max": hi, "points": int(len(xy))})
            except Exception as exc:
                errors.append({"image": path, "tool": name,
                               "error": f"{type(exc).__name__}: {exc}"[:300]})
    json.dump({"versions": versions, "results": results, "errors": errors}, sys.stdout)
    print()


if __name__ == "__main__":
    main()
