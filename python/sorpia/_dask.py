"""Approximation past one machine: the chunks of points held by the workers of
a dask.distributed cluster (``sorpia.approximate(..., client=...)``,
``sorpia approximate --scheduler ADDRESS``; docs/distributed.md).

The loop stays the core's (``sorpia::approximate``: the stop rule, the best
iterate, the records, the solve); `DaskChunks` is the backend it calls
(``_core.PointChunks``), and what it changes is where each chunk's work runs.
One Dask actor per worker (`ChunkHost`) holds, for one run, the cage's limit
surface (built there once from its faces and rules, which travel once) and
the chunks given to that worker (``_core.ApproximationChunk``: points,
weights, footpoints) between iterations. Each call of the driver goes to
every actor at once; what comes back is each chunk's result by chunk index,
and the backend hands the driver the chunks' sums as a list in chunk index
order, which the core adds in that order: the result is the one of the same
chunks in one process (``InMemoryChunks`` with the same ``chunk_points``),
whatever the number of workers. Between iterations only the control vertices
go out, and each chunk's sums come back.

dask.distributed is optional (``pip install 'sorpia[dask]'``): it is imported
only when a client is given or an address dialled.
"""

from __future__ import annotations

import gc
import time
from typing import Any, Optional

import numpy as np

from . import _core
from .errors import ParameterError

INSTALL_HINT = "pip install 'sorpia[dask]'"


def _distributed():
    """The dask.distributed module, or ParameterError saying how to install it."""
    try:
        import distributed
    except ImportError:
        raise ParameterError("client= runs the fit on a Dask cluster and needs dask.distributed, which is not "
                             f"installed: {INSTALL_HINT}") from None
    return distributed


def check_client(client) -> list[str]:
    """The addresses of the workers of `client`, a running dask.distributed
    Client with at least one worker, sorted; a ParameterError naming what is
    wrong otherwise (not a Client, closed, its scheduler gone, no worker).
    The one place a client is checked."""
    distributed = _distributed()
    if not isinstance(client, distributed.Client):
        raise ParameterError(f"client = {client!r} must be a dask.distributed Client or None")
    if client.status != "running":
        raise ParameterError(f"client = {client!r} is {client.status}: give a running Client")
    try:
        workers = worker_addresses(client)
    except Exception as exc:  # the scheduler went away after the client connected
        raise ParameterError(f"client = {client!r}: its scheduler does not answer ({type(exc).__name__}: "
                             f"{exc})") from None
    if not workers:
        raise ParameterError(f"client = {client!r}: the cluster has no worker; start workers (dask worker "
                             "ADDRESS) or wait for them (client.wait_for_workers(n))")
    return workers


def worker_addresses(client) -> list[str]:
    """The addresses of every worker of the client's cluster, sorted."""
    try:
        info = client.scheduler_info(n_workers=-1)  # newer distributed lists only 5 workers unless asked for all
    except TypeError:
        info = client.scheduler_info()
    return sorted(info["workers"])


def connect(address: str, timeout: float = 10.0):
    """A Client of the scheduler at `address` (``--scheduler``): ImportError
    with the install line when dask.distributed is missing, OSError naming the
    address when no scheduler answers within `timeout` seconds."""
    try:
        import distributed
    except ImportError:
        raise ImportError(f"--scheduler {address} runs the fit on a Dask cluster and needs dask.distributed, which "
                          f"is not installed: {INSTALL_HINT}") from None
    try:  # checked before a Client is made: a Client of a malformed address hangs on closing
        distributed.comm.get_address_host_port(address)
    except ValueError as exc:
        raise OSError(f"--scheduler {address} is not a Dask scheduler's address (tcp://HOST:PORT): {exc}") from None
    try:
        return distributed.Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise OSError(f"--scheduler {address}: no Dask scheduler answered there within {timeout:g} s "
                      f"({type(exc).__name__}: {exc})") from None


