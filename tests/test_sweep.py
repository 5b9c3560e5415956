"""threads= for "sor"/"gs": threaded solves against scipy's direct solve and the
one-thread sweep, the caller's vertex order, the parameter's checks.

The threaded sweep splits the vertices into index ranges and sweeps the
vertices shared between ranges last: Gauss-Seidel in another order, so the
solution is the same to the tolerance and the iteration count nearly so.

The core runs the ranges on real threads only from PARALLEL_MIN vertices a
thread (below, one after another, with the same result), so the threaded
cases use meshes of at least PARALLEL_MIN * threads vertices.
"""

import subprocess
import sys
import math

import numpy as np
import pytest
import sorpia
from conftest import direct_solve

TOL = 1e-10
PARALLEL_MIN = 8192  # vertices a thread from which the core runs ranges on threads


@pytest.fixture(scope="module")
def big_irregular():
    # Enough vertices that 3 threads run in parallel.
    v, f = sorpia.shapes.irregular(26000, seed=4)
    assert len(v) >= 3 * PARALLEL_MIN
    return v, f


@pytest.fixture(scope="module")
def big_irregular_reference(big_irregular):
    # The direct solve (about 0.1 s, 15 times the iterative one) is shared by
    # every threads/method case.
    v, f = big_irregular
    return direct_solve(f, v)


@pytest.mark.parametrize("threads", [1, 2, 3])
@pytest.mark.parametrize("method", ["sor", "gs"])
def test_threads_equal_direct_solve(big_irregular, big_irregular_reference, threads, method):
    v, f = big_irregular
    res = sorpia.interpolate(v, f, method=method, tol=TOL, threads=threads)
    assert res.converged
    ref = big_irregular_reference
    # E_k < 1e-10 E_0 and B's eigenvalues lie in about [0.2, 1]: the error in
    # V is a few 1e-10 E_0, far below 1e-8 of the coordinates.
    assert np.abs(res.control_vertices - ref).max() <= 1e-8 * np.abs(ref).max()


@pytest.mark.parametrize("mesh_name", ["grid", "pole", "irregular"])
def test_threads_iterations_close_to_sequential(mesh_name):
    # grid and irregular run 2 and 3 ranges on threads; the small pole, one
    # after another.
    v, f = {"grid": sorpia.shapes.grid(180, 140), "pole": sorpia.shapes.pole(60),
            "irregular": sorpia.shapes.irregular(26000, seed=9)}[mesh_name]
    assert mesh_name == "pole" or len(v) >= 3 * PARALLEL_MIN
    one = sorpia.interpolate(v, f, threads=1)
    ref = direct_solve(f, v)
    for threads in (2, 3):
        res = sorpia.interpolate(v, f, threads=threads)
        assert res.converged
        assert res.iterations <= math.ceil(1.15 * one.iterations)
        assert np.abs(res.control_vertices - ref).max() <= 1e-8 * np.abs(ref).max()


def test_errors_are_the_papers_ek_with_threads(big_irregular):
    # E_k from the fused sweep against the residual of the returned vertices
    # with B from scratch (summed in another order: equal to rounding).
    v, f = big_irregular
    b = sorpia.limit_matrix(f, len(v))
    for k in (1, 3):
        with pytest.warns(sorpia.ConvergenceWarning):
            res = sorpia.interpolate(v, f, threads=2, max_iter=k)
        ek = np.linalg.norm(v - b @ res.control_vertices, axis=1).max()
        assert abs(ek / res.initial_error - res.history[-1]) <= 1e-12


def test_control_vertices_in_callers_order():
    # Relabel the vertices at random: the answer must come back relabelled the
    # same way.
    # 40k vertices shuffled: far enough apart in index that the core sweeps
    # them in a breadth-first order of its own.
    v, f = sorpia.shapes.irregular(40000, seed=2)
    perm = np.random.default_rng(0).permutation(len(v))
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(v))
    vp = v[perm]             # new vertex i is old vertex perm[i]
    fp = inv[f]
    ref = direct_solve(f, v)
    for threads in (1, 2):
        res = sorpia.interpolate(vp, fp, threads=threads)
        assert res.converged
        assert np.abs(res.control_vertices - ref[perm]).max() <= 1e-8 * np.abs(ref).max()


