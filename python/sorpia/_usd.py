"""USD files (.usd, .usda, .usdc) for read_mesh and write_mesh, through usd-core
(``pip install sorpia[usd]``): a UsdGeom.Mesh prim's points, faces,
subdivision scheme, boundary rule, OpenSubdiv's tags (UsdGeomMesh holds
exactly them) and texture coordinates.

The names on each side: USD's ``subdivisionScheme`` catmullClark / loop is
sorpia's scheme "catmull-clark" / "loop"; ``interpolateBoundary``
edgeAndCorner / edgeOnly is the boundary rule "edge-and-corner" / "edge-only";
``creaseIndices``/``creaseLengths``/``creaseSharpnesses`` (chains) are the
``creases`` (edges); ``cornerIndices``/``cornerSharpnesses`` the ``corners``;
``holeIndices`` the ``holes``; the ``st`` primvar the ``uvs``.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path

import numpy as np

from . import _core
from ._mesh import FaceVarying
from ._validate import Polygons
from .errors import MeshError, MeshFileError, ParameterError, UsdWarning

USD_SUFFIXES = (".usd", ".usda", ".usdc")
# USD's tokens and sorpia's names, both ways.
SCHEMES = {"catmullClark": "catmull-clark", "loop": "loop"}
BOUNDARIES = {"edgeAndCorner": "edge-and-corner", "edgeOnly": "edge-only"}
# The values USD's schema allows for each rule token sorpia reads (UsdGeomMesh).
TOKENS = {
    "subdivisionScheme": ("catmullClark", "loop", "bilinear", "none"),
    "interpolateBoundary": ("none", "edgeAndCorner", "edgeOnly"),
    "triangleSubdivisionRule": ("catmullClark", "smooth"),
}
# Why sorpia refuses the values it has no rule for.
REFUSED = {
    ("subdivisionScheme", "bilinear"): "sorpia fits Loop and Catmull-Clark limit surfaces; a bilinear mesh is its "
                                       "own surface (nothing to fit)",
    ("subdivisionScheme", "none"): "the mesh is not a subdivision surface (a polygon mesh: nothing to fit)",
    ("interpolateBoundary", "none"): "sorpia has the boundary rules edge-only and edge-and-corner; 'none' "
                                     "(boundary faces not drawn) it does not have",
    ("triangleSubdivisionRule", "smooth"): "sorpia's Catmull-Clark triangles follow the catmullClark rule; "
                                           "'smooth' it does not have",
}
# The texture coordinates' primvar: USD's convention (UsdPreviewSurface reads "st").
UV_PRIMVAR = "st"


def is_usd(path) -> bool:
    return Path(os.fsdecode(path)).suffix.lower() in USD_SUFFIXES


def _pxr(path):
    """usd-core's modules, or a MeshFileError naming the extra that installs them."""
    try:
        from pxr import Sdf, Usd, UsdGeom, Vt
    except ImportError:
        raise MeshFileError(f"{os.fsdecode(path)}: USD files need usd-core, which is not installed: "
                            "pip install 'sorpia[usd]'") from None
    return Usd, UsdGeom, Sdf, Vt


def _open(path):
    Usd, UsdGeom, _, _ = _pxr(path)
    name = os.fsdecode(path)
    if not Path(name).exists():
        raise MeshFileError(f"{name}: no such file")
    try:
        stage = Usd.Stage.Open(name)
    except Exception as exc:  # pxr.Tf.ErrorException: not a USD file, a bad layer
        raise MeshFileError(f"{name}: not a readable USD stage: {str(exc).strip().splitlines()[-1]}") from None
    if stage is None:
        raise MeshFileError(f"{name}: not a readable USD stage")
    return stage


def mesh_paths(stage) -> list[str]:
    """The paths of the stage's UsdGeom.Mesh prims, in traversal order."""
    from pxr import UsdGeom

    return [str(p.GetPath()) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]


def _mesh(stage, path, prim):
    """The UsdGeom.Mesh the caller asked for: `prim`, else the stage's only mesh."""
    from pxr import UsdGeom

    name = os.fsdecode(path)
    if prim is not None:
        p = stage.GetPrimAtPath(str(prim))
        if not p or not p.IsA(UsdGeom.Mesh):
            found = mesh_paths(stage)
            raise MeshFileError(f"{name}: prim {prim} is {'not a Mesh' if p else 'not on the stage'}; its meshes: "
                                f"{', '.join(found) or 'none'}")
        return UsdGeom.Mesh(p)
    found = mesh_paths(stage)
    if not found:
        raise MeshFileError(f"{name}: the stage has no Mesh prim")
    if len(found) > 1:
        raise MeshFileError(f"{name}: the stage has {len(found)} Mesh prims ({', '.join(found)}): name the one to "
                            "read (prim=..., --prim PATH)")
    return UsdGeom.Mesh(stage.GetPrimAtPath(found[0]))


