"""`sorpia info` run in-process: its counts against counts made here from
the face array alone, its verdict against sorpia's own validation."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sorpia

from cli_support import CLI_MESHES, assert_user_error, write_obj


def independent_counts(F, n):
    """Edges, boundary edges and valences from the face array alone."""
    half = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    edges, counts = np.unique(np.sort(half, axis=1), axis=0, return_counts=True)
    valence = np.bincount(edges.ravel(), minlength=n)
    on_boundary = np.zeros(n, bool)
    on_boundary[edges[counts == 1].ravel()] = True
    extraordinary = np.where(on_boundary, valence != 4, valence != 6)
    return len(edges), int((counts == 1).sum()), valence, extraordinary


@pytest.mark.parametrize("name, genus, loops", [("irregular-torus", 1, 0), ("grid-boundary", 0, 1)])
def test_info_json_counts(name, genus, loops, tmp_path, command):
    V, F = CLI_MESHES[name]()
    src = write_obj(tmp_path / "m.obj", V, F)
    code, stdout, err = command("info", src, "--json")
    assert code == 0, err
    info = json.loads(stdout)
    n_edges, n_bnd, valence, extra = independent_counts(np.asarray(F), len(V))
    assert (info["vertices"], info["faces"], info["edges"], info["boundary_edges"]) == (len(V), len(F), n_edges,
                                                                                        n_bnd)
    assert info["euler_characteristic"] == len(V) - n_edges + len(F) == 2 - 2 * genus - loops
    assert (info["genus"], info["boundary_loops"], info["components"]) == (genus, loops, 1)
    assert info["extraordinary_vertices"] == int(extra.sum())
    assert [e[0] for e in info["extraordinary"]] == np.flatnonzero(extra).tolist()
    assert [e[1] for e in info["extraordinary"]] == valence[extra].tolist()
    assert sum(sum(h.values()) for h in info["valence_histogram"].values()) == len(V)
    assert info["valence_max"] == valence.max()
    assert info["loop_pia"]["can_run"] is True


def test_info_text_lists_the_first_extraordinary_vertices(tmp_path, command):
    V, F = CLI_MESHES["irregular-torus"]()
    src = write_obj(tmp_path / "m.obj", V, F)
    _, _, valence, extra = independent_counts(np.asarray(F), len(V))
    code, stdout, err = command("info", src)
    assert code == 0, err
    rows = {line.split()[0]: line.split()[1:] for line in stdout.splitlines()[-2:]}
    listed = np.flatnonzero(extra)[:16]
    assert rows["vertex"][:16] == [str(i) for i in listed]
    assert rows["vertex"][16:] == ["...", f"({int(extra.sum()) - 16}", "more)"]
    assert rows["valence"] == [str(v) for v in valence[listed]]


def test_info_says_why_loop_pia_cannot_run(tmp_path, command):
    # Two triangles that traverse edge (0, 1) the same way: inconsistent orientation.
    src = write_obj(tmp_path / "flip.obj", np.eye(4, 3), [[0, 1, 2], [0, 1, 3]])
    code, stdout, err = command("info", src)
    assert code == 0, err
    assert "cannot run" in stdout and "orientation" in stdout


# Bad topology written by hand in both text formats, the verdict compared with the
# message of sorpia's own validation (the Python API), not with a text of our own.
MOEBIUS_OFF = """OFF
# the smallest Moebius strip: 5 vertices, faces (i, i+1, i+2) mod 5; each edge (i, i+1)
# is run the same way by its two faces and no choice of orientations can mend all five
5 5 0
1 0 0
0.31 0.95 0.2
-0.81 0.59 -0.2
-0.81 -0.59 0.2
0.31 -0.95 -0.2
3 0 1 2
3 1 2 3
3 2 3 4
3 3 4 0
3 4 0 1
"""

BOWTIE_OBJ = """# two fans around vertex 4 (OBJ index 5), one of three triangles above and one of two
# below, that share only that vertex: a non-manifold ('bowtie') vertex
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
v 0.5 0.5 0
v 0 0 -1
v 1 0 -1
v 1 1 -1
f 5 1 2
f 5 2 3
f 5 3 4
f 5 6 7
f 5 7 8
"""


@pytest.mark.parametrize("name, content, problem, loops", [
    ("moebius.off", MOEBIUS_OFF, "the surface is not orientable", 1),
    # The bowtie's two boundary loops, 0-1-2-3-4 and 4-5-6-7, touch at vertex 4: still two loops.
    ("bowtie.obj", BOWTIE_OBJ, "non-manifold vertex 4:", 2),
], ids=["moebius", "bowtie"])
def test_info_and_fit_name_the_topology_problem_as_the_api_does(name, content, problem, loops, tmp_path,
                                                                 monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    src = tmp_path / name
    src.write_text(content)
    V, F = sorpia.read_mesh(src)
    with pytest.raises(sorpia.MeshError) as refused:
        sorpia.limit_points(V, F)
    expected = str(refused.value)
    assert problem in expected  # the API names the problem (and, for the bowtie, the vertex index)

    code, stdout, err = command("info", src)
    assert code == 0, err  # info describes a mesh Loop PIA cannot run on; not an error
    verdict = [line for line in stdout.splitlines() if line.startswith("Loop PIA")]
    assert len(verdict) == 1 and verdict[0].endswith(f"cannot run: {expected}")
    code, stdout, err = command("info", src, "--json")
    assert code == 0, err
    described = json.loads(stdout)
    assert described["loop_pia"] == {"can_run": False, "reason": expected, "notes": []}
    assert described["genus"] is None  # undetermined for an invalid surface
    n_edges, n_bnd, _, _ = independent_counts(np.asarray(F), len(V))
    assert (described["edges"], described["boundary_edges"], described["boundary_loops"]) == (n_edges, n_bnd, loops)

    code, _, err = command("fit", src, "-o", tmp_path / "c.obj", "--quiet")
    assert_user_error(code, err)
    assert expected in err
    assert not (tmp_path / "c.obj").exists()
