"""Approximation on a Dask cluster (``sorpia.approximate(..., client=...)``,
``sorpia approximate --scheduler``): the chunks held by the workers of a
LocalCluster of two worker processes give the fit of the same chunks in one
process (the same footpoints, the sums added in chunk order: 1e-10 relative),
with one worker and with two; a client that cannot run it is refused by name,
and the client given is left open."""

from __future__ import annotations

import gc
import socket
import sys
import time

import numpy as np
import pytest

distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install "
                                  "'sorpia[dask]'; make test installs it)")

import sorpia  # noqa: E402
from sorpia import ParameterError, shapes  # noqa: E402
from test_approximate_chunks import noisy_samples as chunk_samples, with_outliers, write_ply  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    """Two worker processes of one thread each, for the whole module (a cluster starts in seconds)."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  scheduler_port=0, silence_logs=50) as c:
        yield c


@pytest.fixture(scope="module")
def client(cluster):
    with distributed.Client(cluster, set_as_default=False) as c:
        yield c


@pytest.fixture(scope="module")
def one_worker_client():
    """A cluster of one worker process: the same chunks on fewer workers."""
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  scheduler_port=0, silence_logs=50) as c, \
            distributed.Client(c, set_as_default=False) as cl:
        yield cl


def noisy_samples(k=4000, seed=1):
    """Points near a known limit surface with noise (test_approximate_chunks'), the start cage, and weights."""
    P, V, F = chunk_samples(k, seed)
    return P, V, F, np.random.default_rng(seed + 10).random(k) + 0.5


def relative(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(np.asarray(b))))


def assert_same_fit(dask_result, local):
    """The fit on the cluster is the one of the same chunks in one process: the same iterations, stop reason,
    best iterate and footpoint faces, control vertices and each record's RMS within 1e-10 relative."""
    assert (dask_result.iterations, dask_result.stop_reason, dask_result.best_iteration) == \
        (local.iterations, local.stop_reason, local.best_iteration)
    assert relative(dask_result.control_vertices, local.control_vertices) < 1e-10
    for a, b in zip(dask_result.history, local.history, strict=True):
        for key in ("rms", "max", "surface_rms", "surface_max"):  # the surface's: None where not measured
            assert (a[key] is None) == (b[key] is None), (a["iteration"], key)
            assert b[key] is None or abs(a[key] - b[key]) <= 1e-10 * b[key], (a["iteration"], key)
    np.testing.assert_array_equal(dask_result.face_ids, local.face_ids)
    np.testing.assert_allclose(dask_result.uv, local.uv, rtol=0, atol=1e-10)
    np.testing.assert_allclose(dask_result.distances, local.distances, rtol=1e-10, atol=1e-14)


@pytest.mark.parametrize("tangential", [0.1, 1.0])
def test_two_workers_fit_as_one_process(client, tangential):
    P, V, F, w = noisy_samples()
    kw = dict(tangential=tangential, weights=w, iterations=6, chunk_points=700)
    local = sorpia.approximate(P, V, F, **kw)
    on_cluster = sorpia.approximate(P, V, F, client=client, **kw)
    assert_same_fit(on_cluster, local)
    assert local.history[-1]["rms"] < 0.5 * local.history[0]["rms"]  # a fit that moved: not a trivial equality


@pytest.mark.parametrize("robust", ["tukey", "cauchy"])
def test_robust_fit_with_outliers_on_two_workers_as_in_one_process(client, robust):
    # the robust fit's histogram, loss sums and reweighted sums come from the workers' chunks in order
    P, V, F, _ = noisy_samples(3000, seed=3)
    P, far = with_outliers(P, 30)
    kw = dict(robust=robust, iterations=5, chunk_points=700)
    local = sorpia.approximate(P, V, F, **kw)
    assert_same_fit(sorpia.approximate(P, V, F, client=client, **kw), local)
    assert local.robust_outliers >= 1  # the outliers were cut or damped: the robust path ran


def test_coarse_iterations_on_two_workers_as_in_one_process(client):
    # the workers' chunks sample their points (set_sample) as the chunks in one process do
    P, V, F, w = noisy_samples()
    kw = dict(weights=w, iterations=7, coarse_iterations=3, coarse_points=8, chunk_points=700)
    local = sorpia.approximate(P, V, F, **kw)
    assert local.coarse_iterations == 3 and local.history[1]["points"] < len(P) // 2
    assert_same_fit(sorpia.approximate(P, V, F, client=client, **kw), local)