def _get(attr, where: str, time=None):
    """attr.Get(time) (the default time when None); a value usd-core cannot
    read (a corrupted .usdc: pxr's Tf.ErrorException from inside Get, a
    decompression error) is a MeshFileError naming the file, prim and
    attribute."""
    from pxr import Usd

    try:
        return attr.Get(Usd.TimeCode.Default() if time is None else time)
    except Exception as exc:  # pxr.Tf.ErrorException (a RuntimeError) and the like: the file's bytes are bad
        raise MeshFileError(f"{where}: {attr.GetName()} cannot be read (a damaged file?): "
                            f"{_last_line(exc)}") from None


def _last_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[-1].strip() if text else type(exc).__name__


def _token(mesh, name: str, where: str) -> str:
    """A uniform token attribute's value (its schema fallback when not
    authored): refused by name where sorpia has no rule for it (REFUSED), or
    where it is not one of the schema's values at all (TOKENS: a misspelt
    or foreign token, e.g. "Loop")."""
    value = str(_get(mesh.GetPrim().GetAttribute(name), where))
    if (name, value) in REFUSED:
        raise MeshFileError(f"{where}: {name} = {value} is refused: {REFUSED[name, value]}")
    if value not in TOKENS[name]:
        raise MeshFileError(f"{where}: {name} = {value} is not a value USD defines (it has "
                            f"{', '.join(TOKENS[name])})")
    return value


