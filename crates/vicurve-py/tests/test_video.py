"""vicurve.track on a video: decoded by PyAV (or FFmpeg's programs), the
frames of a lossless 16-bit video (FFV1) track to the curves of the same
frames as an array, and to the command-line tool's on the same video."""

import json
import shutil

import numpy as np
import pytest

import vicurve
import vicurve._video
from test_track import disc_frames

FRAMES = 8
INIT = "circle:45,47,23"


def write_video(path, frames):
    """A lossless 16-bit gray video (FFV1 in Matroska), written by PyAV."""
    av = pytest.importorskip("av")
    with av.open(str(path), "w") as container:
        stream = container.add_stream("ffv1", rate=25)
        stream.width, stream.height = frames.shape[2], frames.shape[1]
        stream.pix_fmt = "gray16le"
        for f in frames:
            frame = av.VideoFrame.from_ndarray(f, format="gray16le")
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)


@pytest.fixture(scope="module")
def video(tmp_path_factory):
    frames = disc_frames(FRAMES)
    path = tmp_path_factory.mktemp("video") / "disc.mkv"
    write_video(path, frames)
    return frames, path


def curves(tracker):
    out = []
    for f in tracker:
        assert f.ok, (f.name, f.reason)
        out.append((f.name, f.input, f.result.spline["control_points"]))
    return out


def test_a_lossless_video_tracks_as_its_frames(video):
    frames, path = video
    from_video = vicurve.track(str(path), INIT, progress=False)
    assert len(from_video) == FRAMES
    got = curves(from_video)
    expected = curves(vicurve.track(frames, INIT, progress=False))
    assert [g[0] for g in got] == [f"disc_{k:04}" for k in range(FRAMES)]
    assert got[3][1] == f"{path}#3"
    worst = max(float(np.abs(a[2] - b[2]).max()) for a, b in zip(got, expected))
    assert worst <= 1e-12, worst


def ffmpeg_present():
    return shutil.which("ffmpeg") is not None and shutil.which("ffprobe") is not None


@pytest.mark.skipif(not ffmpeg_present(), reason="FFmpeg's programs are not on PATH")
def test_pyav_ffmpeg_and_the_command_line_read_the_same_frames(video, cli, tmp_path,
                                                               monkeypatch):
    frames, path = video
    with_pyav = curves(vicurve.track(str(path), INIT, progress=False))
    cli("track", path, "--init", INIT, "--out-dir", tmp_path / "cli")
    # Without PyAV, through the library's FFmpeg reader (the CLI's).
    monkeypatch.setattr(vicurve._video, "open_video", lambda p: None)
    with_ffmpeg = curves(vicurve.track(str(path), INIT, progress=False))
    for k, (a, b) in enumerate(zip(with_pyav, with_ffmpeg)):
        record = json.loads((tmp_path / "cli" / f"disc_{k:04}.json").read_text())
        np.testing.assert_array_equal(a[2], b[2])
        np.testing.assert_array_equal(a[2], np.array(record["curve"]["control_points"]))


def test_without_a_decoder_the_error_names_what_to_install(video, monkeypatch):
    frames, path = video
    monkeypatch.setattr(vicurve._video, "open_video", lambda p: None)
    monkeypatch.setenv("PATH", "")
    with pytest.raises(ImportError, match=r"pip install av"):
        vicurve.track(str(path), INIT, progress=False)