def test_one_worker_fits_as_two(client, one_worker_client):
    P, V, F, _ = noisy_samples(3000, seed=2)
    kw = dict(iterations=5, chunk_points=500)
    two = sorpia.approximate(P, V, F, client=client, **kw)
    one = sorpia.approximate(P, V, F, client=one_worker_client, **kw)
    assert_same_fit(one, two)
    assert_same_fit(two, sorpia.approximate(P, V, F, **kw))


def test_data_beyond_2_to_the_200_fits_as_in_one_process(client):
    # the driver scales such data by a power of two: the workers' chunks and the client's sample alike
    P, V, F, _ = noisy_samples(1500, seed=5)
    kw = dict(iterations=3, chunk_points=400)
    local = sorpia.approximate(P * 1e70, V * 1e70, F, **kw)
    assert_same_fit(sorpia.approximate(P * 1e70, V * 1e70, F, client=client, **kw), local)


def test_more_workers_than_chunks(client):
    # one chunk: a single worker holds it, the other gets nothing to do
    P, V, F, _ = noisy_samples(600, seed=3)
    local = sorpia.approximate(P, V, F, iterations=3)
    assert_same_fit(sorpia.approximate(P, V, F, iterations=3, client=client), local)


def test_client_left_open_and_workers_freed(client):
    P, V, F, _ = noisy_samples(500, seed=4)
    sorpia.approximate(P, V, F, iterations=2, client=client, chunk_points=200)
    assert client.status == "running"
    # the run's actors and chunks are released when it returns (the scheduler hears of it within moments):
    # nothing stays in the workers' memory
    deadline = time.monotonic() + 10
    while any(client.has_what().values()) and time.monotonic() < deadline:
        gc.collect()
        time.sleep(0.1)
    assert not any(client.has_what().values()), client.has_what()


def test_not_a_client_is_refused():
    P, V, F, _ = noisy_samples(200)
    with pytest.raises(ParameterError, match="client = 'tcp://.*' must be a dask.distributed Client"):
        sorpia.approximate(P, V, F, client="tcp://127.0.0.1:8786")


def test_closed_client_is_refused():
    P, V, F, _ = noisy_samples(200)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0",
                                  scheduler_port=0) as c:
        cl = distributed.Client(c, set_as_default=False)
        cl.close()
    with pytest.raises(ParameterError, match="client = .* is closed"):
        sorpia.approximate(P, V, F, client=cl)


def test_client_of_a_gone_scheduler_is_refused():
    P, V, F, _ = noisy_samples(200)
    c = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0",
                                 scheduler_port=0)
    cl = distributed.Client(c, set_as_default=False)
    c.close()  # the scheduler goes; the client is left as it is
    try:
        with pytest.raises(ParameterError, match="client = .* is (closed|connecting|closing)"):
            sorpia.approximate(P, V, F, client=cl)
    finally:
        cl.close()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_cli_scheduler_fits_as_without(tmp_path, cluster, command):
    V, F = shapes.icosphere(4)
    V = V * (1 + 0.02 * np.sin(5 * V[:, :1]))
    sorpia.write_mesh(tmp_path / "scan.ply", V, F)
    code, _, err = command("approximate", str(tmp_path / "scan.ply"), "-o", str(tmp_path / "a.obj"),
                           "--vertices", "60", "--report", str(tmp_path / "a.json"), "--iterations", "3")
    assert code == 0, err
    code, out, err = command("approximate", str(tmp_path / "scan.ply"), "-o", str(tmp_path / "b.obj"),
                             "--vertices", "60", "--report", str(tmp_path / "b.json"), "--iterations", "3",
                             "--scheduler", cluster.scheduler_address)
    assert code == 0, err
    assert f"Dask scheduler {cluster.scheduler_address}, 2 workers" in out
    a, b = sorpia.read_mesh(tmp_path / "a.obj"), sorpia.read_mesh(tmp_path / "b.obj")
    assert relative(b[0], a[0]) < 1e-10


def test_cli_unreachable_scheduler_is_named(tmp_path, command):
    V, F = shapes.icosphere(2)
    sorpia.write_mesh(tmp_path / "scan.ply", V, F)
    address = f"tcp://127.0.0.1:{free_port()}"
    code, _, err = command("approximate", str(tmp_path / "scan.ply"), "-o", str(tmp_path / "a.obj"),
                           "--vertices", "20", "--scheduler", address)
    assert code == 2
    assert f"--scheduler {address}: no Dask scheduler answered there" in err
    assert not (tmp_path / "a.obj").exists()


