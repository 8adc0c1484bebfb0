"""vicurve.track with out_dir: the files of ``vicurve track --out-dir``, and
the resume after an interruption; and the frames held in memory."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import vicurve
from conftest import without_timings
from test_track import disc_frames, write_png16, write_tiff_stack

FRAMES = 30
INIT = "circle:45,47,23"


@pytest.fixture(scope="module")
def pngs(tmp_path_factory):
    d = tmp_path_factory.mktemp("files")
    paths = []
    for k, f in enumerate(disc_frames(FRAMES)):
        p = d / f"f_{k:04}.png"
        write_png16(p, f)
        paths.append(str(p))
    return d, paths


def records(out):
    """Every frame's result file, without the stages' seconds."""
    return [without_timings((out / f"f_{k:04}.json").read_text()) for k in range(FRAMES)]


def control_points(docs):
    return [np.array(r["curve"]["control_points"]) for r in docs]


def test_out_dir_writes_the_command_lines_files_and_resumes(pngs, cli, tmp_path):
    d, paths = pngs
    cli("track", *paths, "--init", INIT, "--out-dir", tmp_path / "cli")
    whole = list(vicurve.track(paths, INIT, out_dir=tmp_path / "whole", progress=False))
    assert [f.resumed for f in whole] == [False] * FRAMES
    assert all(f.ok for f in whole)

    # Interrupted: stop iterating after k frames, then run again.
    k = 11
    first = vicurve.track(paths, INIT, out_dir=tmp_path / "resumed", progress=False)
    for _, frame in zip(range(k), first):
        pass
    del first
    done = {n: os.stat(tmp_path / "resumed" / f"f_{n:04}.json").st_mtime_ns for n in range(k)}
    assert not (tmp_path / "resumed" / f"f_{k:04}.json").exists()
    again = vicurve.track(paths, INIT, out_dir=tmp_path / "resumed", progress=False)
    frames = list(again)
    assert [f.resumed for f in frames] == [n < k for n in range(FRAMES)]
    assert frames[0].result is None and frames[k].result is not None
    assert frames[k].started_from == f"f_{k - 1:04}"
    # Frames already written are not measured (nor written) again.
    for n, t in done.items():
        assert os.stat(tmp_path / "resumed" / f"f_{n:04}.json").st_mtime_ns == t
    summary = again.summary(pandas=False)
    assert list(summary["name"]) == [f"f_{n:04}" for n in range(FRAMES)]
    assert set(summary["outcome"]) == {"converged"}

    expected = records(tmp_path / "cli")
    for out in ("whole", "resumed"):
        mine = records(tmp_path / out)
        worst = max(float(np.abs(a - b).max())
                    for a, b in zip(control_points(mine), control_points(expected)))
        assert worst <= 1e-12, (out, worst)
        # The same documents, and the same summary, byte for byte.
        assert mine == expected, out
        assert (tmp_path / out / "summary.csv").read_bytes() == \
            (tmp_path / "cli" / "summary.csv").read_bytes(), out
        for n in range(FRAMES):
            assert (tmp_path / out / f"f_{n:04}.csv").read_bytes() == \
                (tmp_path / "cli" / f"f_{n:04}.csv").read_bytes(), (out, n)
    # The yielded results are the files' curves.
    for f, r in zip(whole, expected):
        np.testing.assert_array_equal(f.result.spline["control_points"],
                                      np.array(r["curve"]["control_points"]))


def test_the_command_line_resumes_a_python_run(pngs, cli, tmp_path):
    d, paths = pngs
    out = tmp_path / "out"
    for _, frame in zip(range(7), vicurve.track(paths, INIT, out_dir=out, progress=False)):
        pass
    run = cli("track", *paths, "--init", INIT, "--out-dir", out)
    assert "7 frame(s) already done" in run.stderr
    cli("track", *paths, "--init", INIT, "--out-dir", tmp_path / "cli")
    assert records(out) == records(tmp_path / "cli")


def test_another_jobs_folder_is_refused(pngs, tmp_path):
    d, paths = pngs
    out = tmp_path / "out"
    list(vicurve.track(paths[:2], INIT, out_dir=out, progress=False))
    with pytest.raises(ValueError, match="another job"):
        vicurve.track(paths[:2], INIT, out_dir=out, degree=2)
    frames = list(vicurve.track(paths[:2], INIT, out_dir=out, degree=2, force=True,
                                progress=False))
    assert not any(f.resumed for f in frames)


# Memory: the frames of a sequence are never all in memory.

SIDE = 400
MEMORY_FRAMES = 24


# Run in a fresh interpreter, so that memory freed by earlier tests (and
# kept by the allocator) does not hide what the run allocates: the peak
# resident memory (reset through /proc/self/clear_refs) above the resident
# memory before the run, after a warm-up on small frames (thread pool,
# first allocations). "hold" stacks every frame in one array instead: the
# control that the measurement sees frames held in memory.
MEASURE = """
import sys, numpy as np, vicurve
kind, d, n, side = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
small = [vicurve.synth("disc", size=(80, 80), radius=20, blur=1.0, bits=16)[0]] * 2
for _ in vicurve.track(small, vicurve.Circle(40, 40, 19), progress=False):
    pass
