"""Meshes as NumPy arrays: read or made by the library (bs_mesh_load), their
quality report, and conversion to and from meshio.Mesh."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from ._bigstep import ffi, lib
from ._errors import InputError, check, new_error

__all__ = ["Group", "Mesh", "mesh", "quality_dict"]

_CELL_TYPE = {0: "vertex", 1: "line", 2: "triangle", 3: "tetra"}
_DIM_OF = {"vertex": 0, "line": 1, "triangle": 2, "tetra": 3}


@dataclass
class Group:
    """A physical group of a mesh (Gmsh's), keyed by (dim, tag), with a name.

    elems: for dim < 3, (m, dim + 1) vertex indices per element; for dim 3,
    the (m,) indices of its tets. vertices: the sorted vertices it touches.
    """
    name: str
    dim: int
    tag: int
    elems: np.ndarray
    vertices: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))


def _arr(ptr, n, ctype, dtype, shape=None) -> np.ndarray:
    """A copy of n values of C array ptr."""
    if n <= 0 or ptr == ffi.NULL:
        a = np.zeros(0, dtype)
    else:
        a = np.frombuffer(ffi.buffer(ptr, n * ffi.sizeof(ctype)), dtype=dtype).copy()
    return a.reshape(shape) if shape is not None else a


class Mesh:
    """A first-order tetrahedral mesh (copied into NumPy arrays).

    Attributes:
        vertices: (n, 3) float64 positions (m).
        tets: (m, 4) int32, positively oriented.
        material: (m,) int32, the tag of each tet's 3-D group (0: none).
        faces: (k, 3) int32 boundary triangles, outward.
        face_tet: (k,) the tet of each boundary face.
        boundary: (k,) the tag of each face's 2-D group (0: none).
        groups: {name: Group}; when names repeat, the first by (dim, tag).
        group_list: every Group, in (dim, tag) order.
    """

    def __init__(self, vertices, tets, groups: Optional[List[Group]] = None):
        """A mesh from arrays: derived by the library (bs_mesh_create:
        boundary, orientation; unused vertices dropped). Raises InputError
        with the library's message for bad input."""
        m = _create_c(vertices, tets, groups or [])
        try:
            self._from_c(m[0])
        finally:
            lib.bs_mesh_destroy(m)

    @classmethod
    def _wrap(cls, cmesh) -> "Mesh":
        self = cls.__new__(cls)
        self._from_c(cmesh)
        return self

    def _from_c(self, m) -> None:
        self.vertices = _arr(m.x, 3 * m.n_vertices, "double", np.float64, (-1, 3))
        self.tets = _arr(m.tets, 4 * m.n_tets, "int32_t", np.int32, (-1, 4))
        self.material = _arr(m.material, m.n_tets, "int32_t", np.int32)
        self.faces = _arr(m.faces, 3 * m.n_faces, "int32_t", np.int32, (-1, 3))
        self.face_tet = _arr(m.face_tet, m.n_faces, "int32_t", np.int32)
        self.boundary = _arr(m.boundary, m.n_faces, "int32_t", np.int32)
        self.group_list: List[Group] = []
        for i in range(m.n_groups):
            g = m.groups[i]
            per = 1 if g.dim == 3 else g.dim + 1
            elems = _arr(g.elems, per * g.n_elems, "int32_t", np.int32)
            if g.dim < 3:
                elems = elems.reshape(-1, per)
            self.group_list.append(Group(ffi.string(g.name).decode("utf-8", "replace"), int(g.dim), int(g.tag), elems,
                                         _arr(g.vertices, g.n_vertices, "int32_t", np.int32)))
        self.groups: Dict[str, Group] = {}
        for g in self.group_list:
            self.groups.setdefault(g.name, g)

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self.vertices.shape[0])

    @property
    def n_tets(self) -> int:
        """Number of tets."""
        return int(self.tets.shape[0])

    def quality(self, x=None) -> Dict[str, float]:
        """The quality report (bs_mesh_quality_compute) at positions x
        (default: the rest positions): volumes, dihedral angles (degrees),
        radius ratios, counts of inverted, degenerate and sliver tets."""
        m = _create_c(self.vertices, self.tets, self.group_list)
        try:
            q = ffi.new("bs_mesh_quality *")
            xp = ffi.NULL
            if x is not None:
                xa = np.ascontiguousarray(x, dtype=np.float64)
                if xa.shape != self.vertices.shape:
                    raise ValueError("x must have shape %s, got %s" % (self.vertices.shape, xa.shape))
                xp = ffi.cast("double *", ffi.from_buffer(xa))
            lib.bs_mesh_quality_compute(m[0], xp, q)
            return quality_dict(q)
        finally:
            lib.bs_mesh_destroy(m)

    def write(self, path: str) -> None:
        """Writes the mesh: .msh (Gmsh 4.1, with the groups) or .vtu."""
        m = _create_c(self.vertices, self.tets, self.group_list)
        err = new_error()
        try:
            p = os.fspath(path).encode()
            if p.endswith(b".vtu"):
                check(lib.bs_mesh_write_vtu(m[0], ffi.NULL, p, err), err)
            else:
                check(lib.bs_mesh_write_msh(m[0], ffi.NULL, p, err), err)
        finally:
            lib.bs_mesh_destroy(m)

    # ---- meshio ---------------------------------------------------------
    def to_meshio(self):
        """A meshio.Mesh: the tets as a "tetra" block, then one block per
        group of dimension < 3 ("triangle", "line", "vertex"); the groups as
        Gmsh physical groups: cell_data["gmsh:physical"] (the tet block holds
        each tet's 3-D group tag, i.e. `material`) and field_data
        {name: [tag, dim]}, as meshio's Gmsh reader gives them."""
        import meshio
        cells = [("tetra", self.tets.astype(np.int64))]
        phys = [self.material.astype(np.int64)]
        geo = [self.material.astype(np.int64)]
        field_data = {}
        for g in self.group_list:
            field_data[g.name] = np.array([g.tag, g.dim])
            if g.dim == 3:
                continue
            e = g.elems.reshape(-1, g.dim + 1).astype(np.int64)
            cells.append((_CELL_TYPE[g.dim], e))
            phys.append(np.full(len(e), g.tag, np.int64))
            geo.append(np.full(len(e), g.tag, np.int64))
        return meshio.Mesh(self.vertices.copy(), cells, cell_data={"gmsh:physical": phys, "gmsh:geometrical": geo},
                           field_data=field_data)

    @classmethod
    def from_meshio(cls, m) -> "Mesh":
        """A Mesh from a meshio.Mesh with "tetra" cells; Gmsh physical groups
        (cell_data "gmsh:physical" and field_data {name: [tag, dim]}) become
        groups. Other cell types carry only groups (3-D elements other than
        tets are an InputError)."""
        tets = []
        groups: Dict[Tuple[int, int], List[np.ndarray]] = {}
        phys = m.cell_data.get("gmsh:physical")
        offset = 0
        for bi, block in enumerate(m.cells):
            ctype, data = block.type, np.asarray(block.data)
            if ctype not in _DIM_OF:
                raise InputError("meshio mesh: cells of type %r are not simulated (first-order tets only)" % ctype)
            dim = _DIM_OF[ctype]
            tags = np.asarray(phys[bi]) if phys is not None else np.zeros(len(data), np.int64)
            if dim == 3:
                for t in np.unique(tags[tags > 0]):
                    groups.setdefault((3, int(t)), []).append(np.nonzero(tags == t)[0] + offset)
                tets.append(data)
                offset += len(data)
            else:
                for t in np.unique(tags[tags > 0]):
                    groups.setdefault((dim, int(t)), []).append(data[tags == t])
        if not tets:
            raise InputError("meshio mesh: no tetra cells")
        names = {}
        for name, v in (m.field_data or {}).items():
            v = np.asarray(v).ravel()
            if len(v) >= 2:
                names[(int(v[1]), int(v[0]))] = name
        glist = []
        for (dim, tag) in sorted(groups):
            elems = np.concatenate(groups[(dim, tag)])
            glist.append(Group(names.get((dim, tag), ""), dim, tag, elems))
        return cls(np.asarray(m.points, dtype=np.float64)[:, :3], np.concatenate(tets), glist)

    def __repr__(self) -> str:
        return "<bigstep.Mesh: %d vertices, %d tets, %d boundary faces, groups %s>" % (
            self.n_vertices, self.n_tets, len(self.faces), sorted(self.groups))


