"""Throughput of a campaign's three inputs and of 2 Dask workers.

A 256 x 256 16-bit disc drifting and growing over N frames (blur 1 px, 1 %
noise) tracked by ``vicurve.track`` from PNG files (a glob), from one
multi-page TIFF and from a 3-D array; then every 5th frame measured with
the default schedule serially and by ``vicurve.dask.measure`` on a
``LocalCluster`` of 2 thread workers.

    python crates/vicurve-py/bench/bench_campaign.py [--frames N]

Prints frames (or images) per second; timings depend on the machine and
its load, so they are printed, never asserted.
"""

import argparse
import pathlib
import sys
import tempfile
import time

import numpy as np

import vicurve
import vicurve.dask

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
from test_track import write_png16, write_tiff_stack  # noqa: E402

SIZE = 256


def frames(n):
    out = np.empty((n, SIZE, SIZE), np.uint16)
    for k in range(n):
        out[k], _ = vicurve.synth(
            "disc", size=(SIZE, SIZE), center=(120.3 + 0.05 * k, 126.6),
            radius=80 + 0.02 * k, blur=1.0, noise=0.01, seed=k + 1, bits=16)
    return out


def track_rate(source, n):
    t = time.perf_counter()
    ok = sum(f.ok for f in vicurve.track(source, vicurve.Circle(120, 127, 78), progress=False))
    return ok, n / (time.perf_counter() - t)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--frames", type=int, default=300)
    n = parser.parse_args().frames
    stack = frames(n)
    d = pathlib.Path(tempfile.mkdtemp())
    for k in range(n):
        write_png16(d / f"f_{k:04}.png", stack[k])
    write_tiff_stack(d / "s.tif", stack)
    for name, source in [("PNG files", str(d / "f_*.png")),
                         ("multi-page TIFF", str(d / "s.tif")), ("3-D array", stack)]:
        ok, rate = track_rate(source, n)
        print(f"track, {name}: {ok}/{n} frames, {rate:.1f} frames/s", flush=True)
    import distributed
    images = [str(d / f"f_{k:04}.png") for k in range(0, n, 5)]
    init = vicurve.Circle(125, 127, 80)
    t = time.perf_counter()
    vicurve.dask.measure_serial(images, init)
    serial = len(images) / (time.perf_counter() - t)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        t = time.perf_counter()
        vicurve.dask.measure(images, init, client)
        dask = len(images) / (time.perf_counter() - t)
    print(f"measure, {len(images)} images: one process {serial:.1f} images/s, "
          f"Dask 2 workers {dask:.1f} images/s")


if __name__ == "__main__":
    main()
