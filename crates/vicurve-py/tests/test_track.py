"""vicurve.track against the command-line tool's ``vicurve track`` on the
same frames: a drifting, growing disc rendered here."""

import json
import struct
import zlib

import numpy as np
import pytest

import vicurve

FRAMES = 200
SIZE = 110


def disc_frames(n):
    """Frame k: a disc drifting by (0.08, 0.05) px and growing by 0.03 px per
    frame; exact coverage, blur 1 px, 1 % noise, 16-bit."""
    frames = np.empty((n, SIZE, SIZE), dtype=np.uint16)
    for k in range(n):
        image, _ = vicurve.synth(
            "disc", size=(SIZE, SIZE), center=(45.3 + 0.08 * k, 46.6 + 0.05 * k),
            radius=25.0 + 0.03 * k, blur=1.0, noise=0.01, seed=k + 1, bits=16)
        frames[k] = image
    return frames


def write_png16(path, pixels):
    """A 16-bit grayscale PNG (an independent writer: zlib and struct)."""
    h, w = pixels.shape
    raw = b"".join(b"\x00" + pixels[i].astype(">u2").tobytes() for i in range(h))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(raw, 1)) + chunk(b"IEND", b""))


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    """The frames as an array and as PNG files, and the CLI's results."""
    frames = disc_frames(FRAMES)
    d = tmp_path_factory.mktemp("track")
    for k, f in enumerate(frames):
        write_png16(d / f"f_{k:04}.png", f)
    return frames, d


def cli_curves(cli, d, out):
    cli("track", d / "f_*.png", "--init", "circle:45,47,23", "--out-dir", d / out)
    curves = []
    for k in range(FRAMES):
        record = json.loads((d / out / f"f_{k:04}.json").read_text())
        curves.append((np.array(record["curve"]["control_points"]), record))
    return curves


def test_track_gives_the_command_lines_curves(sequence, cli):
    frames, d = sequence
    expected = cli_curves(cli, d, "cli")
    tracker = vicurve.track(frames, vicurve.Circle(45, 47, 23), progress=False)
    assert len(tracker) == FRAMES
    worst = 0.0
    count = 0
    for k, frame in enumerate(tracker):
        assert frame.index == k and frame.ok, (k, frame.outcome, frame.reason)
        ctrl, record = expected[k]
        mine = frame.result.spline["control_points"]
        assert mine.shape == ctrl.shape, k
        worst = max(worst, float(np.abs(mine - ctrl).max()))
        assert frame.started_from == ("init" if k == 0 else f"frame_{k - 1:04}")
        assert record["sequence"]["started_from"] == ("init" if k == 0 else f"f_{k - 1:04}")
        count += 1
    assert count == FRAMES
    assert worst <= 1e-12, worst
    # The same from the files, by a glob.
    by_glob = vicurve.track(str(d / "f_*.png"), "circle:45,47,23", progress=False)
    for k, frame in enumerate(by_glob):
        assert frame.name == f"f_{k:04}"
        np.testing.assert_array_equal(frame.result.spline["control_points"], expected[k][0])
    summary = by_glob.summary(pandas=False)
    assert list(summary["frame"]) == list(range(FRAMES))
    assert set(summary["outcome"]) == {"converged"}
    # The radius grows by 0.03 px per frame: the area follows.
    r = np.sqrt(summary["area"] / np.pi)
    truth = 25.0 + 0.03 * np.arange(FRAMES)
    assert np.abs(r - truth).max() < 0.05, np.abs(r - truth).max()


def test_frames_are_read_one_at_a_time_and_failures_skipped(sequence, tmp_path):
    frames, d = sequence
    produced = []

    def lazily():
        for k in range(12):
            produced.append(k)
            if k == 5:
                yield tmp_path / "missing.png"
            else:
                yield frames[k]

    seen = []
    for frame in vicurve.track(lazily(), vicurve.Circle(45, 47, 23), progress=False):
        # The generator is never ahead of the frame being yielded.
        assert len(produced) == frame.index + 1
        seen.append(frame)
    assert [f.ok for f in seen] == [k != 5 for k in range(12)]
    assert seen[5].outcome == "failed" and "missing.png" in seen[5].reason
    assert seen[5].result is None
    # The frame after the failed one starts from the last good one.
    assert seen[6].started_from == "frame_0004"


def test_a_multi_page_tiff_is_tracked_page_by_page(sequence, tmp_path, cli):
    frames, d = sequence
    stack = tmp_path / "disc.tif"
    write_tiff_stack(stack, frames[:10])
    from_stack = list(vicurve.track(str(stack), "circle:45,47,23", progress=False))
    from_array = list(vicurve.track(frames[:10], "circle:45,47,23", progress=False))
    assert [f.name for f in from_stack] == [f"disc_{k:04}" for k in range(10)]
    assert from_stack[3].input == f"{stack}#3"
    for a, b in zip(from_stack, from_array):
        np.testing.assert_array_equal(a.result.spline["control_points"],
                                      b.result.spline["control_points"])
    # And as the command-line tool names and measures them.
    cli("track", stack, "--init", "circle:45,47,23", "--out-dir", tmp_path / "out")
    for k, f in enumerate(from_stack):
        record = json.loads((tmp_path / "out" / f"disc_{k:04}.json").read_text())
        np.testing.assert_array_equal(f.result.spline["control_points"],
                                      np.array(record["curve"]["control_points"]))


def write_tiff_stack(path, frames):
    """A multi-page 16-bit little-endian TIFF, one strip per page, as ImageJ
    writes stacks (an independent writer)."""
    n, h, w = frames.shape
    out = bytearray(b"II*\x00" + struct.pack("<I", 0))
    previous_next = 4
    for k in range(n):
        data_offset = len(out)
        out += frames[k].astype("<u2").tobytes()
        if len(out) % 2:
            out += b"\x00"
        ifd = len(out)
        struct.pack_into("<I", out, previous_next, ifd)
        tags = [(256, 4, 1, w), (257, 4, 1, h), (258, 3, 1, 16), (259, 3, 1, 1),
                (262, 3, 1, 1), (273, 4, 1, data_offset), (277, 3, 1, 1),
                (278, 4, 1, h), (279, 4, 1, w * h * 2)]
        out += struct.pack("<H", len(tags))
        for tag, kind, count, value in tags:
            if kind == 3:
                out += struct.pack("<HHIHH", tag, kind, count, value, 0)
            else:
                out += struct.pack("<HHII", tag, kind, count, value)
        previous_next = len(out)
        out += struct.pack("<I", 0)
    path.write_bytes(bytes(out))