def rss(field):
    for line in open("/proc/self/status"):
        if line.startswith(field + ":"):
            return int(line.split()[1]) * 1024
open("/proc/self/clear_refs", "w").write("5")
before = rss("VmRSS")
paths = [f"{d}/m_{k:04}.png" for k in range(n)]
frames = {"paths": paths, "glob": d + "/m_*.png", "stack": d + "/stack.tif"}.get(kind)
if kind == "hold":
    held = np.ones((n, side, side))
else:
    ok = [f.ok for f in vicurve.track(frames, vicurve.Circle(200, 200, 57), progress=False)]
    assert ok == [True] * n, ok
print(rss("VmHWM") - before)
"""


@pytest.fixture(scope="module")
def big_frames(tmp_path_factory):
    try:
        open("/proc/self/clear_refs", "w").write("5")
    except OSError:
        pytest.skip("needs Linux's /proc/self/clear_refs (to reset the peak)")
    d = tmp_path_factory.mktemp("memory")
    frames = np.empty((MEMORY_FRAMES, SIDE, SIDE), dtype=np.uint16)
    for k in range(MEMORY_FRAMES):
        frames[k], _ = vicurve.synth(
            "disc", size=(SIDE, SIDE), center=(200.3 + 0.1 * k, 199.6), radius=60.0 + 0.05 * k,
            blur=1.0, noise=0.01, seed=k + 1, bits=16)
    for k, f in enumerate(frames):
        write_png16(d / f"m_{k:04}.png", f)
    write_tiff_stack(d / "stack.tif", frames)
    return d


def peak_frames(d, kind):
    """Peak memory of tracking the frames (`kind`), in frames of the
    library's gray levels (float64)."""
    out = subprocess.run(
        [sys.executable, "-c", MEASURE, kind, str(d), str(MEMORY_FRAMES), str(SIDE)],
        capture_output=True, text=True, check=True)
    return int(out.stdout.split()[-1]) / (SIDE * SIDE * 8)


@pytest.mark.parametrize("kind", ["paths", "glob", "stack"])
def test_a_sequence_never_sits_in_memory(big_frames, kind):
    peak = peak_frames(big_frames, kind)
    print(f"{kind}: peak {peak:.2f} frames")
    # A few frames' worth in flight (the frame measured and the one decoded
    # ahead, each with its decoder's buffer; the interpolation coefficients
    # and the band of the frame measured), never the sequence's 24.
    assert peak < 8, (kind, peak)


def test_the_memory_measurement_sees_frames_held(big_frames):
    peak = peak_frames(big_frames, "hold")
    print(f"hold: peak {peak:.2f} frames")
    assert peak > MEMORY_FRAMES / 2, peak
