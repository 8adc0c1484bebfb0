#!/usr/bin/env python3
"""Dots near the image border, rendered independently of vicurve.

Discs of radius 8, 12 and 20 px whose edge passes 1, 3, 6 and 10 px from
the left border of a 64x64 image, rendered as `dots.py` renders them
(16x supersampled coverage, Gaussian blur 0.7, 1.5 and 2.5 px, one gray
level of noise, 8 bits, bright on dark); each measured by `vicurve
measure` from a circle 0.63 px off its centre and 0.5 px too large, and
from the automatic start. Prints, per radius, blur and gap, the outcomes,
the largest |radius error| (px), the largest |error / sigma| (the median
sample sigma) and the last stage's profile.

    python bench/probes/border.py target/release/vicurve /tmp/border
    python bench/probes/border.py target/release/vicurve /tmp/border -0.3,-0.7

An optional third argument gives other gaps (px, comma-separated); a
negative gap puts the edge beyond the first column of pixel centres
(-0.3: through it, the disc cut by the border beyond -0.8).

Needs numpy, scipy and imageio (bench/peers/requirements.txt).
"""
import json
import os
import sys

import imageio.v3 as iio
import numpy as np

from dots import measure, render

RADII = (8, 12, 20)
BLURS = (0.7, 1.5, 2.5)
GAPS = (1.0, 3.0, 6.0, 10.0)


def main():
    binary, out = sys.argv[1], sys.argv[2]
    gaps = tuple(float(g) for g in sys.argv[3].split(",")) if len(sys.argv) > 3 else GAPS
    os.makedirs(out, exist_ok=True)
    print("| radius | blur | gap | outcomes | max abs(error) px | max abs(error / sigma) | last profile |")
    print("|---|---|---|---|---|---|---|")
    for r in RADII:
        for blur in BLURS:
            for gap in gaps:
                cx, cy = r + gap + 0.3, 32.17
                name = f"{out}/b{r}-{blur}-{gap}"
                iio.imwrite(name + ".png", render(cx, cy, r, blur, True, 1))
                starts = {
                    "circle": f"circle:{cx + 0.6:.3f},{cy - 0.2:.3f},{r + 0.5:.3f}",
                    "auto": None,
                }
                outcomes, errors, ratios, profiles = [], [], [], set()
                for start, init in starts.items():
                    res = f"{name}-{start}"
                    result, _ = measure(binary, name + ".png", res, init)
                    if result is None:
                        outcomes.append("refused")
                        continue
                    d, outcome = result
                    outcomes.append(outcome)
                    stages = json.load(open(res + ".json"))["stages"]
                    profiles.add(stages[-1]["profile"]["type"])
                    if outcome != "converged":
                        continue
                    error = np.hypot(d["x"] - cx, d["y"] - cy).mean() - r
                    errors.append(abs(error))
                    ratios.append(abs(error) / np.median(d["sigma"]))
                worst = f"{max(errors):.4f} | {max(ratios):.1f}" if errors else "|"
                print(f"| {r} | {blur} | {gap:g} | {' '.join(outcomes)} | {worst} | {' '.join(sorted(profiles))} |")


if __name__ == "__main__":
    main()
