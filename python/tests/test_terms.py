"""Energy terms written in Python: derivatives against finite differences,
and examples/02_spring's spring term written in Python against the C one."""
import json
import os
import re
import subprocess

import numpy as np
import pytest

import bigstep
from conftest import cube_scene, material


class Spring(bigstep.PythonTerm):
    """examples/02_spring's term, E = k/2 sum_{v in G} |x_v - (X_v + d)|^2,
    with the C example's arithmetic (the same operations in the same order)."""
    name = "spring"

    def __init__(self, vertices, rest, k, d):
        self.vtx, self.rest, self.k, self.d = np.asarray(vertices), np.array(rest[vertices]), k, np.array(d)

    def value(self, x):
        r = x[self.vtx] - self.rest - self.d
        e = np.cumsum((0.5 * self.k * r * r).ravel())[-1]  # summed left to right, as the C loop
        return e if np.isfinite(e) else None

    def gradient(self, x, g):
        e = self.value(x)
        if e is None:
            return None
        g[self.vtx] += self.k * (x[self.vtx] - self.rest - self.d)
        return e

    def hessian(self, x, H):
        H.add_diagonal(self.vtx, self.k)


class Quartic(bigstep.PythonTerm):
    """A nonlinear term coupling the vertices of each tet: sum over tets of
    c |x_a - x_b|^4 over the tet's first edge."""
    name = "quartic"

    def __init__(self, tets, c=1e3):
        self.a, self.b, self.c = tets[:, 0], tets[:, 1], c

    def value(self, x):
        r = x[self.a] - x[self.b]
        return float(self.c * np.sum(np.sum(r * r, axis=1) ** 2))

    def gradient(self, x, g):
        r = x[self.a] - x[self.b]
        s = np.sum(r * r, axis=1)
        gr = 4 * self.c * s[:, None] * r
        np.add.at(g, self.a, gr)
        np.add.at(g, self.b, -gr)
        return self.value(x)

    def hessian(self, x, H):
        r = x[self.a] - x[self.b]
        s = np.sum(r * r, axis=1)
        B = 4 * self.c * (s[:, None, None] * np.eye(3) + 2 * r[:, :, None] * r[:, None, :])
        H.add(self.a, self.a, B)
        H.add(self.b, self.b, B)
        H.add(self.a, self.b, -B)
        H.add(self.b, self.a, -B)


def _spring_scene(mode="static", frames=1):
    return {"time": {"fps": 24, "frames": frames, "steps_per_frame": 2},
            "solver": {"mode": mode, "tolerance": 1e-9},
            "gravity": [0, 0 if mode == "static" else -9.8, 0],
            "bodies": [{"mesh": "box", "box": {"cells": [4, 4, 4], "size": [1, 1, 1]},
                        "material": material("neo_hookean", 1e5)}],
            "output": {"dir": ""}}


def _spring_sim(d):
    sim = bigstep.Simulation(d)
    g = sim.mesh.groups["xmax"]
    term = Spring(g.vertices, sim.x0, 1e4, [0.2, -0.1, 0.05])
    sim.add_term(term)
    return sim, term


def test_gradient_and_hessian_match_finite_differences():
    sim = bigstep.Simulation(cube_scene())
    term = Quartic(sim.mesh.tets)
    sim.add_term(term)
    r = sim.check_term(term)
    assert r["gradient_error"] < 1e-6 and r["hessian_error"] < 1e-6
    sp, st = _spring_sim(_spring_scene())
    r = sp.check_term(st)
    assert r["gradient_error"] < 1e-7 and r["hessian_error"] < 1e-7
    sim.run(2)  # and the term steps
    assert sim.frame == 2 and np.isfinite(sim.x).all()


