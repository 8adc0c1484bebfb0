"""vicurve.run against the command-line tool's ``vicurve run`` on the same
job file: the necking specimen of ``vicurve synth necking`` (two edges and
the width between them, tracked)."""

import csv
import shutil

import numpy as np
import pytest

import vicurve
from conftest import without_timings


@pytest.fixture(scope="module")
def necking(tmp_path_factory, cli):
    d = tmp_path_factory.mktemp("run") / "neck"
    cli("synth", "necking", "--out", d, "--frames", "4", "--size", "300x120")
    return d


def test_run_gives_the_command_lines_files_and_summary(necking, cli, tmp_path):
    shutil.copytree(necking, tmp_path / "cli")
    shutil.copytree(necking, tmp_path / "py")
    cli("run", tmp_path / "cli" / "job.toml")
    table = vicurve.run(tmp_path / "py" / "job.toml", progress=False, pandas=False)
    cli_dir, py_dir = tmp_path / "cli" / "results", tmp_path / "py" / "results"
    assert (py_dir / "summary.csv").read_bytes() == (cli_dir / "summary.csv").read_bytes()
    for k in range(4):
        stem = f"frame_{k:03}"
        for name in ("top", "bottom"):
            mine = without_timings((py_dir / f"{stem}.{name}.json").read_text())
            theirs = without_timings((cli_dir / f"{stem}.{name}.json").read_text())
            # The input is recorded as the job names it (another folder).
            mine["input"].pop("path"), theirs["input"].pop("path")
            assert mine == theirs, (stem, name)
        assert (py_dir / f"{stem}.width.csv").read_bytes() == \
            (cli_dir / f"{stem}.width.csv").read_bytes()
    # The table is the summary's.
    with open(cli_dir / "summary.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(table) == list(rows[0])
    assert len(table["frame"]) == len(rows) == 4 * 3
    assert list(table["curve"]) == [r["curve"] for r in rows]
    assert list(table["outcome"]) == [r["outcome"] for r in rows]
    for column in ("length", "min_width", "residual"):
        expected = [float(r[column]) if r[column] else np.nan for r in rows]
        np.testing.assert_array_equal(table[column], expected)
    assert table["iterations"].dtype.kind == "i" and table["width_samples"][2] > 250


def test_run_resumes_and_shards_as_the_command_line(necking, tmp_path):
    shutil.copytree(necking, tmp_path / "job")
    job = tmp_path / "job" / "job.toml"
    first = vicurve.run(job, progress=False, pandas=False)
    # Done frames are skipped: the files stay as they are.
    summary = (tmp_path / "job" / "results" / "summary.csv").read_bytes()
    mtime = (tmp_path / "job" / "results" / "frame_000.top.json").stat().st_mtime_ns
    again = vicurve.run(job, progress=False, pandas=False)
    assert (tmp_path / "job" / "results" / "frame_000.top.json").stat().st_mtime_ns == mtime
    assert (tmp_path / "job" / "results" / "summary.csv").read_bytes() == summary
    np.testing.assert_array_equal(first["min_width"], again["min_width"])
    with pytest.raises(ValueError, match="cannot be split"):
        vicurve.run(job, shard="1/2")


def test_run_returns_a_dataframe_with_pandas(necking, tmp_path):
    pd = pytest.importorskip("pandas")
    shutil.copytree(necking, tmp_path / "job")
    table = vicurve.run(tmp_path / "job" / "job.toml", progress=False)
    assert isinstance(table, pd.DataFrame) and len(table) == 12


def test_job_files_that_cannot_run(tmp_path):
    with pytest.raises(FileNotFoundError, match="job file not found"):
        vicurve.run(tmp_path / "nothing.toml")
    (tmp_path / "bad.toml").write_text('images = "x/*.png"\nout_dir = "o"\nspeling = 1\n')
    with pytest.raises(ValueError, match="speling"):
        vicurve.run(tmp_path / "bad.toml")
    (tmp_path / "a.png").write_bytes(b"")
    (tmp_path / "overlay.toml").write_text(
        'images = ["a.png"]\nout_dir = "o"\n[[curve]]\ninit = "circle:5,5,3"\n'
        '[outputs]\noverlay = "png"\n')
    with pytest.raises(ValueError, match="overlays are drawn by the command-line tool"):
        vicurve.run(tmp_path / "overlay.toml")
