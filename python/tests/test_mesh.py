"""Meshes as arrays, the quality report, and the round trip through meshio."""
import numpy as np
import pytest

import bigstep


def test_mesh_box_and_quality():
    m, q = bigstep.mesh("box:3x2x2:1.5x1x1")
    assert m.n_tets == 3 * 2 * 2 * 6 and m.vertices.shape == (4 * 3 * 3, 3)
    assert q["n_inverted"] == 0 and 0 < q["dihedral_min"] <= q["dihedral_max"] < 180
    assert {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax", "body"} <= set(m.groups)
    assert m.groups["body"].dim == 3 and len(m.groups["body"].elems) == m.n_tets
    assert m.faces.shape[1] == 3 and len(m.face_tet) == len(m.faces)
    m2, _ = bigstep.mesh("box:3x2x2:1.5x1x1", refine=1)
    assert m2.n_tets == 8 * m.n_tets
    assert m.quality() == q


def test_mesh_from_geometry(src):
    import os
    geo = [os.path.join(src, "data", "meshes", f) for f in ("sphere.off", "sphere.stl")]
    geo = [g for g in geo if os.path.exists(g)]
    if not geo:
        pytest.skip("no sphere surface in data/meshes")
    m, q = bigstep.mesh(geo[0], size=0.3, min_dihedral=5)
    assert m.n_tets > 0 and q["dihedral_min"] >= 5
    with pytest.raises(bigstep.InputError, match="dihedral"):
        bigstep.mesh(geo[0], size=0.3, min_dihedral=60)


def test_meshio_round_trip(tmp_path):
    meshio = pytest.importorskip("meshio")
    m, _ = bigstep.mesh("box:3x2x2:1.5x1x1")
    mm = m.to_meshio()
    assert isinstance(mm, meshio.Mesh)
    back = bigstep.Mesh.from_meshio(mm)
    assert np.array_equal(back.vertices, m.vertices)
    assert np.array_equal(back.tets, m.tets)
    assert np.array_equal(back.material, m.material)
    assert [(g.name, g.dim, g.tag) for g in back.group_list] == [(g.name, g.dim, g.tag) for g in m.group_list]
    for g, h in zip(back.group_list, m.group_list):
        assert np.array_equal(g.elems, h.elems) and np.array_equal(g.vertices, h.vertices)
    # through a file meshio writes and reads (Gmsh 2.2, which keeps the physical groups)
    p = str(tmp_path / "m.msh")
    meshio.write(p, mm, file_format="gmsh22", binary=False)
    back2 = bigstep.Mesh.from_meshio(meshio.read(p))
    assert np.array_equal(back2.vertices, m.vertices) and np.array_equal(back2.tets, m.tets)
    assert {g.name: len(g.elems) for g in back2.group_list} == {g.name: len(g.elems) for g in m.group_list}
    # and the library reads what bigstep writes
    m.write(str(tmp_path / "b.msh"))
    again, _ = bigstep.mesh(str(tmp_path / "b.msh"))
    assert again.n_tets == m.n_tets and set(again.groups) == set(m.groups)


def test_simulation_on_a_python_mesh(tmp_path):
    m, _ = bigstep.mesh("box:4x1x1:1x0.25x0.25")
    p = str(tmp_path / "beam.msh")
    m.write(p)
    d = {"time": {"fps": 24, "frames": 2, "steps_per_frame": 1}, "solver": {"mode": "static"},
         "bodies": [{"mesh": p, "material": {"model": "neo_hookean", "youngs": 1e6, "poisson": 0.3,
                                            "density": 1000},
                     "scripted": [{"group": "xmin", "fixed": True}]}], "output": {"dir": ""}}
    with bigstep.Simulation(d) as sim:
        sim.statics()
        assert sim.x[:, 1].min() < 0
