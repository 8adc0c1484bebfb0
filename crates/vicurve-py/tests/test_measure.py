"""vicurve.measure on synthesized images: accuracy, result fields, inputs."""

import json
import math
import threading
import time

import numpy as np
import pytest

import vicurve

CENTRE = (255.8, 255.3)


@pytest.fixture(scope="module")
def disc150():
    """Exact-coverage disc of radius 150, 8-bit, noiseless (vicurve synth defaults)."""
    image, truth = vicurve.synth("disc", size=(512, 512), radius=150)
    return image, truth


@pytest.fixture(scope="module")
def disc150_result(disc150):
    image, _ = disc150
    return vicurve.measure(image, vicurve.Circle(256, 256, 140))


def test_disc_default_settings_accuracy(disc150, disc150_result):
    _, truth = disc150
    r = disc150_result
    assert r.outcome == "converged" and r.divergence is None
    stats = vicurve.eval(r.points, truth)
    assert stats["points"] == len(r.points)
    assert abs(stats["bias"]) <= 2e-3
    assert stats["scatter"] <= 1e-3
    assert stats["max_abs"] <= 5e-3
    assert math.isclose(r.length, 2 * math.pi * 150, rel_tol=1e-5)
    assert math.isclose(r.area, math.pi * 150**2, rel_tol=1e-5)
    # The predicted noise uncertainty is of the order of the scatter.
    assert 0 < np.nanmean(r.sigma) < 5e-3


def test_result_arrays_are_consistent(disc150_result):
    r = disc150_result
    n = len(r.points)
    assert r.points.shape == (n, 2) and r.points.dtype == np.float64
    assert r.normals.shape == (n, 2)
    assert r.s.shape == (n,) and r.sigma.shape == (n,)
    np.testing.assert_allclose(np.hypot(*r.normals.T), 1.0, atol=1e-12)
    # Closed curves: counterclockwise on screen, normals outward.
    outward = (r.points - np.array(CENTRE)) * r.normals
    assert np.all(outward.sum(axis=1) > 0)
    assert np.all(np.diff(r.s) > 0) and np.max(np.diff(r.s)) <= 1.0 + 1e-9
    assert np.all(np.isfinite(r.sigma))
    # sigma is the noise's, inflated where the model misfits.
    assert r.sigma_noise.shape == (n,) and r.misfit.shape == (n,)
    assert r.misfit.dtype == np.bool_
    assert np.all(r.sigma >= r.sigma_noise)
    # x = column, y = row: the disc is centred where synth put it.
    np.testing.assert_allclose(circle_centre(r.points), CENTRE, atol=1e-3)


def circle_centre(points):
    """Least-squares (Kasa) centre of points on a circle."""
    x, y = points.T
    a = np.c_[x, y, np.ones_like(x)]
    sol, *_ = np.linalg.lstsq(a, x * x + y * y, rcond=None)
    return sol[:2] / 2


def test_spline_passes_through_the_samples(disc150_result):
    interpolate = pytest.importorskip("scipy.interpolate")
    r = disc150_result
    sp = r.spline
    assert sp["degree"] == 3 and sp["closed"] is True
    k = sp["degree"]
    knots, ctrl = sp["knots"], sp["control_points"]
    assert len(knots) == len(ctrl) + k + 1
    curve = interpolate.BSpline(knots, ctrl, k)
    u = np.linspace(knots[k], knots[-k - 1], 20001)
    dense = curve(u)  # a closed polyline, vertices 0.05 px apart
    nearest = np.argmin(
        np.hypot(*(r.points[:, None, :] - dense[None, :-1, :]).transpose(2, 0, 1)), axis=1
    )
    best = np.full(len(r.points), np.inf)
    for first in (nearest - 1, nearest):  # the two segments at the nearest vertex
        a, b = dense[first % 20000], dense[first % 20000 + 1]
        t = np.clip(np.sum((r.points - a) * (b - a), axis=1) / np.sum((b - a) ** 2, axis=1), 0, 1)
        foot = a + t[:, None] * (b - a)
        best = np.minimum(best, np.hypot(*(r.points - foot).T))
    # Chords 0.05 px long on a radius of 150 px stray 2e-6 px from the arc.
    assert np.max(best) <= sp["fit_error"] + 1e-5
    # The curve closes: its end is its start.
    np.testing.assert_allclose(dense[-1], dense[0], atol=1e-9)


