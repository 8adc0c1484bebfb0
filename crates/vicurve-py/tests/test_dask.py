"""vicurve.dask on a LocalCluster of 2 workers gives the serial results."""

import numpy as np
import pytest

import vicurve

distributed = pytest.importorskip("distributed")
import vicurve.dask  # noqa: E402


def disc(k, size=80):
    image, _ = vicurve.synth("disc", size=(size, size), center=(40.3 + 0.2 * k, 39.6),
                             radius=20.0 + 0.1 * k, blur=1.0, noise=0.01, seed=k + 1, bits=16)
    return image


@pytest.fixture(scope="module")
def client():
    # Threads: the fits release the GIL, so 2 workers run 2 fits at once.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as c:
            yield c


def assert_same(a, b):
    assert list(a.keys()) == list(b.keys())
    for k in a:
        x, y = np.asarray(a[k]), np.asarray(b[k])
        if x.dtype.kind == "f":
            np.testing.assert_array_equal(x, y, err_msg=k)  # NaN equal to NaN
        else:
            assert list(x) == list(y), k


def test_measure_on_two_workers_equals_serial(client, tmp_path):
    images = [disc(k) for k in range(8)]
    images.insert(3, tmp_path / "missing.png")  # a failure is a row
    init = vicurve.Circle(40, 40, 19)
    on_cluster = vicurve.dask.measure(images, init, client)
    serial = vicurve.dask.measure_serial(images, init)
    assert_same(on_cluster, serial)
    outcomes = list(np.asarray(on_cluster["outcome"]))
    assert outcomes[3] == "failed" and outcomes.count("converged") == 8
    assert list(np.asarray(on_cluster["image"])) == list(range(9))


def test_track_on_two_workers_equals_serial(client):
    sequences = [np.stack([disc(k + 5 * s) for k in range(5)]) for s in range(3)]
    init = "circle:41,40,20"
    on_cluster = vicurve.dask.track(sequences, init, client)
    serial = vicurve.dask.track_serial(sequences, init)
    assert_same(on_cluster, serial)
    assert list(np.asarray(on_cluster["sequence"])) == [s for s in range(3) for _ in range(5)]
    assert set(np.asarray(on_cluster["outcome"])) == {"converged"}
