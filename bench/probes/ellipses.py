#!/usr/bin/env python3
"""Small ellipses (oblique dots, holes seen at an angle), rendered
independently of vicurve and measured with `--model ellipse`.

Semi-axes 6 x 3.6 to 12 x 8 px at three angles, 16x supersampled pixel
coverage, Gaussian blur 1.5 and 2.5 px (scipy), gray 40 to 210, one gray
level of Gaussian noise, 8 bits; each measured from a circle of the mean
semi-axis 0.64 px off the centre. Prints, per ellipse and blur, the largest
|error| of the long and the short semi-axis (px) and of error / sigma over
the three draws, and the fitted blurs.

    python bench/probes/ellipses.py target/release/vicurve /tmp/ellipses

Needs numpy, scipy and imageio (bench/peers/requirements.txt).
"""
import json
import os
import subprocess
import sys

import imageio.v3 as iio
import numpy as np
from scipy.ndimage import gaussian_filter

SIZE = 64
SUPERSAMPLE = 16
ELLIPSES = ((6, 3.6), (8, 4.8), (10, 6), (12, 8))
BLURS = (1.5, 2.5)
SEEDS = (1, 2, 3)


def render(cx, cy, a, b, angle, blur, seed):
    """The ellipse's image: exact-coverage to 1/256 px^2, blurred, noisy."""
    off = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    y, x = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    cover = np.zeros((SIZE, SIZE))
    c, s = np.cos(angle), np.sin(angle)
    for dy in off:
        for dx in off:
            u = c * (x + dx - cx) + s * (y + dy - cy)
            w = -s * (x + dx - cx) + c * (y + dy - cy)
            cover += (u / a) ** 2 + (w / b) ** 2 <= 1
    cover /= SUPERSAMPLE**2
    cover = gaussian_filter(cover, blur, mode="nearest", truncate=6)
    noise = np.random.default_rng(seed).normal(0.0, 1.0, cover.shape)
    return np.clip(np.round(40 + 170 * cover + noise), 0, 255).astype(np.uint8)


def main():
    binary, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    print("| semi-axes | blur | long px | long / sigma | short px | short / sigma | blurs |")
    print("|---|---|---|---|---|---|---|")
    for a, b in ELLIPSES:
        for blur in BLURS:
            worst = [0.0, 0.0, 0.0, 0.0]
            blurs, failed = [], []
            for seed in SEEDS:
                cx, cy, angle = 31.4 + 0.1 * seed, 32.3 - 0.07 * seed, 0.5 + 0.3 * seed
                name = f"{out}/e{a}-{blur}-{seed}"
                iio.imwrite(name + ".png", render(cx, cy, a, b, angle, blur, seed))
                init = f"circle:{cx + 0.5:.2f},{cy - 0.4:.2f},{(a + b) / 2:.2f}"
                run = subprocess.run(
                    [binary, "measure", name + ".png", "--init", init,
                     "--model", "ellipse", "--out", name + ".json"],
                    capture_output=True, text=True)
                try:
                    model = json.load(open(name + ".json"))["model"]
                except (OSError, ValueError, KeyError):
                    failed.append(f"seed {seed}: {run.stderr.strip()[-80:]}")
                    continue
                if model["outcome"]["status"] != "converged":
                    failed.append(f"seed {seed}: {model['outcome']['status']}")
                    continue
                p = {q["name"]: q for q in model["parameters"]}
                long, short = sorted((p["a"], p["b"]), key=lambda q: -q["value"])
                el, es = long["value"] - a, short["value"] - b
                worst = [max(worst[0], abs(el)), max(worst[1], abs(el) / long["sigma"]),
                         max(worst[2], abs(es)), max(worst[3], abs(es) / short["sigma"])]
                blurs.append(model["profile"].get("blur", float("nan")))
            print(f"| {a} x {b} | {blur} | {worst[0]:.4f} | {worst[1]:.1f} | {worst[2]:.4f} "
                  f"| {worst[3]:.1f} | {' '.join(f'{x:.3f}' for x in blurs)} |")
            for line in failed:
                print(f"not measured: {a} x {b} blur {blur} {line}")


if __name__ == "__main__":
    main()