class ChunkHost:
    """A Dask actor on one worker for one run: the cage's limit surface, built
    there once, its footpoint search for the current control vertices, and
    the chunks of points given to this worker, by chunk index."""

    def __init__(self, cage: dict):
        from .surface import LimitSurface

        self.surface = LimitSurface(**cage)._surface
        self.search_: Optional[Any] = None
        self.chunks: dict[int, Any] = {}
        self.sampled: dict[int, Any] = {}  # the coarse iterations' chunks (set_sample), empty: all points

    def add(self, index: int, points, weights: Optional[np.ndarray], first: int, count: int) -> int:
        """Chunk `index`: the points first .. first + count of all, given as an
        array, or read here from the file at the path `points`."""
        if isinstance(points, str):
            points = _core.read_point_file(points, first, count)
        self.chunks[index] = _core.ApproximationChunk(points, weights, first)
        return count

    def set_control_vertices(self, vertices: np.ndarray) -> None:
        self.surface.set_vertices(vertices)
        self.search_ = None

    def set_sample(self, k: int, sample_points: int) -> None:
        """The chunks' points in the fixed sample of about sample_points of all k
        for the calls that follow (ApproximationChunk.sampled), or all points
        again with 0 (PointChunks.set_sample)."""
        self.sampled = {} if sample_points == 0 else {i: c.sampled(k, sample_points) for i, c in self.chunks.items()}

    def _search(self, grid: int, max_steps: int):
        if self.search_ is None:
            self.search_ = _core.FootpointSearch(self.surface, grid, max_steps)
        return self.search_

    def run(self, name: str, args: tuple) -> list:
        """[(index, chunk.name(...), (wall, cpu))] for this worker's chunks in
        index order: the per-chunk work of the driver's call `name`
        (PointChunks), with its wall seconds and its process's CPU seconds
        (the core's threads) on the worker."""
        if name in ("search", "search_fresh", "refine_fresh"):
            search = self._search(*args[:2])
            call = (lambda c: getattr(c, name)(search, *args[2:]))  # noqa: E731
        elif name == "refine":
            call = lambda c: c.refine(self.surface, *args)  # noqa: E731
        elif name in ("normal_sums", "robust_normal_sums"):
            call = lambda c: getattr(c, name)(self.surface, *args)  # noqa: E731
        elif name == "sample":  # FileChunks' fixed sample of the points: args (k, sample_points)
            call = lambda c: c.points[_core.point_sample_mask(c.first, c.size, *args)]  # noqa: E731
        else:
            call = lambda c: getattr(c, name)(*args)  # noqa: E731
        out = []
        chunks = self.sampled or self.chunks
        for i in sorted(chunks):
            t0, c0 = time.perf_counter(), time.process_time()
            result = call(chunks[i])
            out.append((i, result, (time.perf_counter() - t0, time.process_time() - c0)))
        return out


