"""Videos for ``vicurve.track``, decoded by PyAV (``pip install av``) when it
is installed; ``vicurve.track`` falls back on FFmpeg's ``ffmpeg`` and
``ffprobe`` programs on PATH, as the command-line tool reads videos.

Frames are the first video stream's, as 16-bit luma (``gray16le``, what the
command-line tool asks FFmpeg for), so that both front ends read the same
gray levels.
"""


def open_video(path):
    """``(count, frames)`` of the video at ``path`` with PyAV: the number of
    frames (its packets counted, without decoding) and an iterator of the
    frames as 2-D ``uint16`` arrays, decoded one at a time; None when PyAV
    is not installed."""
    try:
        import av
    except ImportError:
        return None
    with av.open(str(path)) as container:
        count = sum(1 for p in container.demux(video=0) if p.size)

    def frames():
        with av.open(str(path)) as container:
            for frame in container.decode(video=0):
                yield frame.to_ndarray(format="gray16le")

    return count, frames()
