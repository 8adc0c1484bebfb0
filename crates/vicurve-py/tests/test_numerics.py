"""The engine's B-spline basis and image interpolation against SciPy."""

import numpy as np
import pytest

import vicurve

scipy_interpolate = pytest.importorskip("scipy.interpolate")
ndimage = pytest.importorskip("scipy.ndimage")


def scipy_open_basis(degree, n_el, length, s, derivative=0):
    """The open uniform basis: knots (i - p) h, i = 0 .. n_el + 2p."""
    h = length / n_el
    knots = (np.arange(n_el + 2 * degree + 1) - degree) * h
    n = n_el + degree
    spline = scipy_interpolate.BSpline(knots, np.eye(n), degree)
    if derivative:
        spline = spline.derivative(derivative)
    return spline(s)


@pytest.mark.parametrize(
    "degree,derivative", [(p, d) for p in range(1, 6) for d in range(3) if d <= p]
)
def test_open_basis_matches_scipy(degree, derivative):
    n_el, length = 7, 93.5
    s = np.concatenate([np.linspace(0, length, 1001), [length * 0.5 + 1e-9]])
    mine = vicurve.basis_values(degree, n_el, length, False, s, derivative=derivative)
    ref = scipy_open_basis(degree, n_el, length, s, derivative)
    assert mine.shape == (len(s), n_el + degree)
    scale = (n_el / length) ** derivative
    np.testing.assert_allclose(mine, ref, rtol=0, atol=1e-12 * max(1.0, scale))
    if derivative == 0:
        np.testing.assert_allclose(mine.sum(axis=1), 1.0, atol=1e-13)


@pytest.mark.parametrize("degree", [1, 2, 3, 4, 5])
def test_periodic_basis_is_the_wrapped_open_one(degree):
    n_el, length = 9, 120.0
    s = np.linspace(0, length, 900, endpoint=False)
    mine = vicurve.basis_values(degree, n_el, length, True, s)
    assert mine.shape == (len(s), n_el)
    unwrapped = scipy_open_basis(degree, n_el, length, s)
    wrapped = np.zeros((len(s), n_el))
    for i in range(n_el + degree):
        wrapped[:, i % n_el] += unwrapped[:, i]
    np.testing.assert_allclose(mine, wrapped, rtol=0, atol=1e-12)
    # Periodic: s and s + L give the same values.
    np.testing.assert_allclose(
        vicurve.basis_values(degree, n_el, length, True, s + length), mine, atol=1e-12
    )
    d1 = vicurve.basis_values(degree, n_el, length, True, s, derivative=1)
    np.testing.assert_allclose(d1.sum(axis=1), 0.0, atol=1e-12)


@pytest.fixture(scope="module")
def texture():
    rng = np.random.default_rng(5)
    return rng.random((37, 53))


def random_points(shape, count, rng):
    h, w = shape
    return rng.uniform(0, w - 1, count), rng.uniform(0, h - 1, count)


def test_cubic_matches_map_coordinates_with_mirror_boundaries(texture):
    rng = np.random.default_rng(1)
    xs, ys = random_points(texture.shape, 4000, rng)
    # The borders themselves and the cells next to them.
    h, w = texture.shape
    edge_x = np.r_[0.0, 0.3, w - 1.3, w - 1.0, 0.0, w - 1.0]
    edge_y = np.r_[0.0, h - 1.0, 0.7, h - 1.0, h - 1.6, 0.2]
    xs, ys = np.r_[xs, edge_x], np.r_[ys, edge_y]
    mine = vicurve.interpolate(texture, xs, ys, kind="cubic")
    # The engine mirrors about the first and last pixel centres: scipy's
    # 'mirror' mode, in the prefilter and the evaluation alike.
    ref = ndimage.map_coordinates(texture, [ys, xs], order=3, mode="mirror")
    np.testing.assert_allclose(mine, ref, rtol=0, atol=1e-12)
    # Pixel centres are interpolated exactly.
    ii, jj = np.mgrid[0:h, 0:w]
    np.testing.assert_allclose(
        vicurve.interpolate(texture, jj.astype(float), ii.astype(float)), texture, atol=1e-12
    )


def test_bilinear_matches_map_coordinates_order_1(texture):
    rng = np.random.default_rng(2)
    xs, ys = random_points(texture.shape, 4000, rng)
    xs, ys = xs.reshape(40, 100), ys.reshape(40, 100)
    mine = vicurve.interpolate(texture, xs, ys, kind="bilinear")
    assert mine.shape == (40, 100)
    ref = ndimage.map_coordinates(texture, [ys, xs], order=1, mode="mirror")
    np.testing.assert_allclose(mine, ref, rtol=0, atol=1e-13)


@pytest.mark.parametrize("kind", ["cubic", "bilinear", "keys"])
def test_gradients_are_the_derivatives_of_the_values(texture, kind):
    rng = np.random.default_rng(3)
    xs, ys = random_points(texture.shape, 500, rng)
    # Keep clear of pixel-centre lines, where bilinear gradients jump.
    xs = np.clip(np.floor(xs) + 0.2 + 0.6 * (xs % 1), 0.5, texture.shape[1] - 1.5)
    ys = np.clip(np.floor(ys) + 0.2 + 0.6 * (ys % 1), 0.5, texture.shape[0] - 1.5)
    v, gx, gy = vicurve.interpolate(texture, xs, ys, kind=kind, gradient=True)
    np.testing.assert_array_equal(v, vicurve.interpolate(texture, xs, ys, kind=kind))
    e = 1e-6
    fx = (vicurve.interpolate(texture, xs + e, ys, kind=kind)
          - vicurve.interpolate(texture, xs - e, ys, kind=kind)) / (2 * e)
    fy = (vicurve.interpolate(texture, xs, ys + e, kind=kind)
          - vicurve.interpolate(texture, xs, ys - e, kind=kind)) / (2 * e)
    np.testing.assert_allclose(gx, fx, atol=1e-6)
    np.testing.assert_allclose(gy, fy, atol=1e-6)


def test_keys_reproduces_quadratics_inside():
    ii, jj = np.mgrid[0:30, 0:40].astype(float)
    quad = 0.01 * jj**2 - 0.02 * ii * jj + 0.005 * ii**2 + 0.1 * jj
    rng = np.random.default_rng(4)
    xs, ys = rng.uniform(2, 37, 300), rng.uniform(2, 27, 300)
    exact = 0.01 * xs**2 - 0.02 * ys * xs + 0.005 * ys**2 + 0.1 * xs
    np.testing.assert_allclose(vicurve.interpolate(quad, xs, ys, kind="keys"), exact,
                               atol=1e-12)


def test_outside_the_pixel_centres_is_nan(texture):
    h, w = texture.shape
    xs = np.array([-0.01, w - 0.99, 3.0, 3.0, np.nan])
    ys = np.array([3.0, 3.0, -0.5, h - 0.5, 3.0])
    assert np.all(np.isnan(vicurve.interpolate(texture, xs, ys)))
    v, gx, gy = vicurve.interpolate(texture, xs, ys, gradient=True)
    assert np.all(np.isnan(v)) and np.all(np.isnan(gx)) and np.all(np.isnan(gy))
