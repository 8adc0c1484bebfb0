#!/usr/bin/env python3
"""Dots a few blurs across, rendered independently of vicurve.

Discs of radius 3 to 12 px, 16x supersampled pixel coverage, Gaussian blur
0.7, 1.5 and 2.5 px (scipy), gray 40 and 210 (bright and dark dots), one
gray level of Gaussian noise, 8 bits; each measured by `vicurve measure`
from a circle 0.78 px off its centre and 0.4 px too large, and from the
automatic start. Prints, per radius and blur, the largest |radius error|
(px) and |error / sigma| (the median sample sigma) over its eight
measurements, and the refusals.

    python bench/probes/dots.py target/release/vicurve /tmp/dots

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
RADII = (3, 4, 4.5, 5, 6, 8, 12)
BLURS = (0.7, 1.5, 2.5)


def render(cx, cy, r, blur, bright, seed):
    """The dot's image: exact-coverage to 1/256 px^2, blurred, noisy, 8 bits."""
    off = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    y, x = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    cover = np.zeros((SIZE, SIZE))
    for dy in off:
        for dx in off:
            cover += (x + dx - cx) ** 2 + (y + dy - cy) ** 2 <= r * r
    cover /= SUPERSAMPLE**2
    cover = gaussian_filter(cover, blur, mode="nearest", truncate=6)
    lo, hi = (40.0, 210.0) if bright else (210.0, 40.0)
    noise = np.random.default_rng(seed).normal(0.0, 1.0, cover.shape)
    return np.clip(np.round(lo + (hi - lo) * cover + noise), 0, 255).astype(np.uint8)


def measure(binary, png, out, init, extra=()):
    """`vicurve measure` of `png` from `init` (an `--init` value; None for
    the automatic start) with the `extra` arguments, its results in
    `out`.json and `out`.csv:
    ((samples, outcome), None), or (None, [its last error line]) when it
    was refused. A diverged fit (exit code 3) still writes its results."""
    args = [binary, "measure", png, "--out", out + ".json", "--points", out + ".csv"]
    if init:
        args += ["--init", init]
    args += list(extra)
    run = subprocess.run(args, capture_output=True, text=True)
    if run.returncode not in (0, 3) or not os.path.exists(out + ".csv"):
        return None, run.stderr.strip().splitlines()[-1:] or [""]
    d = np.genfromtxt(out + ".csv", delimiter=",", names=True)
    outcome = json.load(open(out + ".json"))["outcome"]["status"]
    return (d, outcome), None


def main():
    binary, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    print("| radius | blur | measured | max abs(error) px | max abs(error / sigma) |")
    print("|---|---|---|---|---|")
    refusals = []
    for r in RADII:
        for blur in BLURS:
            errors, ratios, measured = [], [], 0
            for bright in (True, False):
                for seed in (1, 2):
                    cx, cy = 31.3 + 0.17 * seed, 32.6 - 0.11 * seed
                    name = f"{out}/d{r}-b{blur}-{int(bright)}-{seed}"
                    iio.imwrite(name + ".png", render(cx, cy, r, blur, bright, seed))
                    starts = {
                        "circle": f"circle:{cx + 0.6:.3f},{cy - 0.5:.3f},{r + 0.4:.3f}",
                        "auto": None,
                    }
                    for start, init in starts.items():
                        result, error = measure(binary, name + ".png", f"{name}-{start}", init)
                        if result is None:
                            refusals.append(f"r {r} blur {blur} {start}: {error[0]}")
                            continue
                        d, outcome = result
                        if outcome != "converged":
                            refusals.append(f"r {r} blur {blur} {start}: {outcome}")
                            continue
                        measured += 1
                        error = np.hypot(d["x"] - cx, d["y"] - cy).mean() - r
                        errors.append(abs(error))
                        ratios.append(abs(error) / np.median(d["sigma"]))
            if errors:
                print(f"| {r} | {blur} | {measured}/8 | {max(errors):.4f} | {max(ratios):.1f} |")
            else:
                print(f"| {r} | {blur} | 0/8 | | |")
    for line in refusals:
        print("not measured:", line)


if __name__ == "__main__":
    main()