def test_history_has_the_result_file_fields(disc150_result):
    r = disc150_result
    record = json.loads(r.to_json())
    assert len(r.history) == len(record["stages"]) >= 2
    for mine, filed in zip(r.history, record["stages"]):
        assert set(mine) == set(filed)
        assert mine["outcome"]["status"] == "converged"
        assert mine["iterations"] >= 1
    assert r.iterations == sum(s["iterations"] for s in r.history)
    assert record["outcome"] == {"status": "converged"}
    assert record["curve"]["control_points"] == r.spline["control_points"].tolist()
    assert record["input"]["width"] == 512 and record["input"]["height"] == 512
    assert r.polarity == "bright inside" == record["polarity"]
    assert r.config == record["config"]
    assert r.edge_spread is not None and r.edge_spread["sigma"] < 0.5
    assert r.blur_corrected is True


def test_dtypes_are_scaled_like_image_files(disc150):
    image8, _ = disc150
    init = vicurve.Circle(256, 256, 146)
    stages = [(10, 20)]
    a = vicurve.measure(image8, init, stages=stages, blur_correction=False)
    b = vicurve.measure(image8 / 255.0, init, stages=stages, blur_correction=False)
    c = vicurve.measure((image8 / 255.0).astype(np.float32), init, stages=stages,
                        blur_correction=False)
    np.testing.assert_array_equal(a.points, b.points)
    # float32 rounds the levels: nearly, not exactly, the same curve.
    np.testing.assert_allclose(a.points, c.points, atol=1e-5)
    image16, truth16 = vicurve.synth("disc", size=(512, 512), radius=150, bits=16)
    assert image16.dtype == np.uint16
    d = vicurve.measure(image16, init, stages=stages, blur_correction=False)
    e = vicurve.measure(image16 / 65535.0, init, stages=stages, blur_correction=False)
    np.testing.assert_array_equal(d.points, e.points)
    # Non-contiguous and big-endian arrays are read as what they show.
    f = vicurve.measure(np.asfortranarray(image8), init, stages=stages, blur_correction=False)
    np.testing.assert_array_equal(a.points, f.points)
    g = vicurve.measure((image8 / 255.0).astype(">f8"), init, stages=stages,
                        blur_correction=False)
    np.testing.assert_array_equal(a.points, g.points)
    # A transposed image holds the transposed disc.
    t = vicurve.measure(image8.T, init, stages=stages,
                        blur_correction=False)
    np.testing.assert_allclose(circle_centre(t.points), CENTRE[::-1], atol=1e-3)


def test_open_edge_from_a_segment():
    image, truth = vicurve.synth("sine-edge", size=(400, 300), blur=1.0, amplitude=12,
                                 wavelength=150)
    r = vicurve.measure(image, vicurve.Segment(30, 150, 370, 150))
    assert r.outcome == "converged"
    assert r.area is None and r.spline["closed"] is False
    # Open curves keep the segment's direction (+x).
    assert r.points[0, 0] < r.points[-1, 0]
    stats = vicurve.eval(r.points, truth)
    assert abs(stats["bias"]) < 3e-3 and stats["scatter"] < 1e-2


def test_contour_ring_with_explicit_options():
    image, truth = vicurve.synth("ring", size=(300, 300), radius=90, blur=1.0)
    r = vicurve.measure(image, vicurve.Circle(150, 150, 85), kind="contour",
                        polarity="bright-line", interpolation="bilinear", degree=2)
    assert r.outcome == "converged"
    assert r.polarity == "bright line on a dark ground"
    assert r.config["interpolation"] == "bilinear" and r.config["degree"] == 2
    stats = vicurve.eval(r.points, truth)
    assert abs(stats["bias"]) < 2e-3 and stats["scatter"] < 5e-3