def test_python_spring_matches_c_example_output(prefix, src, tmp_path):
    """The example's printed results, from its own binary and from Python."""
    exe = tmp_path / "spring"
    cc = subprocess.run(["cc", os.path.join(src, "examples", "02_spring", "main.c"), "-I%s/include" % prefix,
                         "-L%s/lib" % prefix, "-Wl,-rpath,%s/lib" % prefix, "-lbigstep", "-lm", "-o", str(exe)],
                        capture_output=True, text=True)
    if cc.returncode:
        pytest.skip("cannot build examples/02_spring against %s: %s" % (prefix, cc.stderr[-500:]))
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    it, grad = re.search(r"converged in (\d+) Newton iterations, \|grad E\| (\S+) N", out).groups()
    dist = re.search(r"rigid motion by d: (\S+) m", out).group(1)
    sim, term = _spring_sim(_spring_scene())
    fs = sim.statics()
    worst = np.max(np.abs(sim.x - sim.x0 - term.d))
    assert (str(fs["iterations"]), "%.1e" % fs["grad_max"]) == (it, grad)
    assert float(dist) < 1e-12 and worst < 1e-12


@pytest.mark.parametrize("mode,frames", [("static", 1), ("dynamic", 4)])
def test_python_spring_trajectory_equals_c(prefix, src, tmp_path, mode, frames):
    """The trajectory with the example's C term (its own callbacks, through
    spring_harness.c) and with the Python term: equal bit for bit."""
    exe = tmp_path / "harness"
    cc = subprocess.run(["cc", os.path.join(os.path.dirname(__file__), "spring_harness.c"),
                         "-I%s/include" % prefix, "-L%s/lib" % prefix, "-Wl,-rpath,%s/lib" % prefix, "-lbigstep",
                         "-lm", "-o", str(exe)], capture_output=True, text=True)
    if cc.returncode:
        pytest.skip("cannot build the harness against %s: %s" % (prefix, cc.stderr[-500:]))
    d = _spring_scene(mode, frames)
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(d))
    subprocess.run([str(exe), str(p), str(tmp_path / "c.bin")], check=True)
    c = np.fromfile(tmp_path / "c.bin", dtype=np.float64)
    sim, _ = _spring_sim(d)
    xs = []
    if mode == "static":
        sim.statics()
        xs.append(sim.x.copy())
    else:
        sim.run(callback=lambda s, f: xs.append(s.x.copy()) if f["frame"] > 0 else None)
    py = np.concatenate([x.ravel() for x in xs])
    assert c.shape == py.shape
    assert np.array_equal(c, py), "max difference %g" % np.max(np.abs(c - py))


def test_term_errors_are_raised():
    class Bad(bigstep.PythonTerm):
        def value(self, x):
            raise ZeroDivisionError("in value")

        def gradient(self, x, g):
            raise ZeroDivisionError("in gradient")

        def hessian(self, x, H):
            pass

    sim = bigstep.Simulation(cube_scene())
    sim.add_term(Bad())
    with pytest.raises(ZeroDivisionError):
        sim.advance_frame()
    sim.close()

    class OffPattern(Spring):
        def hessian(self, x, H):
            H.add([0], [H.n - 1], np.eye(3)[None])

    sim = bigstep.Simulation(cube_scene())
    sim.add_term(OffPattern([0], sim.x0, 1.0, [0, 0, 0]))
    with pytest.raises(bigstep.InputError, match="not in the mesh's pattern"):
        sim.advance_frame()
    sim.close()
    sim = bigstep.Simulation(cube_scene())
    sim.advance_frame()
    with pytest.raises(bigstep.InputError, match="before the first step"):
        sim.add_term(Spring([0], sim.x0, 1.0, [0, 0, 0]))


def test_kept_callback_arrays_stay_safe():
    """Arrays and matrices a term keeps past its call: the arrays keep the
    simulation's memory alive, the matrix refuses further use."""
    kept = {}

    class Keeper(Spring):
        def gradient(self, x, g):
            kept["x"], kept["g"] = x, g
            return super().gradient(x, g)

        def hessian(self, x, H):
            kept["H"] = H
            super().hessian(x, H)

    sim = bigstep.Simulation(cube_scene())
    sim.add_term(Keeper([0, 1], sim.x0, 10.0, [0, 0, 0]))
    sim.advance_frame()
    sim.close()
    del sim
    import gc
    gc.collect()
    assert np.isfinite(kept["x"]).all() and kept["g"].shape == kept["x"].shape
    with pytest.raises(bigstep.InputError, match="after the hessian"):
        kept["H"].add_diagonal([0], 1.0)