def _array(attr, dtype, where: str, warn_time: bool = False) -> np.ndarray:
    """An array attribute's value at the default time (empty when not authored).
    Time-sampled with no default value: the first sample, with a UsdWarning
    saying so (and with one as well, only when `warn_time`). A value that
    cannot be read, or is not an array of numbers, is a MeshFileError naming
    the attribute."""
    value = _get(attr, where)
    try:
        samples = attr.GetTimeSamples()
    except Exception as exc:  # pxr.Tf.ErrorException: a damaged file
        raise MeshFileError(f"{where}: {attr.GetName()} cannot be read (a damaged file?): {_last_line(exc)}") from None
    if value is None and samples:
        value = _get(attr, where, samples[0])
        warnings.warn(f"{where}: {attr.GetName()} has {len(samples)} time samples and no default value: read "
                      f"the sample at time {samples[0]:g}", UsdWarning, stacklevel=5)
    elif samples and warn_time:
        warnings.warn(f"{where}: {attr.GetName()} has {len(samples)} time samples: read the default value",
                      UsdWarning, stacklevel=5)
    if value is None:
        return np.zeros(0, dtype=dtype)
    try:
        return np.array(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise MeshFileError(f"{where}: {attr.GetName()} is not an array of numbers ({exc})") from None


def read_usd(path, *, prim=None, tags: bool = False, attributes: bool = False):
    """read_mesh for a USD file: (vertices, faces, tags dict or None,
    attributes dict or None, scheme). The scheme (sorpia's name) is read
    always; a value sorpia has no rule for is refused only with `tags`.
    What usd-core itself cannot read (pxr's Tf.ErrorException, a
    RuntimeError, anywhere on the stage of a damaged file) is a
    MeshFileError naming the file."""
    _pxr(path)
    try:
        return _read_usd(path, prim, tags, attributes)
    except RuntimeError as exc:
        raise MeshFileError(f"{os.fsdecode(path)}: usd-core cannot read the stage (a damaged file?): "
                            f"{_last_line(exc)}") from None


def _read_usd(path, prim, tags: bool, attributes: bool):
    _, UsdGeom, _, Vt = _pxr(path)

    name = os.fsdecode(path)
    stage = _open(path)
    mesh = _mesh(stage, path, prim)
    where = f"{name}: {mesh.GetPath()}"
    vertices = _array(mesh.GetPointsAttr(), np.float64, where, warn_time=True).reshape(-1, 3)
    counts = _array(mesh.GetFaceVertexCountsAttr(), np.int64, where)
    indices = _array(mesh.GetFaceVertexIndicesAttr(), np.int64, where)
    if not len(vertices) or not len(counts):
        raise MeshFileError(f"{where}: no {'points' if not len(vertices) else 'faces'}")
    if not np.isfinite(vertices).all():
        raise MeshFileError(f"{where}: point {int(np.flatnonzero(~np.isfinite(vertices).all(axis=1))[0])} is not "
                            "finite")
    ok, reason = UsdGeom.Mesh.ValidateTopology(Vt.IntArray(indices.tolist()), Vt.IntArray(counts.tolist()),
                                               len(vertices))
    if not ok:
        raise MeshFileError(f"{where}: invalid topology: {reason}")
    if (counts < 3).any():
        f = int(np.flatnonzero(counts < 3)[0])
        raise MeshFileError(f"{where}: face {f} has {counts[f]} vertices (a face needs 3 or more)")
    counts, indices = counts.astype(np.int32), indices.astype(np.int32)
    faces = indices.reshape(len(counts), -1) if (counts == counts[0]).all() else Polygons(counts, indices)
    scheme_token = str(_get(mesh.GetSubdivisionSchemeAttr(), where))
    tag_dict = _read_tags(mesh, where, len(counts)) if tags else None
    attribute_dict = _read_attributes(mesh, where, counts, indices, len(vertices)) if attributes else None
    return vertices, faces, tag_dict, attribute_dict, SCHEMES.get(scheme_token, scheme_token)


def _read_tags(mesh, where: str, n_faces: int) -> dict:
    scheme = SCHEMES[_token(mesh, "subdivisionScheme", where)]
    out: dict = {"scheme": scheme}
    if scheme == "catmull-clark":
        _token(mesh, "triangleSubdivisionRule", where)
    out["boundary"] = BOUNDARIES[_token(mesh, "interpolateBoundary", where)]
    chain = _array(mesh.GetCreaseIndicesAttr(), np.int64, where)
    lengths = _array(mesh.GetCreaseLengthsAttr(), np.int64, where)
    sharpness = _array(mesh.GetCreaseSharpnessesAttr(), np.float64, where)
    if len(chain) or len(lengths) or len(sharpness):
        out["creases"] = _crease_edges(chain, lengths, sharpness, where)
    corners = _array(mesh.GetCornerIndicesAttr(), np.int64, where)
    corner_sharpness = _array(mesh.GetCornerSharpnessesAttr(), np.float64, where)
    if len(corners) != len(corner_sharpness):
        raise MeshFileError(f"{where}: cornerIndices has {len(corners)} values and cornerSharpnesses "
                            f"{len(corner_sharpness)}: one sharpness per corner")
    if len(corners):
        out["corners"] = (corners.astype(np.int32), corner_sharpness)
    holes = _array(mesh.GetHoleIndicesAttr(), np.int64, where)
    if len(holes):
        out["holes"] = holes.astype(np.int32)
    return out


def _crease_edges(chain, lengths, sharpness, where: str):
    """USD's creases (chains of creaseLengths vertices in creaseIndices, one
    sharpness per crease or per crease edge) as sorpia's (edges (k, 2), sharpness (k,))."""
    if (lengths < 2).any():
        c = int(np.flatnonzero(lengths < 2)[0])
        raise MeshFileError(f"{where}: crease {c} has creaseLengths {lengths[c]} (a crease is 2 or more vertices)")
    if lengths.sum() != len(chain):
        raise MeshFileError(f"{where}: creaseLengths add up to {lengths.sum()} but creaseIndices has {len(chain)} "
                            "values")
    n_edges = int((lengths - 1).sum())
    starts = np.repeat(np.cumsum(lengths) - lengths, lengths - 1)
    within = np.arange(n_edges) - np.repeat(np.cumsum(lengths - 1) - (lengths - 1), lengths - 1)
    first = starts + within
    edges = np.stack([chain[first], chain[first + 1]], axis=1).astype(np.int32)
    if len(sharpness) == len(lengths):
        per_edge = np.repeat(sharpness, lengths - 1)
    elif len(sharpness) == n_edges:
        per_edge = sharpness
    else:
        raise MeshFileError(f"{where}: creaseSharpnesses has {len(sharpness)} values: one per crease "
                            f"({len(lengths)}) or one per crease edge ({n_edges})")
    return edges, np.ascontiguousarray(per_edge, dtype=np.float64)


def _read_attributes(mesh, where: str, counts, indices, n_points: int) -> dict:
    """The texture coordinates (the ``st`` primvar) and normals, each a FaceVarying; a
    primvar sorpia cannot carry (constant or uniform) is left out with a UsdWarning."""
    from pxr import UsdGeom

    out = {}
    api = UsdGeom.PrimvarsAPI(mesh.GetPrim())
    # (key, values attribute, interpolation, indices attribute or None) of each channel the mesh has.
    channels = []
    for key, name in (("uvs", UV_PRIMVAR), ("normals", "normals")):
        pv = api.GetPrimvar(name)
        if pv and pv.HasAuthoredValue():
            channels.append((key, pv.GetAttr(), pv.GetInterpolation(), pv.GetIndicesAttr() if pv.IsIndexed()
                             else None))
    if not any(key == "normals" for key, *_ in channels) and mesh.GetNormalsAttr().HasAuthoredValue():
        channels.append(("normals", mesh.GetNormalsAttr(), mesh.GetNormalsInterpolation(), None))
    for key, attr, interpolation, indices_attr in channels:
        label = f"{where}: {attr.GetName()}"
        values = _array(attr, np.float64, label)
        values = values.reshape(len(values), -1)
        index = _array(indices_attr, np.int64, label) if indices_attr is not None else np.arange(len(values))
        if interpolation == UsdGeom.Tokens.faceVarying:
            corner = index
        elif interpolation in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying):
            if len(index) != n_points:
                raise MeshFileError(f"{label}: {interpolation} values for {len(index)} points; the mesh has "
                                    f"{n_points}")
            corner = index[indices]
        else:
            warnings.warn(f"{label}: left out: {interpolation} interpolation (sorpia carries values per vertex or "
                          "per face corner)", UsdWarning, stacklevel=4)
            continue
        if len(corner) != len(indices):
            raise MeshFileError(f"{label}: {len(corner)} face-varying values; the faces have {len(indices)} "
                                "corners")
        if len(corner) and (corner.min() < 0 or corner.max() >= len(values)):
            bad = int(np.flatnonzero((corner < 0) | (corner >= len(values)))[0])
            raise MeshFileError(f"{label}: corner {bad} names value {corner[bad]}; there are {len(values)}")
        out[key] = FaceVarying(np.ascontiguousarray(values), np.ascontiguousarray(corner, dtype=np.int32))
    return out


