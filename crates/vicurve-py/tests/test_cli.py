"""The package and the command-line tool give the same images, truths and
results for the same input."""

import csv
import json

import numpy as np
import pytest

import vicurve
from conftest import read_pixels, without_timings

# (CLI arguments, the same as vicurve.synth keyword arguments)
SYNTH_CASES = [
    (["disc", "--size", "200x150", "--radius", "50", "--blur", "0.8", "--noise", "0.02",
      "--seed", "7"],
     dict(shape="disc", size=(200, 150), radius=50, blur=0.8, noise=0.02, seed=7)),
    (["ellipse", "--size", "240x200", "--axes", "80,40", "--angle", "30", "--bits", "16"],
     dict(shape="ellipse", size=(240, 200), axes=(80, 40), angle=30, bits=16)),
    (["star", "--size", "256x256", "--radius", "80", "--amplitude", "0.15", "--lobes", "4",
      "--phase", "10", "--levels", "0.1,0.9", "--center", "120.25,130.5"],
     dict(shape="star", size=(256, 256), radius=80, amplitude=0.15, lobes=4, phase=10,
          levels=(0.1, 0.9), center=(120.25, 130.5))),
    (["sine-edge", "--size", "300x160", "--amplitude", "9", "--wavelength", "120",
      "--y0", "70.4", "--profile", "4"],
     dict(shape="sine-edge", size=(300, 160), amplitude=9, wavelength=120, y0=70.4,
          profile=4)),
    (["ring", "--size", "200x200", "--radius", "60", "--line", "2.5", "--blur", "1"],
     dict(shape="ring", size=(200, 200), radius=60, line=2.5, blur=1)),
    (["sine-line", "--size", "220x140", "--levels", "0.8,0.3"],
     dict(shape="sine-line", size=(220, 140), levels=(0.8, 0.3))),
    (["disc", "--size", "160x160", "--radius", "50", "--blur", "1", "--tone", "srgb"],
     dict(shape="disc", size=(160, 160), radius=50, blur=1, tone="srgb")),
    (["disc", "--size", "160x160", "--radius", "50", "--blur", "1", "--blur-y", "2.5"],
     dict(shape="disc", size=(160, 160), radius=50, blur=1, blur_y=2.5)),
    (["paper-disc"], dict(shape="paper-disc")),
    (["ellipse", "--size", "200x160", "--blur", "1", "--noise", "0.01", "--shading",
      "0.12,-0.06,0.2"],
     dict(shape="ellipse", size=(200, 160), blur=1, noise=0.01, shading="0.12,-0.06,0.2")),
    (["paper-disc", "--tone", "2.2", "--shading", "0.1,0"],
     dict(shape="paper-disc", tone="2.2", shading="0.1,0")),
]


@pytest.mark.parametrize("cli_args,kwargs", SYNTH_CASES, ids=[c[0][0] for c in SYNTH_CASES])
def test_synth_matches_the_command_line(tmp_path, cli, cli_args, kwargs):
    png, truth_file = tmp_path / "img.png", tmp_path / "truth.json"
    cli("synth", *cli_args, "--out", png, "--truth", truth_file)
    image, truth = vicurve.synth(**kwargs)
    full = 65535.0 if image.dtype == np.uint16 else 255.0
    assert image.dtype == (np.uint16 if full > 255 else np.uint8)
    pixels = read_pixels(png, *image.shape)
    np.testing.assert_array_equal(image / full, pixels)
    assert truth == json.loads(truth_file.read_text())


