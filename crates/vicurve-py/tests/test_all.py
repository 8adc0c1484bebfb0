"""vicurve.measure_all: every disc of an image, its table."""

import numpy as np
import pytest

import vicurve


def discs(centres, r=14.0, size=(200, 320)):
    """Bright discs (exact to a pixel's resolution by 4x4 supersampling)."""
    h, w = size
    yy, xx = np.mgrid[0:h * 4, 0:w * 4]
    x, y = (xx + 0.5) / 4 - 0.5, (yy + 0.5) / 4 - 0.5
    inside = np.zeros_like(x, dtype=bool)
    for cx, cy in centres:
        inside |= (x - cx) ** 2 + (y - cy) ** 2 < r * r
    cover = inside.reshape(h, 4, w, 4).mean(axis=(1, 3))
    return 0.2 + 0.6 * cover


def test_measure_all_finds_every_disc_and_tabulates_them():
    centres = [(60.3, 50.2), (160.7, 48.9), (250.1, 140.6), (70.4, 150.3)]
    results, table = vicurve.measure_all(discs(centres), model="circle")
    assert len(results) == 4
    cx = np.asarray(table["model_cx"])
    cy = np.asarray(table["model_cy"])
    outcome = list(table["outcome"])
    assert outcome == ["measured"] * 4
    # Row-major numbering: the two top discs first, left to right.
    order = [0, 1, 3, 2]
    for k, (x, y) in zip(order, centres):
        assert abs(cx[k] - x) < 0.02 and abs(cy[k] - y) < 0.02
    assert all(r is not None and r.area > 0 for r in results)


def test_a_touching_pair_is_reported_failed():
    centres = [(60.3, 50.2), (88.8, 50.2), (250.1, 140.6)]
    results, table = vicurve.measure_all(discs(centres), model="circle")
    outcome = list(table["outcome"])
    assert outcome.count("measured") == 1
    # Merged: the circle does not fit, or its fit runs away; apart: too close.
    assert all(o in ("model_misfit", "model", "too_close") for o in outcome if o != "measured")
    assert len(list(table["message"])) == len(outcome)


def test_the_table_is_a_dataframe_with_pandas():
    pd = pytest.importorskip("pandas")
    _, table = vicurve.measure_all(discs([(60.3, 50.2)]))
    assert isinstance(table, pd.DataFrame)
    assert list(table["outcome"]) == ["measured"]


def test_square_objects_are_measured_with_breaks_at_their_corners():
    # Two squares of side 40 turned by 0.3 rad, 8x8 supersampled.
    h, w = 120, 240
    yy, xx = np.mgrid[0:h * 8, 0:w * 8]
    x, y = (xx + 0.5) / 8 - 0.5, (yy + 0.5) / 8 - 0.5
    inside = np.zeros_like(x, dtype=bool)
    c, s = np.cos(0.3), np.sin(0.3)
    for cx, cy in [(60.3, 60.2), (170.6, 58.7)]:
        u = c * (x - cx) + s * (y - cy)
        v = -s * (x - cx) + c * (y - cy)
        inside |= (np.abs(u) < 20) & (np.abs(v) < 20)
    image = 0.2 + 0.6 * inside.reshape(h, 8, w, 8).mean(axis=(1, 3))
    results, table = vicurve.measure_all(image, corners=4)
    assert list(table["outcome"]) == ["measured"] * 2
    # Sides measured as straight lines meeting at corners: the area within
    # a pixel of the exact 1600 px^2.
    assert all(abs(r.area - 1600.0) < 1.0 for r in results), [r.area for r in results]
    with pytest.raises(ValueError, match="corners"):
        vicurve.measure_all(image, corners=2)

def test_measure_finds_a_squares_corners():
    # A square of side 60 turned by 0.3 rad, 8x8 supersampled, measured
    # from a circle without breaks: its corners are found (within a pixel
    # of the true ones), or not looked for.
    n, cx, cy = 160, 80.3, 80.2
    yy, xx = np.mgrid[0:n * 8, 0:n * 8]
    x, y = (xx + 0.5) / 8 - 0.5, (yy + 0.5) / 8 - 0.5
    c, s = np.cos(0.3), np.sin(0.3)
    u = c * (x - cx) + s * (y - cy)
    v = -s * (x - cx) + c * (y - cy)
    inside = (np.abs(u) < 30) & (np.abs(v) < 30)
    image = 0.2 + 0.6 * inside.reshape(n, 8, n, 8).mean(axis=(1, 3))
    start = vicurve.Circle(cx, cy, 30.0)
    r = vicurve.measure(image, start)
    assert len(r.corners_found) == 4
    corners = [(cx + c * a - s * b, cy + s * a + c * b)
               for a, b in [(30, 30), (30, -30), (-30, 30), (-30, -30)]]
    for px, py in r.corners_found:
        assert min(np.hypot(px - qx, py - qy) for qx, qy in corners) < 1.0, (px, py)
    assert abs(r.area - 3600.0) < 1.0
    assert vicurve.measure(image, start, find_corners=False).corners_found == []


def test_holes_and_lines():
    # A disc of radius 30 with a hole of radius 12: with holes=True the
    # hole is an object too, its parent the disc.
    h, w = 160, 160
    yy, xx = np.mgrid[0:h * 4, 0:w * 4]
    x, y = (xx + 0.5) / 4 - 0.5, (yy + 0.5) / 4 - 0.5
    d = np.hypot(x - 80.3, y - 79.6)
    ring = ((d < 30.0) & (d > 12.0)).reshape(h, 4, w, 4).mean(axis=(1, 3))
    _, table = vicurve.measure_all(0.2 + 0.6 * ring, holes=True, model="circle")
    assert list(table["outcome"]) == ["measured", "measured"]
    assert np.isnan(table["parent"][0]) and table["parent"][1] == 0
    assert abs(table["model_r"][1] - 12.0) < 0.02
    # A thin ring (3 px wide) measured as a line.
    line = ((d < 31.5) & (d > 28.5)).reshape(h, 4, w, 4).mean(axis=(1, 3))
    _, lines = vicurve.measure_all(0.2 + 0.6 * line, kind="contour", model="circle")
    assert list(lines["outcome"]) == ["measured"]
    assert abs(lines["model_r"][0] - 30.0) < 0.02
    with pytest.raises(ValueError):
        vicurve.measure_all(line, kind="wiggle")
