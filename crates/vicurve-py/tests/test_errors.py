"""Every error path raises a Python exception with the engine's message."""

import numpy as np
import pytest

import vicurve


@pytest.fixture(scope="module")
def disc():
    image, _ = vicurve.synth("disc", size=(200, 200), radius=60)
    return image


INIT = vicurve.Circle(100, 100, 55)


def test_missing_file(tmp_path):
    missing = tmp_path / "nowhere.png"
    with pytest.raises(FileNotFoundError, match="file not found: .*nowhere.png"):
        vicurve.measure(missing, INIT)
    with pytest.raises(FileNotFoundError):
        vicurve.interpolate(str(missing), [1.0], [1.0])
    with pytest.raises(FileNotFoundError):
        vicurve.eval([[0.0, 0.0]], tmp_path / "truth.json")


def test_a_file_that_is_not_an_image(tmp_path):
    text = tmp_path / "notes.png"
    text.write_text("not an image")
    with pytest.raises(ValueError, match="unsupported image"):
        vicurve.measure(text, INIT)


def test_arrays_that_are_not_gray_images(disc):
    rgb = np.dstack([disc, disc, disc])
    with pytest.raises(ValueError, match="2-D array.*3-D"):
        vicurve.measure(rgb, INIT)
    with pytest.raises(ValueError, match="2-D array.*1-D"):
        vicurve.measure(disc.ravel(), INIT)
    for dtype in (np.int32, np.int16, np.bool_, np.complex128, np.float16):
        with pytest.raises(ValueError, match="unsupported dtype"):
            vicurve.measure(disc.astype(dtype), INIT)
    with pytest.raises(ValueError, match="empty"):
        vicurve.measure(np.zeros((0, 10)), INIT)
    with pytest.raises(ValueError, match="0-D"):
        vicurve.measure(3.5, INIT)
    with pytest.raises(ValueError, match="0-D"):
        vicurve.measure(object(), INIT)
    with pytest.raises(ValueError, match="unsupported dtype object"):
        vicurve.measure(np.array([[object(), object()]]), INIT)


def test_non_finite_pixels(disc):
    bad = disc / 255.0
    bad[17, 42] = np.nan
    with pytest.raises(ValueError, match=r"non-finite.*x=42, y=17"):
        vicurve.measure(bad, INIT)
    bad[17, 42] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        vicurve.interpolate(bad, [1.0], [1.0])


def test_curves_outside_the_image_or_invalid(disc):
    with pytest.raises(ValueError, match="leaves the image"):
        vicurve.measure(disc, vicurve.Circle(100, 100, 150))
    # A closed curve's band may be cut by the border; an open curve along
    # it has no stretch whose band fits.
    with pytest.raises(ValueError, match="band of half-width 5"):
        vicurve.measure(disc, vicurve.Segment(0.5, 10, 0.5, 190), stages=[(5, 10)])
    with pytest.raises(ValueError, match="radius"):
        vicurve.measure(disc, vicurve.Circle(100, 100, 1))
    with pytest.raises(ValueError, match="non-finite"):
        vicurve.measure(disc, vicurve.Segment(0, np.nan, 10, 10))
    with pytest.raises(ValueError, match="at least 3"):
        vicurve.measure(disc, vicurve.Polyline([[1, 1], [5, 5]], closed=True))
    with pytest.raises(ValueError, match=r"N x 2"):
        vicurve.Polyline(np.zeros((5, 3)))
    with pytest.raises(ValueError, match="cannot parse initial curve"):
        vicurve.measure(disc, "circle:1,2")
    with pytest.raises(TypeError, match="init: expected"):
        vicurve.measure(disc, (100, 100, 55))


def test_automatic_start_errors(disc):
    # A line's automatic start follows the line through a picked point.
    with pytest.raises(ValueError, match="pick"):
        vicurve.measure(disc, None, kind="contour")
    with pytest.raises(ValueError, match="grow"):
        vicurve.measure(disc, vicurve.Circle(100, 100, 55), grow=True)
    with pytest.raises(ValueError, match="grow"):
        vicurve.measure(disc, vicurve.Segment(150, 90, 150, 110), grow="far")
    with pytest.raises(ValueError, match="levels"):
        vicurve.measure(disc, vicurve.Circle(100, 100, 55), levels="uneven")
    with pytest.raises(ValueError, match="tone"):
        vicurve.measure(disc, vicurve.Circle(100, 100, 55), tone="warm")
    with pytest.raises(ValueError, match="no contrast"):
        vicurve.measure(np.full((100, 100), 0.5), None)
    with pytest.raises(ValueError, match="outside"):
        vicurve.measure(disc, vicurve.Auto(pick=(500, 500)))


