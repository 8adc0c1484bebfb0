#!/usr/bin/env python3
"""Dots in a grid, rendered independently of vicurve: a printed circle grid
seen through a defocused lens.

3x3 discs of radius 4, 5 and 6 px at pitches of 14, 18 and 24 px, 8x
supersampled pixel coverage, Gaussian blur 1.5 and 2.5 px (scipy), gray
40 and 210, one gray level of Gaussian noise, 8 bits. Each image is
measured two ways: `vicurve measure --all` (every dot, its bands kept off
its neighbours), and `vicurve measure` of the middle dot alone from a
circle 0.58 px off its centre and 0.4 px too large (which does not know
the neighbours). Every output sample is scored by its distance to its
dot's circle. Prints, per radius, pitch and blur: the dots `--all`
measured (of 9) and its largest |error| (px) and |error / sigma|; the
single measurement's outcome, largest |error| and |error / sigma|.

    python bench/probes/grids.py target/release/vicurve /tmp/grids

Needs numpy, scipy and imageio (bench/peers/requirements.txt).
"""
import csv
import json
import os
import subprocess
import sys

import imageio.v3 as iio
import numpy as np
from scipy.ndimage import gaussian_filter

SIZE = 96
SUPERSAMPLE = 8
RADII = (4, 5, 6)
PITCHES = (14, 18, 24)
BLURS = (1.5, 2.5)


def centres(pitch):
    """The nine dots' centres, the middle one off the pixel grid."""
    return [(48.3 + i * pitch, 47.6 + j * pitch) for j in (-1, 0, 1) for i in (-1, 0, 1)]


def render(dots, r, blur, seed):
    """The grid's image: coverage to 1/64 px^2, blurred, noisy, 8 bits."""
    off = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    y, x = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    cover = np.zeros((SIZE, SIZE))
    for dy in off:
        for dx in off:
            inside = np.zeros((SIZE, SIZE), bool)
            for cx, cy in dots:
                inside |= (x + dx - cx) ** 2 + (y + dy - cy) ** 2 <= r * r
            cover += inside
    cover /= SUPERSAMPLE**2
    cover = gaussian_filter(cover, blur, mode="nearest", truncate=6)
    noise = np.random.default_rng(seed).normal(0.0, 1.0, cover.shape)
    return np.clip(np.round(40.0 + 170.0 * cover + noise), 0, 255).astype(np.uint8)


def scored(xs, ys, sigmas, dots, r):
    """Largest |error| and |error / sigma| of samples, each scored against
    the circle of the dot nearest to their mean."""
    mx, my = np.mean(xs), np.mean(ys)
    cx, cy = min(dots, key=lambda c: (c[0] - mx) ** 2 + (c[1] - my) ** 2)
    e = np.hypot(xs - cx, ys - cy) - r
    return np.abs(e).max(), np.abs(e / sigmas).max()


def measure_all(binary, png, out, dots, r):
    """`measure --all`: (dots measured, largest |error|, largest ratio)."""
    run = subprocess.run(
        [binary, "measure", png, "--all", "--out", out + ".json", "--points", out + ".csv"],
        capture_output=True,
        text=True,
    )
    if not os.path.exists(out + ".csv"):
        return 0, float("nan"), float("nan"), run.stderr.strip()
    rows = list(csv.DictReader(open(out + ".csv")))
    worst = [0.0, 0.0]
    objects = sorted({q["object"] for q in rows})
    for o in objects:
        q = [a for a in rows if a["object"] == o]
        xs = np.array([float(a["x"]) for a in q])
        ys = np.array([float(a["y"]) for a in q])
        sig = np.array([float(a["sigma"]) for a in q])
        e, z = scored(xs, ys, sig, dots, r)
        worst = [max(worst[0], e), max(worst[1], z)]
    return len(objects), worst[0], worst[1], ""


def measure_one(binary, png, out, dots, r):
    """`measure` of the middle dot: (outcome, largest |error|, ratio)."""
    cx, cy = dots[4]
    run = subprocess.run(
        [binary, "measure", png, "--init", f"circle:{cx + 0.5:.2f},{cy - 0.3:.2f},{r + 0.4:.2f}",
         "--out", out + ".json", "--points", out + ".csv"],
        capture_output=True,
        text=True,
    )
    if run.returncode not in (0, 3):
        return "refused", float("nan"), float("nan")
    rows = list(csv.DictReader(open(out + ".csv")))
    xs = np.array([float(a["x"]) for a in rows])
    ys = np.array([float(a["y"]) for a in rows])
    sig = np.array([float(a["sigma"]) for a in rows])
    e, z = scored(xs, ys, sig, [dots[4]], r)
    return json.load(open(out + ".json"))["outcome"]["status"], e, z


def main():
    binary, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    print("| radius | pitch | blur | --all measured | --all max px | --all max / sigma "
          "| one dot | one dot max px | one dot max / sigma |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in RADII:
        for pitch in PITCHES:
            for blur in BLURS:
                dots = centres(pitch)
                name = f"{out}/g{r}-{pitch}-{blur}"
                iio.imwrite(name + ".png", render(dots, r, blur, 3))
                n, e, z, _ = measure_all(binary, name + ".png", name + "-all", dots, r)
                outcome, e1, z1 = measure_one(binary, name + ".png", name + "-one", dots, r)
                print(f"| {r} | {pitch} | {blur} | {n}/9 | {e:.3f} | {z:.1f} "
                      f"| {outcome} | {e1:.3f} | {z1:.1f} |")


if __name__ == "__main__":
    main()