def test_interpolator_solve_takes_threads():
    v, f = sorpia.shapes.torus(140, 120)  # 2 ranges on threads
    assert len(v) >= 2 * PARALLEL_MIN
    solver = sorpia.Interpolator(f, len(v))
    a = solver.solve(v, threads=1)
    b = solver.solve(v, threads=2)
    assert np.abs(a.control_vertices - b.control_vertices).max() <= 1e-8 * np.abs(v).max()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"threads": 0}, r"threads = 0 must be an integer in 1\.\."),
        ({"threads": -2}, r"threads = -2 must be"),
        ({"threads": 10**6}, r"threads = 1000000 must be an integer in 1\.\."),
        ({"threads": 1.5}, r"threads = 1\.5 must be an integer"),
        ({"threads": True}, r"threads = True must be an integer"),
        ({"threads": "2"}, r"threads = '2' must be an integer"),
        ({"threads": None}, r"threads = None must be an integer"),
        ({"method": "cg", "threads": 2}, r"threads = 2 applies to method='sor', 'gs' or 'auto' only"),
        ({"method": "pia", "threads": 3}, r"threads = 3 applies to method='sor', 'gs' or 'auto' only"),
    ],
)
def test_bad_threads(kwargs, match):
    v, f = sorpia.shapes.icosphere(0)
    with pytest.raises(sorpia.ParameterError, match=match):
        sorpia.interpolate(v, f, **kwargs)
    with pytest.raises(sorpia.ParameterError, match=match):
        sorpia.Interpolator(f, len(v)).solve(v, **kwargs)


def test_numpy_integer_threads_accepted():
    v, f = sorpia.shapes.icosphere(1)
    assert sorpia.interpolate(v, f, threads=np.int64(2)).converged


FORK_AFTER_THREADS = """
import os, signal, sys
import numpy as np
import sorpia
v, f = sorpia.shapes.irregular(40000, 1)
parent = sorpia.interpolate(v, f, threads=2)  # the pool's workers exist now
pid = os.fork()
if pid == 0:
    signal.alarm(60)  # a hang ends the child with SIGALRM
    child = sorpia.interpolate(v, f, threads=2)
    same = np.array_equal(child.control_vertices, parent.control_vertices)
    os._exit(0 if child.converged and same else 1)
_, status = os.waitpid(pid, 0)
print(os.waitstatus_to_exitcode(status))
"""


def test_a_forked_child_solves_on_threads_after_its_parent_did():
    """multiprocessing's fork start method: a child forked after the parent
    solved on threads must solve on threads too, with the parent's result bit
    for bit (the threads' ranges do not depend on timing). With OpenMP's
    runtime the child hung in the parallel region."""
    out = subprocess.run([sys.executable, "-c", FORK_AFTER_THREADS], capture_output=True, text=True, timeout=180)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "0", out.stdout + out.stderr


NO_THREAD_TO_BE_HAD = """
import resource, sys
import numpy as np
import sorpia
v, f = sorpia.shapes.irregular(40000, 1)
one = sorpia.interpolate(v, f, threads=1)
# Every new thread's stack is RLIMIT_STACK (4 GiB, set before this process
# started); the address space left is far less: no thread can start.
soft, hard = resource.getrlimit(resource.RLIMIT_AS)
resource.setrlimit(resource.RLIMIT_AS, (2 << 30, hard))
res = sorpia.interpolate(v, f, threads=2)
ok = res.converged and np.abs(res.control_vertices - one.control_vertices).max() < 1e-8
print("ok" if ok else "wrong")
"""


def test_threads_that_cannot_start_leave_the_work_to_the_caller():
    """Under memory limits where no thread can be started, threads=2 runs the
    ranges on the calling thread and returns the solution (with OpenMP's
    runtime the process printed 'Thread creation failed' and exited 1)."""
    import resource

    def big_stacks():
        resource.setrlimit(resource.RLIMIT_STACK, (4 << 30, resource.RLIM_INFINITY))

    out = subprocess.run([sys.executable, "-c", NO_THREAD_TO_BE_HAD], capture_output=True, text=True, timeout=180,
                         preexec_fn=big_stacks)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
