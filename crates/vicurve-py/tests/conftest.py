"""Shared fixtures of the vicurve Python tests.

The tests run against the installed package (``pip install
./crates/vicurve-py``). Comparisons with the command-line tool need its
binary: ``VICURVE_CLI`` names it, otherwise ``target/release/vicurve`` or
``target/debug/vicurve`` of the repository (or of ``CARGO_TARGET_DIR``) is
used. ``.ci/run`` sets ``VICURVE_CLI``; when it is set and missing the
tests fail rather than skip.
"""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]


def _cli_candidates():
    dirs = []
    if os.environ.get("CARGO_TARGET_DIR"):
        dirs.append(pathlib.Path(os.environ["CARGO_TARGET_DIR"]))
    dirs.append(REPO / "target")
    for d in dirs:
        for profile in ("release", "debug"):
            yield d / profile / "vicurve"


@pytest.fixture(scope="session")
def cli():
    """A function running the ``vicurve`` binary; returns the CompletedProcess."""
    named = os.environ.get("VICURVE_CLI")
    if named:
        path = pathlib.Path(named)
        assert path.is_file(), f"VICURVE_CLI={named} does not exist"
    else:
        found = [p for p in _cli_candidates() if p.is_file()]
        if not found:
            pytest.skip("no vicurve binary (build it with cargo build, or set VICURVE_CLI)")
        path = found[0]

    def run(*args, cwd=None, check=True):
        out = subprocess.run(
            [str(path), *map(str, args)], capture_output=True, text=True, cwd=cwd
        )
        if check and out.returncode != 0:
            raise AssertionError(
                f"vicurve {' '.join(map(str, args))} exited {out.returncode}: {out.stderr}"
            )
        return out

    return run


def without_timings(document):
    """A result file (text or dict) without the stages' wall-clock seconds."""
    d = json.loads(document) if isinstance(document, str) else document
    for stage in d.get("stages", []):
        stage.pop("seconds", None)
    return d


def read_pixels(path, height, width):
    """The gray levels of an image file as vicurve reads them (bilinear
    interpolation at the pixel centres returns the pixels exactly)."""
    import vicurve

    ii, jj = np.mgrid[0:height, 0:width]
    return vicurve.interpolate(
        str(path), jj.astype(float), ii.astype(float), kind="bilinear"
    )
