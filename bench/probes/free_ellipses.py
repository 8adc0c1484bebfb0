#!/usr/bin/env python3
"""Small ellipses measured as free-form curves (no model), rendered
independently of vicurve as `ellipses.py` renders them.

Semi-axes 6 x 3.6 to 24 x 14 px at three angles, 16x supersampled pixel
coverage, Gaussian blur 0.7, 1.5 and 2.5 px (scipy), gray 40 to 210, one
gray level of Gaussian noise, 8 bits; each measured by `vicurve measure`
from a circle of the mean semi-axis 0.63 px off the centre and from the
automatic start. Every output sample is scored by its signed distance to
the exact ellipse. Prints, per ellipse and blur, the outcomes and, over
the six measurements, the largest |mean error| (px), the largest |error|
of a sample (px) and the largest |error / sigma| of a sample.

    python bench/probes/free_ellipses.py target/release/vicurve /tmp/free

Needs numpy, scipy and imageio (bench/peers/requirements.txt).
"""
import os
import sys

import imageio.v3 as iio
import numpy as np

from dots import measure
from ellipses import render

ELLIPSES = ((6, 3.6), (10, 6), (16, 9.6), (24, 14))
BLURS = (0.7, 1.5, 2.5)
SEEDS = (1, 2, 3)


def distance(px, py, cx, cy, a, b, angle):
    """Signed distance (outside positive) of points to the ellipse."""
    c, s = np.cos(angle), np.sin(angle)
    u = c * (px - cx) + s * (py - cy)
    w = -s * (px - cx) + c * (py - cy)
    t = np.linspace(0, 2 * np.pi, 20001)
    d = np.hypot(u[:, None] - a * np.cos(t)[None], w[:, None] - b * np.sin(t)[None]).min(1)
    return np.where((u / a) ** 2 + (w / b) ** 2 < 1, -d, d)


def main():
    binary, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    print("| semi-axes | blur | converged | max abs(mean error) px | max abs(error) px | max abs(error / sigma) |")
    print("|---|---|---|---|---|---|")
    for a, b in ELLIPSES:
        for blur in BLURS:
            converged, means, worst, ratios = 0, [], [], []
            for seed in SEEDS:
                cx, cy, angle = 31.4 + 0.1 * seed, 32.3 - 0.07 * seed, 0.5 + 0.3 * seed
                name = f"{out}/e{a}-{blur}-{seed}"
                iio.imwrite(name + ".png", render(cx, cy, a, b, angle, blur, seed))
                circle = f"circle:{cx + 0.6:.3f},{cy - 0.2:.3f},{0.5 * (a + b):.3f}"
                for start, init in (("circle", circle), ("auto", None)):
                    result, _ = measure(binary, name + ".png", f"{name}-{start}", init)
                    if result is None or result[1] != "converged":
                        continue
                    converged += 1
                    d = result[0]
                    e = distance(d["x"], d["y"], cx, cy, a, b, angle)
                    means.append(abs(e.mean()))
                    worst.append(np.abs(e).max())
                    ratios.append((np.abs(e) / d["sigma"]).max())
            if converged:
                print(f"| {a} x {b} | {blur} | {converged}/6 | {max(means):.3f} | {max(worst):.3f} | {max(ratios):.1f} |")
            else:
                print(f"| {a} x {b} | {blur} | 0/6 | | | |")


if __name__ == "__main__":
    main()