def quality_dict(q) -> Dict[str, float]:
    return {k: (int(getattr(q, k)) if k.startswith("n_") else float(getattr(q, k)))
            for k in ("vol_min", "vol_max", "dihedral_min", "dihedral_max", "radius_ratio_min",
                      "radius_ratio_mean", "n_inverted", "n_degenerate", "n_sliver")}


def _create_c(vertices, tets, groups: List[Group]):
    """A bs_mesh ** (the caller destroys it) from arrays, through bs_mesh_create."""
    x = np.ascontiguousarray(vertices, dtype=np.float64)
    t = np.asarray(tets)
    if x.ndim != 2 or x.shape[1] != 3:
        raise InputError("vertices must have shape (n, 3), got %s" % (x.shape,))
    if t.ndim != 2 or t.shape[1] != 4:
        raise InputError("tets must have shape (m, 4), got %s" % (t.shape,))
    if len(x) >= 2**31 or len(t) >= 2**31:
        raise InputError("too many vertices or tets for int32 indices")
    if t.size and (t.min() < -2**31 or t.max() >= 2**31):
        raise InputError("a tet index is outside int32")
    t = np.ascontiguousarray(t, dtype=np.int32)
    keep = [x, t]
    cg = ffi.new("bs_group[]", max(1, len(groups)))
    for i, g in enumerate(groups):
        if g.dim not in (0, 1, 2, 3):
            raise InputError("group %r: dim must be 0..3, got %r" % (g.name, g.dim))
        per = 1 if g.dim == 3 else g.dim + 1
        e = np.asarray(g.elems)
        if e.size and (e.min() < -2**31 or e.max() >= 2**31):
            raise InputError("group %r: an index is outside int32" % (g.name,))
        e = np.ascontiguousarray(e, dtype=np.int32).ravel()
        if e.size % per:
            raise InputError("group %r: %d indices are not elements of %d" % (g.name, e.size, per))
        name = ffi.new("char[]", str(g.name).encode())
        keep += [e, name]
        cg[i].dim, cg[i].tag, cg[i].name = int(g.dim), int(g.tag), name
        cg[i].n_elems = e.size // per
        cg[i].elems = ffi.cast("int32_t *", ffi.from_buffer(e)) if e.size else ffi.NULL
        cg[i].n_vertices, cg[i].vertices = 0, ffi.NULL
    out = ffi.new("bs_mesh **")
    err = new_error()
    st = lib.bs_mesh_create(len(x), ffi.cast("double *", ffi.from_buffer(x)) if x.size else ffi.NULL, len(t),
                            ffi.cast("int32_t *", ffi.from_buffer(t)) if t.size else ffi.NULL, len(groups),
                            cg if groups else ffi.NULL, out, err)
    check(st, err, InputError)
    del keep
    return out


