"""Bad input raises a Python exception with the library's message, never a
crash: a few hundred malformed scenes, wrong arguments, a closed simulation."""
import copy
import math
import random

import numpy as np
import pytest

import bigstep
from conftest import cube_scene

NASTY = [None, True, False, 0, -1, 1, 2**31, -2**63, 1e308, -1e-308, 0.5, math.nan, math.inf, -math.inf, "",
         "box", "x" * 5000, "\u00e9\u4e2d", "../../etc/passwd", "/nonexistent/m.msh", [], [1], [1, 2, 3],
         [math.nan, 0, 0], ["a", "b", "c"], [1e300, 1e300, 1e300], {}, {"a": 1}, [[1, 2, 3]], 4097, -4, 1e9]


def _paths(d, prefix=()):
    yield prefix
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _paths(v, prefix + (i,))


def _mutate(d, rng):
    d = copy.deepcopy(d)
    paths = [p for p in _paths(d) if p]
    for _ in range(rng.randint(1, 3)):
        p = rng.choice(paths)
        parent = d
        try:
            for k in p[:-1]:
                parent = parent[k]
            op = rng.random()
            if op < 0.15 and isinstance(parent, dict):
                parent.pop(p[-1], None)
            elif op < 0.25 and isinstance(parent, dict):
                parent[p[-1] + "x"] = rng.choice(NASTY)
            else:
                parent[p[-1]] = rng.choice(NASTY)
        except (KeyError, IndexError, TypeError):
            pass
    return d


def _small(sc):
    """Whether a valid scene is small enough to build and step here."""
    d = sc.to_dict()
    for b in d.get("bodies", []):
        if b.get("mesh") != "box" or b.get("refine", 0) > 0:
            return False
        c = b.get("box", {}).get("cells", [4, 4, 4])
        if c[0] * c[1] * c[2] > 64:
            return False
    return sc.steps_per_frame <= 4


def test_malformed_scenes_raise_never_crash():
    rng = random.Random(1234)
    base = cube_scene()
    n_err = n_ok = n_run = 0
    for i in range(400):
        d = _mutate(base, rng)
        try:
            sc = bigstep.Scene(d)
        except bigstep.SceneError as e:
            assert str(e) and e.code < 0
            n_err += 1
            continue
        n_ok += 1
        if not _small(sc):
            continue
        try:
            with bigstep.Simulation(sc, output=False) as sim:
                n_run += 1
                if sc.mode == "static":
                    sim.statics()
                else:
                    sim.advance_frame()
                sim.qoi()
        except bigstep.Error as e:
            assert str(e)
    assert n_err > 200 and n_run > 10


def test_malformed_json_text_and_files(tmp_path):
    for text in ["{", "{\"time\": }", "[]", "{\"time\": {\"fps\": 1e999}}", "{\"a\":1,\"a\":2}", "\"str\"",
                 "{" * 10000, "{\"bodies\": [" + "{}," * 1000 + "{}]}"]:
        with pytest.raises(bigstep.SceneError):
            bigstep.Scene(text)
    p = tmp_path / "bad.json"
    p.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(bigstep.SceneError):
        bigstep.Scene(p)
    with pytest.raises(bigstep.SceneError, match="cannot open"):
        bigstep.Scene(tmp_path / "missing.json")
    with pytest.raises(bigstep.SceneError):
        bigstep.Scene("bad\0path.json")


def test_wrong_python_types():
    with pytest.raises(TypeError):
        bigstep.Scene(42)
    with pytest.raises(TypeError):
        bigstep.Scene(cube_scene(), sets="time.fps=3")
    with pytest.raises(TypeError):
        bigstep.Scene(cube_scene(), sets=[1, 2])
    with pytest.raises(TypeError):
        bigstep.Scene({"a": object()})
    with pytest.raises(bigstep.SceneError):
        bigstep.Scene({"time": {"fps": math.nan}})
    sim = bigstep.Simulation(cube_scene())
    for bad in (-1, 1.5, "3", True):
        with pytest.raises((bigstep.InputError, TypeError)):
            sim.run(bad)
    with pytest.raises(TypeError):
        sim.run(1, callback=3)
    with pytest.raises(bigstep.InputError):
        sim.set_state(x=np.zeros((2, 2)))
    with pytest.raises(bigstep.InputError):
        sim.set_state(x=np.zeros((1, 3)), vertices=[10**6])
    with pytest.raises(bigstep.InputError):
        sim.set_state(x=np.zeros((1, 3)), vertices=[0.5])
    with pytest.raises(TypeError):
        sim.add_term(object())
    with pytest.raises(bigstep.InputError):
        bigstep.Mesh(np.zeros((3, 3)), np.zeros((1, 4), int))  # a tet index out of range
    with pytest.raises(bigstep.InputError):
        bigstep.Mesh(np.zeros((3, 2)), np.zeros((1, 4), int))
    with pytest.raises(bigstep.InputError):
        bigstep.mesh("/nonexistent.msh")
    with pytest.raises(bigstep.InputError):
        bigstep.mesh("box:0x0x0")
    sim.close()
    with pytest.raises(bigstep.ClosedError):
        sim.run()
    with pytest.raises(bigstep.ClosedError):
        sim.add_term(bigstep.PythonTerm())


def test_nan_state_raises_library_message():
    with bigstep.Simulation(cube_scene()) as sim:
        x = sim.x.copy()
        x[3] = np.nan
        with pytest.raises(bigstep.InputError) as e:
            sim.set_state(x=x)
        assert "not finite at vertex 3" in str(e.value) and e.value.status == "input"
        v = sim.v.copy()
        v[0, 0] = np.inf
        with pytest.raises(bigstep.InputError, match="not finite"):
            sim.set_state(v=v)
        sim.advance_frame()  # the state was left as it was
        assert np.isfinite(sim.x).all()