def test_stages_in_every_accepted_form(disc150):
    image, _ = disc150
    init = vicurve.Circle(256, 256, 145)
    a = vicurve.measure(image, init, stages=[(10, 25), (5, "40px")], blur_correction=False)
    b = vicurve.measure(image, init, stages="10:25,5:40px", blur_correction=False)
    np.testing.assert_array_equal(a.points, b.points)
    assert [s["half_width"] for s in a.history] == [10.0, 5.0]
    assert a.history[0]["elements"] == 25
    c = vicurve.measure(image, init, stages=[(4, "auto")], blur_correction=False)
    assert c.outcome == "converged" and c.config["stages"][0]["elements"] == {
        "auto": {"longest": 40.0, "shortest": 5.0}
    }


def test_polyline_and_text_starts(disc150):
    image, truth = disc150
    th = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    pts = np.c_[256 + 142 * np.cos(th), 256 - 142 * np.sin(th)]
    r = vicurve.measure(image, vicurve.Polyline(pts, closed=True))
    assert r.outcome == "converged"
    assert abs(vicurve.eval(r.points, truth)["bias"]) <= 2e-3
    init = r.initial_curve
    assert isinstance(init, vicurve.Polyline) and init.closed
    np.testing.assert_array_equal(init.points, pts)
    s = vicurve.measure(image, "circle:256,256,146", stages=[(10, 20)])
    assert s.initial_curve == vicurve.Circle(256, 256, 146)


def test_automatic_start(disc150):
    image, truth = disc150
    r = vicurve.measure(image)  # init=None: automatic start
    assert r.outcome == "converged"
    assert abs(vicurve.eval(r.points, truth)["bias"]) <= 2e-3
    start = r.auto_start
    assert start["closed"] is True and start["bright"] is True
    assert isinstance(r.initial_curve, vicurve.Polyline)
    picked = vicurve.measure(image, vicurve.Auto(pick=CENTRE))
    np.testing.assert_allclose(picked.points, r.points, atol=1e-9)


def test_path_input_and_its_name(tmp_path, cli):
    png = tmp_path / "disc.png"
    cli("synth", "disc", "--size", "300x300", "--radius", "100", "--out", png)
    r = vicurve.measure(png, vicurve.Circle(150, 150, 95), stages=[(5, 20)])
    assert json.loads(r.to_json())["input"] == {"path": str(png), "width": 300, "height": 300}
    a = vicurve.measure(str(png), vicurve.Circle(150, 150, 95), stages=[(5, 20)])
    np.testing.assert_array_equal(a.points, r.points)


def test_the_fit_releases_the_gil():
    image, _ = vicurve.synth("star", size=(1024, 1024), radius=300, amplitude=0.2,
                             blur=1.0, noise=0.01)
    span = {}

    def work():
        # Fits until a quarter second has passed, however fast one is
        # (one took 90 to 130 ms on the CI machine): the ticks below need
        # a span to fall in.
        span["start"] = time.perf_counter()
        while time.perf_counter() - span["start"] < 0.25:
            vicurve.measure(image, vicurve.Circle(512, 512, 300))
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    inside = [t for t in ticks if span["start"] + 0.02 < t < span["end"] - 0.02]
    duration = span["end"] - span["start"]
    assert duration > 0.1
    # With the GIL held by the fit, this thread could not tick at all.
    assert len(inside) >= 10, (len(inside), duration)


def test_iteration_limit_warns(disc150):
    image, _ = disc150
    with pytest.warns(RuntimeWarning, match="iteration limit"):
        r = vicurve.measure(image, vicurve.Circle(256, 256, 140), stages=[(10, 20)],
                            max_iterations=1)
    assert r.outcome == "iteration_limit"
    assert r.history[-1]["outcome"] == {"status": "iteration_limit"}