@pytest.mark.parametrize(
    "stages,message",
    [
        ([(10,)], "stage 0"),
        ([(10, 5, 3)], "stage 0"),
        ([], "empty list"),
        ([(10, 0)], "0 elements"),
        ([(10, -3)], "-3 elements"),
        ([(0.1, 10)], "half-width 0.1"),
        ([(10, 20), ("a", 5)], "stage 1"),
        ([(10, 2.5)], "stage 0"),
        ([(10, True)], "stage 0"),
        ([(10, "lots")], "stage 0"),
        ("10:x", "cannot parse stages"),
        ("", "cannot parse stages"),
        (42, "list of"),
        (["10:25"], "stage 0"),
    ],
)
def test_malformed_stages(disc, stages, message):
    with pytest.raises(ValueError, match=message):
        vicurve.measure(disc, INIT, stages=stages)


@pytest.mark.parametrize(
    "kwargs,message",
    [
        (dict(kind="edge"), "invalid kind"),
        (dict(polarity="bright"), "invalid polarity"),
        (dict(interpolation="nearest"), "invalid interpolation"),
        (dict(degree=0), "invalid degree"),
        (dict(degree=6), "invalid degree"),
        (dict(degree=-1), "invalid degree"),
        (dict(tolerance=0.0), "invalid tolerance"),
        (dict(tolerance=float("nan")), "invalid tolerance"),
        (dict(max_iterations=0), "max iterations"),
        (dict(max_iterations=-5), "max_iterations"),
    ],
)
def test_bad_parameters(disc, kwargs, message):
    with pytest.raises(ValueError, match=message):
        vicurve.measure(disc, INIT, **kwargs)


def test_a_diverging_fit_raises_fit_error_with_the_partial_result():
    flat = np.full((120, 120), 0.5)
    with pytest.raises(vicurve.FitError, match="diverged: the band sees no contrast") as caught:
        vicurve.measure(flat, vicurve.Circle(60, 60, 30), stages=[(5, 10)])
    assert isinstance(caught.value, RuntimeError)
    result = caught.value.result
    assert isinstance(result, vicurve.Result)
    assert result.outcome == "diverged" and result.divergence == "no_contrast"
    assert result.message.startswith("diverged:")
    assert result.history[-1]["outcome"]["status"] == "diverged"
    assert len(result.points) > 0


def test_synth_errors():
    with pytest.raises(ValueError, match="invalid shape"):
        vicurve.synth("square")
    with pytest.raises(ValueError, match="bits"):
        vicurve.synth("disc", bits=12)
    with pytest.raises(ValueError, match="size"):
        vicurve.synth("disc", size=(0, 10))
    with pytest.raises(ValueError, match="amplitude"):
        vicurve.synth("star", amplitude=1.5)
    with pytest.raises(ValueError, match="line_width"):
        vicurve.synth("ring", radius=5, line=20)
    with pytest.raises(ValueError, match="noise"):
        vicurve.synth("disc", noise=-1)


def test_eval_errors():
    _, truth = vicurve.synth("disc", size=(64, 64), radius=20)
    with pytest.raises(ValueError, match="N x 2"):
        vicurve.eval(np.zeros((4, 3)), truth)
    with pytest.raises(ValueError, match="no point"):
        vicurve.eval(np.zeros((0, 2)), truth)
    with pytest.raises(ValueError, match="non-finite"):
        vicurve.eval([[1.0, np.nan]], truth)
    with pytest.raises(ValueError, match="cannot parse truth"):
        vicurve.eval([[1.0, 2.0]], {"shape": {"shape": "hexagon"}, "kind": "silhouette"})
    with pytest.raises(ValueError, match="invalid r"):
        vicurve.eval([[1.0, 2.0]], {"shape": "circle", "cx": 0, "cy": 0, "r": -1})
    with pytest.raises(TypeError, match="truth: expected"):
        vicurve.eval([[1.0, 2.0]], 42)
    # A bare shape is accepted as well as the truth file's content.
    stats = vicurve.eval([[10.0, 0.0]], {"shape": "circle", "cx": 0, "cy": 0, "r": 8})
    assert stats["bias"] == pytest.approx(2.0)


def test_basis_and_interpolation_errors():
    with pytest.raises(ValueError, match="degree"):
        vicurve.basis_values(6, 10, 100.0, False, [1.0])
    with pytest.raises(ValueError, match="elements"):
        vicurve.basis_values(3, 3, 100.0, True, [1.0])
    with pytest.raises(ValueError, match="curve length"):
        vicurve.basis_values(3, 10, -1.0, False, [1.0])
    with pytest.raises(ValueError, match="derivative"):
        vicurve.basis_values(3, 10, 10.0, False, [1.0], derivative=3)
    with pytest.raises(ValueError, match="same shape"):
        vicurve.interpolate(np.zeros((5, 5)), [1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="invalid interpolation"):
        vicurve.interpolate(np.zeros((5, 5)), [1.0], [1.0], kind="quintic")
