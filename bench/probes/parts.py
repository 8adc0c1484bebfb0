#!/usr/bin/env python3
"""Machined parts against a backlight: rounded rectangles, rendered
independently of vicurve.

Rectangles of 70 x 40 px turned by 0.3 rad, corner radius 0 (sharp), 1.5,
4 and 12 px, 16x supersampled pixel coverage, Gaussian blur 0.7, 1.5 and
2.5 px (scipy), dark on bright (40 on 210) and bright on dark, one gray
level of Gaussian noise, 8 bits, in a 128 x 96 image; each measured by
`vicurve measure` from the automatic start and from a closed polyline
through the four corners 2 px outside (four clicks). Every output sample
is scored by its signed distance to the exact outline. Prints, per corner
radius and blur, the outcomes and, over the measurements, the largest
|mean error| (px), the largest |error| of a sample (px) and the largest
|error / sigma| of a sample, on the sides (samples more than 3 px plus
the blur from a corner's arc) and at the corners.

    python bench/probes/parts.py target/release/vicurve /tmp/parts

Needs numpy, scipy and imageio (bench/peers/requirements.txt).
"""
import os
import sys

import imageio.v3 as iio
import numpy as np
from scipy.ndimage import gaussian_filter

from dots import measure

W, H = 128, 96
SUPERSAMPLE = 16
HALF = (35.0, 20.0)
ANGLE = 0.3
RADII = (0.0, 1.5, 4.0, 12.0)
BLURS = (0.7, 1.5, 2.5)


def local(px, py, cx, cy):
    """Points in the part's frame (x along its long side)."""
    c, s = np.cos(ANGLE), np.sin(ANGLE)
    return c * (px - cx) + s * (py - cy), -s * (px - cx) + c * (py - cy)


def distance(px, py, cx, cy, r):
    """Signed distance (outside positive) to the rounded rectangle, and
    the distance along the outline to the nearest corner's arc (0 on it)."""
    u, v = local(px, py, cx, cy)
    qx, qy = np.abs(u) - (HALF[0] - r), np.abs(v) - (HALF[1] - r)
    outside = np.hypot(np.maximum(qx, 0), np.maximum(qy, 0))
    d = outside + np.minimum(np.maximum(qx, qy), 0) - r
    # Along a side, how far the foot is from where the arc begins.
    to_corner = np.maximum(np.maximum(-qx, -qy), 0)
    return d, to_corner


def render(cx, cy, r, blur, dark, seed):
    """The part's image: coverage to 1/256 px^2, blurred, noisy, 8 bits."""
    off = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    y, x = np.mgrid[0:H, 0:W].astype(float)
    cover = np.zeros((H, W))
    for dy in off:
        for dx in off:
            cover += distance(x + dx, y + dy, cx, cy, r)[0] <= 0
    cover /= SUPERSAMPLE**2
    cover = gaussian_filter(cover, blur, mode="nearest", truncate=6)
    lo, hi = (210.0, 40.0) if dark else (40.0, 210.0)
    noise = np.random.default_rng(seed).normal(0.0, 1.0, cover.shape)
    return np.clip(np.round(lo + (hi - lo) * cover + noise), 0, 255).astype(np.uint8)


def clicks(cx, cy, name):
    """A closed polyline through the corners, 2 px outside: its CSV."""
    c, s = np.cos(ANGLE), np.sin(ANGLE)
    hx, hy = HALF[0] + 2, HALF[1] + 2
    with open(name, "w") as f:
        f.write("x,y\n")
        for u, v in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)):
            f.write(f"{cx + c * u - s * v:.3f},{cy + s * u + c * v:.3f}\n")
    return f"polyline:{name}"


def main():
    binary, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    print("| corner radius | blur | converged | max abs(mean error) px "
          "| sides: max abs(error) px | sides: max abs(error / sigma) "
          "| corners: max abs(error) px | corners: max abs(error / sigma) |")
    print("|---|---|---|---|---|---|---|---|")
    notes = []
    for r in RADII:
        for blur in BLURS:
            converged, runs, means = 0, 0, []
            sides, corners = ([], []), ([], [])
            for dark in (True, False):
                for seed in (1, 2):
                    cx, cy = 63.4 + 0.13 * seed, 47.7 - 0.21 * seed
                    name = f"{out}/p{r}-b{blur}-{int(dark)}-{seed}"
                    iio.imwrite(name + ".png", render(cx, cy, r, blur, dark, seed))
                    starts = {"auto": None, "clicks": clicks(cx, cy, name + "-start.csv")}
                    extra = ["--closed"]
                    for start, init in starts.items():
                        runs += 1
                        result, error = measure(binary, name + ".png", f"{name}-{start}", init,
                                                extra if init else ())
                        if result is None:
                            notes.append(f"r {r} blur {blur} {start} {name}: {error[0]}")
                            continue
                        d, outcome = result
                        if outcome != "converged":
                            notes.append(f"r {r} blur {blur} {start} {name}: {outcome}")
                            continue
                        converged += 1
                        e, along = distance(d["x"], d["y"], cx, cy, r)
                        ratio = np.abs(e) / d["sigma"]
                        means.append(abs(e.mean()))
                        side = along > 3 + blur
                        for keep, (worst, ratios) in ((side, sides), (~side, corners)):
                            if keep.any():
                                worst.append(np.abs(e[keep]).max())
                                ratios.append(ratio[keep].max())
            cells = [f"{converged}/{runs}"]
            if converged:
                cells.append(f"{max(means):.4f}")
                for worst, ratios in (sides, corners):
                    cells += [f"{max(worst):.3f}", f"{max(ratios):.1f}"] if worst else ["", ""]
            print(f"| {r} | {blur} | " + " | ".join(cells) + " |")
    for line in notes:
        print("not converged:", line)


if __name__ == "__main__":
    main()