class DaskChunks(_core.PointChunks):
    """The driver's backend (``_core.PointChunks``) whose chunks live on the
    workers of a Dask cluster: chunk c of ``chunk_points`` points on worker
    ``c * len(workers) // n_chunks`` (contiguous runs of chunks per worker).
    Every sum goes back to the driver as a list in chunk index order.

    `points`: an array, whose chunks are sent from here (and which the
    surface-to-data report measures from, as InMemoryChunks'), or the path of
    a file FileChunks streams, whose chunks each worker reads itself (a
    filesystem they all see at that path) and whose report comes from
    FileChunks' fixed sample of `sample_points`; its footpoints are not
    gathered (as FileChunks')."""

    def __init__(self, client, workers: list[str], cage: dict, points, weights: Optional[np.ndarray],
                 chunk_points: int, sample_points: int):
        super().__init__()
        self.client, self.points, self.sample_points = client, points, sample_points
        self.weights = weights  # the sample leaves out the points of weight 0, as the core's chunks do
        self.e = 0  # the driver's scaling of data beyond 2^+-200 (scale)
        self.k = _core.point_file_points(points) if isinstance(points, str) else len(points)
        starts = list(range(0, self.k, chunk_points))
        self.n_chunks = len(starts)
        workers = workers[:self.n_chunks]  # a worker without a chunk gets no actor
        self.futures = [client.submit(ChunkHost, cage, actor=True, workers=[w], allow_other_workers=False,
                                      pure=False) for w in workers]
        with client.as_current():  # the actors' handles call through this client (it need not be the default)
            self.hosts = [f.result() for f in self.futures]
        owner = [c * len(self.hosts) // self.n_chunks for c in range(self.n_chunks)]
        # what each actor holds, for a message when its worker is lost: (address, first chunk, last chunk)
        self.holds = [(w, owner.index(h), len(owner) - 1 - owner[::-1].index(h)) for h, w in enumerate(workers)]
        # What the cluster did, for ApproximationResult.timings["cluster"]: the workers' seconds per call (summed
        # over chunks), the bytes of arrays sent to the workers (the points once, then the control vertices) and
        # back per call.
        self.stats = {"workers": len(self.hosts), "chunks": self.n_chunks, "chunk_points": chunk_points,
                      "worker_seconds": {}, "worker_cpu_seconds": {}, "bytes_to_workers": sum(
                          _nbytes(a) for a in (points, weights) if isinstance(a, np.ndarray)), "bytes_from_workers": {}}
        self._wait([self.hosts[owner[c]].add(c, points if isinstance(points, str) else points[s:s + chunk_points],
                                        None if weights is None else weights[s:s + chunk_points], s,
                                        min(chunk_points, self.k - s))
               for c, s in enumerate(starts)])

    def close(self) -> None:
        """Releases the actors, and with them the chunks on the workers (the client stays open)."""
        for f in self.futures:
            f.release()
        self.futures, self.hosts = [], []
        # Each actor's handle holds a future of its key in a reference cycle (distributed's Actor): the key, and
        # so the actor and its chunks, is released on the workers once the cycle collector frees the handle.
        gc.collect()

    def _wait(self, futures: list) -> list:
        """The results of calls of the actors (ActorFutures, one per actor or per chunk), in order; an OSError
        naming the worker and its chunks where a worker that held chunks is lost."""
        out = []
        for f in futures:
            try:
                out.append(f.result())
            except OSError as exc:  # the actor's worker cannot be reached: its chunks' states are gone
                try:
                    alive = set(worker_addresses(self.client))
                except Exception:  # the scheduler too
                    alive = set()
                lost = ", ".join(f"{w} (chunks {a}..{b})" for w, a, b in self.holds if w not in alive)
                raise OSError(f"a Dask worker holding this fit's chunks was lost: {lost or exc}; the chunks' "
                              "footpoints lived in its memory, so the fit cannot go on: run it again") from exc
        return out

    def _all(self, name: str, *args) -> list:
        """Each chunk's result of `name`, in chunk index order."""
        parts = self._wait([h.run(name, args) for h in self.hosts])
        out = sorted((triple for part in parts for triple in part), key=lambda triple: triple[0])
        for j, key in enumerate(("worker_seconds", "worker_cpu_seconds")):
            seconds = self.stats[key]
            seconds[name] = seconds.get(name, 0.0) + sum(t[j] for _, _, t in out)
        back = self.stats["bytes_from_workers"]
        back[name] = back.get(name, 0) + sum(_nbytes(r) for _, r, _ in out)
        return [r for _, r, _ in out]

    def _each(self, name: str, *args) -> None:
        self._all(name, *args)

    def size(self):
        return self.k

    def extent(self):
        return self._all("extent")

    def scale(self, e):
        self.e = e
        self._each("scale", e)

    def moments(self, center, diagonal):
        return self._all("moments", tuple(center), diagonal)

    def line_offset(self, mean, axis, diagonal):
        return self._all("line_offset", tuple(mean), tuple(axis), diagonal)

    def set_control_vertices(self, vertices):
        vertices = np.ascontiguousarray(vertices)
        self.stats["bytes_to_workers"] += len(self.hosts) * int(vertices.nbytes)
        self._wait([h.set_control_vertices(vertices) for h in self.hosts])

    def search(self, grid, max_steps):
        return self._all("search", grid, max_steps)

    def refine(self, grid, max_steps):
        return self._all("refine", grid, max_steps)

    def keep_best(self):
        self._each("keep_best")

    def search_fresh(self, grid, max_steps, closer):
        return self._all("search_fresh", grid, max_steps, closer)

    def refine_fresh(self, grid, max_steps):
        return self._all("refine_fresh", grid, max_steps)

    def keep_fresh(self, closer):
        self._each("keep_fresh", closer)

    def keep_fresh_in_best(self):
        return self._all("keep_fresh_in_best")

    def normal_sums(self, tangential):
        return self._all("normal_sums", tangential)

    def distance_histogram(self, unit):
        return self._all("distance_histogram", unit)

    def robust_sums(self, robust, scale):
        return self._all("robust_sums", tuple(robust), scale)

    def robust_normal_sums(self, tangential, robust, scale):
        return self._all("robust_normal_sums", tangential, tuple(robust), scale)

    def set_sample(self, sample_points):
        self._wait([h.set_sample(self.k, sample_points) for h in self.hosts])

    def sample(self):
        if isinstance(self.points, str):
            return np.concatenate(self._all("sample", self.k, self.sample_points))
        # the client holds the array: the report measures from every point that counts (weight > 0; scaled as the
        # chunks), as in one process
        points = self.points if self.weights is None else self.points[np.asarray(self.weights) > 0]
        return np.ldexp(points, -self.e) if self.e else points

    def best_footpoints(self):
        if isinstance(self.points, str):
            return None  # a billion footpoints are not gathered on the client
        parts = self._all("best_footpoints")
        return tuple(np.concatenate([p[j] for p in parts]) for j in range(3))


def _nbytes(result) -> int:
    """The bytes of the arrays in a chunk's result (a tuple of arrays and numbers)."""
    if isinstance(result, np.ndarray):
        return int(result.nbytes)
    if isinstance(result, (tuple, list)):
        return sum(_nbytes(r) for r in result)
    return 8