def mesh(path: str, size: float = 0.0, min_dihedral: float = 0.0, *, refine: int = 0, close_holes: bool = False,
         mesher: str = "auto", merge_coincident: bool = False) -> Tuple[Mesh, Dict[str, float]]:
    """Reads or makes a mesh (bs_mesh_load) and returns ``(mesh, quality)``.

    path: a .msh file (taken as is), a geometry (.geo, .step/.stp, .brep,
    .iges) or a closed surface (.stl, .off, .obj, .ply) meshed at `size`
    (m; 0: the file's own), or a box spec "box:NX[xNYxNZ][:LX[xLYxLZ]]".
    min_dihedral: the quality gate (degrees) for meshes bigstep makes
    (0: the library's default, 10; < 0: none); a mesh under it is refused
    with the library's message (InputError). refine: uniform refinements.
    quality: the dict of :meth:`Mesh.quality`.
    """
    o = ffi.new("bs_mesh_read_opts *")
    o.size = float(size)
    o.min_dihedral = float(min_dihedral)
    if not (isinstance(refine, int) and 0 <= refine <= 8):
        raise InputError("refine must be an int in 0..8, got %r" % (refine,))
    o.refine = refine
    o.close_holes = int(bool(close_holes))
    o.merge_coincident = int(bool(merge_coincident))
    mp = ffi.new("int *")
    if lib.bs_mesh_parse_mesher(str(mesher).encode(), mp):
        raise InputError("mesher must be auto, cgal or remesh, got %r" % (mesher,))
    o.surface_mesher = mp[0]
    out = ffi.new("bs_mesh **")
    err = new_error()
    check(lib.bs_mesh_load(os.fspath(path).encode(), o, out, err), err, InputError)
    try:
        m = Mesh._wrap(out[0])
        q = ffi.new("bs_mesh_quality *")
        lib.bs_mesh_quality_compute(out[0], ffi.NULL, q)
        return m, quality_dict(q)
    finally:
        lib.bs_mesh_destroy(out)