def write_usd(path, vertices, counts, indices, *, scheme=None, tags: dict, uvs=None, normals=None,
              prim=None, template=None) -> None:
    """write_mesh for a USD file (see there); `tags` holds the checked creases,
    corners, holes and boundary (sorpia's forms) given; `template` a USD file
    whose stage is copied with this mesh written into its prim."""
    Usd, UsdGeom, Sdf, Vt = _pxr(path)
    name = os.fsdecode(path)
    check_float32(vertices, "USD")
    if template is not None:
        stage = _open(template)
        mesh = _mesh(stage, template, prim)
        where = f"{os.fsdecode(template)}: {mesh.GetPath()}"
        _refit_primvars(mesh, counts, indices, len(vertices), where, keep={UV_PRIMVAR} if uvs is not None else set())
    else:
        stage = Usd.Stage.CreateInMemory()
        prim_path = Sdf.Path(str(prim) if prim is not None else "/Mesh")
        if not prim_path.IsAbsolutePath() or not prim_path.IsPrimPath():
            raise ParameterError(f"prim must be an absolute prim path such as /Mesh, got {prim!r}")
        mesh = UsdGeom.Mesh.Define(stage, prim_path)
        for parent in prim_path.GetPrefixes()[:-1]:
            UsdGeom.Xform.Define(stage, parent)
        stage.SetDefaultPrim(stage.GetPrimAtPath(prim_path.GetPrefixes()[0]))
    points = Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(vertices, dtype=np.float32))
    # The fitted cage is one shape: time samples (of another pose) would override it.
    mesh.GetPointsAttr().Clear()
    mesh.CreatePointsAttr(points)
    mesh.CreateExtentAttr(UsdGeom.PointBased.ComputeExtent(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(counts, dtype=np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(indices, dtype=np.int32)))
    if scheme is not None:
        mesh.CreateSubdivisionSchemeAttr({v: k for k, v in SCHEMES.items()}[scheme])
    if "boundary" in tags:
        mesh.CreateInterpolateBoundaryAttr({v: k for k, v in BOUNDARIES.items()}[tags["boundary"]])
    _write_tags(mesh, tags, Vt)
    for key, channel, role in (("uvs", uvs, "uv"), ("normals", normals, "normal")):
        if channel is None:
            continue
        values, corner = channel
        if key == "uvs":
            type_name = {1: Sdf.ValueTypeNames.DoubleArray, 2: Sdf.ValueTypeNames.TexCoord2dArray,
                         3: Sdf.ValueTypeNames.TexCoord3dArray}[values.shape[1]]
            pv = UsdGeom.PrimvarsAPI(mesh.GetPrim()).CreatePrimvar(UV_PRIMVAR, type_name,
                                                                  UsdGeom.Tokens.faceVarying)
        else:
            pv = UsdGeom.PrimvarsAPI(mesh.GetPrim()).CreatePrimvar("normals", Sdf.ValueTypeNames.Normal3fArray,
                                                                  UsdGeom.Tokens.faceVarying)
        pv.Set(values if values.shape[1] > 1 else values[:, 0])
        pv.SetIndices(Vt.IntArray.FromNumpy(np.ascontiguousarray(corner, dtype=np.int32)))
    _export_atomically(stage, name)


def _write_tags(mesh, tags: dict, Vt) -> None:
    """The creases (each edge a crease of 2 vertices, its own sharpness), corners and holes; every tag
    attribute is authored (empty when the mesh has none), so a template's old tags never stay."""
    edges, sharpness = tags.get("creases", (np.zeros((0, 2), np.int32), np.zeros(0)))
    mesh.CreateCreaseIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(edges, dtype=np.int32).reshape(-1)))
    mesh.CreateCreaseLengthsAttr(Vt.IntArray.FromNumpy(np.full(len(edges), 2, dtype=np.int32)))
    mesh.CreateCreaseSharpnessesAttr(Vt.FloatArray.FromNumpy(np.asarray(sharpness, dtype=np.float32)))
    vertices, corner_sharpness = tags.get("corners", (np.zeros(0, np.int32), np.zeros(0)))
    mesh.CreateCornerIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(vertices, dtype=np.int32)))
    mesh.CreateCornerSharpnessesAttr(Vt.FloatArray.FromNumpy(np.asarray(corner_sharpness, dtype=np.float32)))
    mesh.CreateHoleIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(tags.get("holes", np.zeros(0)), dtype=np.int32)))


