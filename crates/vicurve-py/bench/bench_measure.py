"""Time vicurve.measure from Python on the images of the Rust benchmarks.

The Rust side is ``cargo run --release -p vicurve-py --example
bench_measure -- N``: the same images (``vicurve.synth`` draws the presets
``paper_disc`` and ``star_1024`` exactly), starting circles and settings,
measured "from the image" like the criterion benches "paper disc, one stage
(from the image)" and "star 1024x1024, default schedule (from the image)"
of docs/benchmarks.md (the cubic prefilter is part of every call, as it is
of a Python call). What Python adds: converting the array to the engine's
float64 image, and building the result object.

    python crates/vicurve-py/bench/bench_measure.py [--repeat N]

Prints, per case, the best and the median wall-clock time of N calls after
a few warm-up calls.
"""

import argparse
import statistics
import time

import vicurve


def paper_disc_case():
    """The paper's disc (512 x 512, R = 10 profile, 8-bit), one stage."""
    image, _ = vicurve.synth("paper-disc")
    init = vicurve.Circle(255, 257, 203)
    kwargs = dict(stages=[(10, 25)], blur_correction=False)
    return image, init, kwargs


def star_case():
    """The 1024 x 1024 star (blur 1, 1 % noise, 8-bit), default schedule."""
    image, _ = vicurve.synth(
        "star", size=(1024, 1024), center=(512.3, 511.6), radius=300, amplitude=0.2,
        lobes=5, blur=1.0, noise=0.01, seed=3, bits=8,
    )
    return image, vicurve.Circle(522.3, 511.6, 300), {}


def time_calls(image, init, kwargs, repeat, warmup):
    for _ in range(warmup):
        vicurve.measure(image, init, **kwargs)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        vicurve.measure(image, init, **kwargs)
        times.append(time.perf_counter() - start)
    return min(times), statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=50, help="timed calls per case")
    parser.add_argument("--warmup", type=int, default=3, help="untimed calls first")
    args = parser.parse_args()

    disc, disc_init, disc_kwargs = paper_disc_case()
    star, star_init, star_kwargs = star_case()
    cases = [
        ("paper disc, one stage (R = 10, 25 elements), uint8 array", disc, disc_init,
         disc_kwargs, args.repeat),
        ("paper disc, one stage, float64 array", disc / 255.0, disc_init, disc_kwargs,
         args.repeat),
        ("1024^2 star, default schedule, uint8 array", star, star_init, star_kwargs,
         max(5, args.repeat // 5)),
    ]
    print(f"vicurve {vicurve.__version__}; best and median of N calls (after "
          f"{args.warmup} warm-up calls)")
    for name, image, init, kwargs, repeat in cases:
        best, median = time_calls(image, init, kwargs, repeat, args.warmup)
        print(f"{name}: best {best * 1e3:.1f} ms, median {median * 1e3:.1f} ms (N = {repeat})")


if __name__ == "__main__":
    main()