def test_grow_from_a_segment(disc150):
    """A 30 px segment on the disc's edge grows all round; same accuracy."""
    image, truth = disc150
    # The disc's centre is (255.8, 255.3): its right edge is at x = 405.8.
    r = vicurve.measure(image, vicurve.Segment(404, 270, 404, 240), grow=True)
    assert r.outcome == "converged"
    assert r.grow["ends"] == ["closed", "closed"]
    assert json.loads(r.to_json())["grow"]["ends"] == ["closed", "closed"]
    stats = vicurve.eval(r.points, truth)
    assert abs(stats["bias"]) <= 2e-3 and stats["max_abs"] <= 1e-2
    # A length: an open piece of about that length.
    r = vicurve.measure(image, vicurve.Segment(404, 270, 404, 240), grow=200)
    assert r.grow["ends"] == ["length", "length"]
    assert abs(r.length - 200) < 3
    assert vicurve.measure(image, vicurve.Circle(256, 256, 140)).grow is None


def test_contour_from_a_picked_point():
    """A thin ring: the line through the picked point is followed all round."""
    image, truth = vicurve.synth("ring", size=(300, 300), radius=100, blur=1.0)
    # Centre (150.3, 149.8): the ring's rightmost point is (250.3, 149.8).
    r = vicurve.measure(image, vicurve.Auto(pick=(251, 151)), kind="contour",
                        levels="global")
    assert r.outcome == "converged"
    assert r.config["levels"] == {"type": "global"}
    assert vicurve.eval(r.points, truth)["max_abs"] <= 3e-2


def test_an_encoded_image_is_measured_in_linear_light():
    """An sRGB-encoded disc: found by tone="auto", undone exactly as told."""
    image, truth = vicurve.synth("disc", size=(200, 200), radius=60, blur=1.0, noise=0.01,
                                 tone="srgb")
    start = vicurve.Circle(100, 99, 60)
    auto = vicurve.measure(image, start)
    assert auto.tone != "linear"
    assert auto.tone_estimate["evidence"] > 25
    assert abs(vicurve.eval(auto.points, truth)["bias"]) < 0.05
    # The reading's uncertainty shifts the whole curve: reported once,
    # not in the samples' sigma.
    assert auto.sigma_shift == auto.tone_estimate["position_sd"] > 0
    assert auto.sigma_shift > 2 * float(auto.sigma.max())
    told = vicurve.measure(image, start, tone="srgb")
    assert told.tone == "srgb" and told.tone_estimate is None
    assert told.sigma_shift == 0
    assert abs(vicurve.eval(told.points, truth)["bias"]) < 5e-3
    linear = vicurve.measure(image, start, tone="linear")
    assert vicurve.eval(linear.points, truth)["bias"] > 0.1


def test_an_astigmatic_blur_is_fitted():
    """A disc blurred 1 px along x and 2.5 px along y (synth blur_y=): the
    last stage's pixel edge carries the blur's anisotropy, p = (1 - 6.25) / 2
    px² (q = 0), and the curve is within 3e-3 px of the truth on average
    (+5.7e-3 before the blur's normal-tangent covariance entered the
    curvature's skew)."""
    image, truth = vicurve.synth("disc", size=(240, 240), radius=80, blur=1.0, blur_y=2.5,
                                 noise=0.01)
    assert truth["image"]["blur_sigma_y"] == 2.5
    r = vicurve.measure(image, vicurve.Circle(120, 119, 80))
    profile = r.history[-1]["profile"]
    assert profile["type"] == "pixel_edge"
    assert abs(profile["anisotropy"]["p"] + 2.625) < 0.5
    assert abs(profile["anisotropy"]["q"]) < 0.3
    assert abs(vicurve.eval(r.points, truth)["bias"]) < 3e-3