def test_cli_malformed_scheduler_address_is_named(tmp_path, command):
    V, F = shapes.icosphere(2)
    sorpia.write_mesh(tmp_path / "scan.ply", V, F)
    code, _, err = command("approximate", str(tmp_path / "scan.ply"), "-o", str(tmp_path / "a.obj"),
                           "--vertices", "20", "--scheduler", "scheduler-host")
    assert code == 2
    assert "--scheduler scheduler-host is not a Dask scheduler's address (tcp://HOST:PORT)" in err


def test_without_dask_the_install_line_is_given(tmp_path, command, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed raises ImportError
    P, V, F, _ = noisy_samples(200)
    with pytest.raises(ParameterError, match=r"needs dask.distributed, which is not installed: pip install "
                                             r"'sorpia\[dask\]'"):
        sorpia.approximate(P, V, F, client=object())
    sorpia.write_mesh(tmp_path / "scan.ply", V, F)
    code, _, err = command("approximate", str(tmp_path / "scan.ply"), "-o", str(tmp_path / "a.obj"),
                           "--vertices", "20", "--scheduler", "tcp://127.0.0.1:8786")
    assert code == 2
    assert "--scheduler tcp://127.0.0.1:8786 runs the fit on a Dask cluster and needs dask.distributed" in err


@pytest.mark.parametrize("kind", ["npy", "ply"])
def test_file_read_by_the_workers_fits_as_streamed(tmp_path, client, kind):
    # A path: each worker reads its chunks from the file, the report measures from FileChunks' fixed sample (fewer
    # points than the file here), and the result is the out-of-core run's in one process, footpoints not kept.
    P, V, F, _ = noisy_samples(3000, seed=6)
    path = tmp_path / f"points.{kind}"
    if kind == "npy":
        np.save(path, P)
    else:
        write_ply(path, P.astype(np.float32), np.float32)
    kw = dict(iterations=4, chunk_points=700, sample_points=1000)
    streamed = sorpia.approximate(path, V, F, **kw)
    on_cluster = sorpia.approximate(path, V, F, client=client, **kw)
    assert len(on_cluster.face_ids) == len(streamed.face_ids) == 0
    assert_same_fit(on_cluster, streamed)
    assert on_cluster.timings["cluster"]["bytes_to_workers"] < P.nbytes  # the points were not sent


def test_cli_streamed_file_read_by_the_workers(tmp_path, cluster, command):
    # --stream with --scheduler: the workers read the chunks from the file; the cage written is the one of the
    # streamed run in one process
    P, V, F, _ = noisy_samples(2500, seed=7)
    np.save(tmp_path / "scan.npy", P)
    sorpia.write_mesh(tmp_path / "cage.obj", V, F)
    common = ["--cage", str(tmp_path / "cage.obj"), "--stream", "yes", "--iterations", "3"]
    code, _, err = command("approximate", str(tmp_path / "scan.npy"), "-o", str(tmp_path / "a.obj"), *common)
    assert code == 0, err
    code, out, err = command("approximate", str(tmp_path / "scan.npy"), "-o", str(tmp_path / "b.obj"), *common,
                             "--scheduler", cluster.scheduler_address)
    assert code == 0, err
    assert "2 workers" in out
    a, b = sorpia.read_mesh(tmp_path / "a.obj"), sorpia.read_mesh(tmp_path / "b.obj")
    assert relative(b[0], a[0]) < 1e-10


def test_lost_worker_is_named():
    # A worker killed between two calls of the driver: its actor and chunks are gone, and the next call says which
    # worker and chunks, instead of Dask's bare comm error.
    import os
    import signal

    from sorpia import _dask

    P, V, F, _ = noisy_samples(1000, seed=8)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  scheduler_port=0, silence_logs=50) as c, \
            distributed.Client(c, set_as_default=False) as cl:
        workers = _dask.check_client(cl)
        chunks = _dask.DaskChunks(cl, workers, dict(vertices=V, faces=F), P, None, 300, 1000)
        assert sum(e[0] for e in chunks.extent()) == 1000
        os.kill(cl.run(os.getpid)[workers[1]], signal.SIGKILL)
        with pytest.raises(OSError, match=rf"a Dask worker holding this fit's chunks was lost: "
                                          rf"{workers[1]} \(chunks 2..3\)"):
            for _ in range(50):  # until the scheduler has noticed
                chunks.extent()
                time.sleep(0.1)
        chunks.close()