# (synth arguments, measure CLI arguments, the same as measure keyword arguments)
MEASURE_CASES = [
    ("closed-default",
     ["disc", "--size", "300x300", "--radius", "100", "--blur", "0.8", "--noise", "0.01"],
     ["--init", "circle:150,150,90"],
     dict(init=vicurve.Circle(150, 150, 90))),
    ("open-stages",
     ["sine-edge", "--size", "300x200", "--blur", "1", "--amplitude", "8"],
     ["--init", "segment:30,100,270,100", "--stages", "10:6,5:40px,2:auto", "--degree", "2"],
     dict(init=vicurve.Segment(30, 100, 270, 100), stages=[(10, 6), (5, "40px"), (2, "auto")],
          degree=2)),
    ("contour-bilinear",
     ["ring", "--size", "240x240", "--radius", "80", "--blur", "1", "--levels", "0.9,0.2"],
     ["--init", "circle:120,120,76", "--kind", "contour", "--interp", "bilinear",
      "--polarity", "dark-line", "--tolerance", "1e-5", "--max-iter", "150"],
     dict(init=vicurve.Circle(120, 120, 76), kind="contour", interpolation="bilinear",
          polarity="negative", tolerance=1e-5, max_iterations=150)),
    ("paper-disc",
     ["paper-disc"],
     ["--init", "circle:255,257,203", "--stages", "10:25", "--no-blur-correction"],
     dict(init=vicurve.Circle(255, 257, 203), stages=[(10, 25)], blur_correction=False)),
]


def read_points_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return np.array([[float(r[k]) for k in ("s", "x", "y", "nx", "ny", "sigma")] for r in rows])


@pytest.mark.parametrize("name,synth_args,measure_args,kwargs", MEASURE_CASES,
                         ids=[c[0] for c in MEASURE_CASES])
def test_measure_matches_the_command_line(tmp_path, cli, name, synth_args, measure_args,
                                          kwargs):
    png = tmp_path / "img.png"
    cli("synth", *synth_args, "--out", png)
    out_json, out_csv = tmp_path / "r.json", tmp_path / "p.csv"
    cli("measure", png, *measure_args, "--out", out_json, "--points", out_csv)
    cli_record = json.loads(out_json.read_text())
    assert cli_record["outcome"]["status"] == "converged", name

    from_file = vicurve.measure(str(png), **kwargs)
    # The same document, the stages' timings aside.
    assert without_timings(from_file.to_json()) == without_timings(cli_record)
    ctrl = np.array(cli_record["curve"]["control_points"])
    np.testing.assert_allclose(from_file.spline["control_points"], ctrl, rtol=0, atol=1e-12)
    np.testing.assert_allclose(from_file.spline["knots"], cli_record["curve"]["knots"],
                               rtol=0, atol=1e-12)
    # The CSV holds 6 decimals.
    table = read_points_csv(out_csv)
    assert table.shape[0] == len(from_file.points) == cli_record["samples"]
    np.testing.assert_allclose(from_file.points, table[:, 1:3], rtol=0, atol=6e-7)
    np.testing.assert_allclose(from_file.normals, table[:, 3:5], rtol=0, atol=6e-7)
    np.testing.assert_allclose(from_file.s, table[:, 0], rtol=0, atol=6e-7)

    # The image as an array gives the same curve.
    pixels = read_pixels(png, cli_record["input"]["height"], cli_record["input"]["width"])
    as_uint8 = np.rint(pixels * 255).astype(np.uint8)
    from_array = vicurve.measure(as_uint8, **kwargs)
    np.testing.assert_allclose(from_array.points, from_file.points, rtol=0, atol=1e-12)
    np.testing.assert_allclose(from_array.spline["control_points"], ctrl, rtol=0, atol=1e-12)
    record = without_timings(from_array.to_json())
    assert record["input"]["path"] == "<numpy array, uint8>"
    record["input"]["path"] = cli_record["input"]["path"]
    assert record == without_timings(cli_record)


def test_a_diverged_fit_gives_the_command_lines_record(tmp_path, cli):
    png = tmp_path / "flat.png"
    cli("synth", "disc", "--size", "120x120", "--radius", "20", "--levels", "0.5,0.5",
        "--out", png)
    out_json = tmp_path / "r.json"
    run = cli("measure", png, "--init", "circle:60,60,30", "--stages", "5:10", "--out",
              out_json, check=False)
    assert run.returncode == 3
    with pytest.raises(vicurve.FitError) as caught:
        vicurve.measure(str(png), vicurve.Circle(60, 60, 30), stages=[(5, 10)])
    result = caught.value.result
    assert result.outcome == "diverged"
    assert without_timings(result.to_json()) == without_timings(out_json.read_text())
    # The engine's reason, in both messages.
    reason = result.message.split(": ", 1)[1]
    assert reason in str(caught.value) and reason in run.stderr