def _refit_primvars(mesh, counts, indices, n_points: int, where: str, keep: set) -> None:
    """When the faces written differ from the template mesh's (--triangulate,
    --repair, a split), the mesh's per-point, per-face and per-corner primvars
    no longer fit: they are blocked, with a UsdWarning naming them."""
    from pxr import Usd, UsdGeom

    old_counts = mesh.GetFaceVertexCountsAttr().Get(Usd.TimeCode.Default())
    old_indices = mesh.GetFaceVertexIndicesAttr().Get(Usd.TimeCode.Default())
    old_points = mesh.GetPointsAttr().Get(Usd.TimeCode.Default())
    if (old_counts is not None and old_indices is not None and np.array_equal(np.array(old_counts), counts)
            and np.array_equal(np.array(old_indices), indices)
            and (old_points is None or len(old_points) == n_points)):
        return
    blocked = []
    for pv in UsdGeom.PrimvarsAPI(mesh.GetPrim()).GetPrimvarsWithAuthoredValues():
        if pv.GetPrimvarName() in keep or pv.GetInterpolation() == UsdGeom.Tokens.constant:
            continue
        pv.GetAttr().Block()
        if pv.IsIndexed():
            pv.GetIndicesAttr().Block()
        blocked.append(str(pv.GetPrimvarName()))
    if mesh.GetNormalsAttr().HasAuthoredValue():
        mesh.GetNormalsAttr().Block()
        blocked.append("normals")
    if blocked:
        warnings.warn(f"{where}: the faces written differ from the stage's, so its primvars {', '.join(blocked)} "
                      "no longer fit them: blocked in the output", UsdWarning, stacklevel=4)


def _export_atomically(stage, name: str) -> None:
    """The stage's root layer exported to a temporary folder (the same suffix:
    USD picks the format by it), then its bytes written over `name` by the
    core's atomic writer (sorpia::write_file_atomic: a temporary file beside
    `name`, the mode a plain open() gives, or the replaced file's, fsync,
    rename), as every other output is written; the temporary folder is
    removed however the write ends."""
    with tempfile.TemporaryDirectory(prefix="sorpia-usd-") as folder:
        tmp = os.path.join(folder, "stage" + Path(name).suffix)
        if not stage.GetRootLayer().Export(tmp):
            raise MeshFileError(f"{name}: USD could not write the file")
        with open(tmp, "rb") as f:
            data = f.read()
    _core.write_file_atomic(os.fsencode(name), data)


def check_float32(vertices, what: str = "USD") -> None:
    """Refuse coordinates a float32 file cannot hold (beyond float32's
    largest finite value, 3.4e38), as the STL writer refuses them: a
    MeshError naming the first such vertex."""
    v = np.asarray(vertices, dtype=np.float64)
    beyond = np.abs(v) > float(np.finfo(np.float32).max)
    if beyond.any():
        i = int(np.flatnonzero(beyond.any(axis=1))[0])
        x = float(v[i][np.flatnonzero(beyond[i])[0]])
        raise MeshError(f"write_mesh: vertex {i} has coordinate {x!r}, beyond float32, which {what} stores")
