"""Scenes and simulations: dict scenes, stepping, the state views, fields,
QoIs and statistics."""
import gc
import threading
import time

import numpy as np
import pytest

import bigstep
from conftest import cube_scene


def test_scene_sources(src, tmp_path):
    d = cube_scene()
    a = bigstep.Scene(d)
    assert a.mode == "dynamic" and a.frames == 6 and a.steps_per_frame == 2
    assert a.qoi_names == ["tip_y"]
    b = bigstep.Scene(a.to_json())
    assert b.to_dict() == a.to_dict()
    p = tmp_path / "s.json"
    p.write_text(a.to_json())
    c = bigstep.Scene(p, sets={"time.frames": 3})
    assert c.frames == 3
    assert bigstep.Scene(str(p), sets=["time.frames=4"]).frames == 4
    assert a.with_sets({"solver.mode": "static"}).mode == "static"
    assert bigstep.schema()["type"] == "object"


def test_scene_errors_carry_the_key():
    with pytest.raises(bigstep.SceneError) as e:
        bigstep.Scene(cube_scene(gravty=[0, 0, 0]))
    assert e.value.key == "gravty" and "did you mean 'gravity'" in str(e.value)
    assert isinstance(e.value, ValueError)
    with pytest.raises(bigstep.SceneError) as e:
        bigstep.Scene(cube_scene(), sets={"time.fps": "24"})
    assert e.value.key == "time.fps" and "must be a number" in str(e.value)
    d = cube_scene()
    d["bodies"][0]["mesh"] = "no/such/mesh.msh"
    del d["bodies"][0]["box"]
    with pytest.raises(bigstep.SceneError) as e:
        bigstep.Simulation(d)
    assert e.value.key == "bodies.0.mesh" and "no/such/mesh.msh" in str(e.value)
    d = cube_scene()
    d["bodies"][0]["scripted"][0]["group"] = "nogroup"
    with pytest.raises(bigstep.SceneError) as e:
        bigstep.Simulation(d)
    assert "nogroup" in str(e.value)


def test_run_frames_and_callback():
    seen = []
    with bigstep.Simulation(cube_scene()) as sim:
        assert sim.frame == 0 and sim.time == 0.0
        fs = sim.advance_frame()
        assert fs["frame"] == 1 and fs["n_steps"] == 2 and sim.frame == 1
        sim.run(2, lambda s, f: seen.append((f["frame"], s.time, s.qoi()["tip_y"])))
        assert [f for f, _, _ in seen] == [2, 3] and sim.frame == 3
        assert seen[-1][1] == 3 / 24
        sim.run(callback=lambda s, f: False)  # stops after the next frame
        assert sim.frame == 4
        totals = sim.run()
        assert sim.frame == 6 and totals["steps"] == 12 and totals["failed"] == 0
        st = sim.step_stats()
        assert st.dtype == bigstep.STEP_DTYPE and len(st) == 2 and (st["iterations"] > 0).all()
        assert set(sim.step_stats(as_dict=True)) == set(bigstep.STEP_DTYPE.names)
        with pytest.raises(bigstep.InputError):
            sim.advance_frame()  # the scene's frames are done


def test_callback_exception_propagates():
    with bigstep.Simulation(cube_scene()) as sim:
        def cb(s, f):
            if f["frame"] == 2:
                raise RuntimeError("from the callback")
        with pytest.raises(RuntimeError, match="from the callback"):
            sim.run(callback=cb)
        assert sim.frame == 2
        with pytest.raises(bigstep.BusyError):
            sim.run(callback=lambda s, f: s.advance_frame())
        sim.run()
        assert sim.frame == 6


def test_steps_equal_frames_bit_for_bit():
    a = bigstep.Simulation(cube_scene())
    b = bigstep.Simulation(cube_scene())
    for _ in range(3):
        a.advance_frame()
        r1 = b.step()
        assert b.frame == a.frame - 1 and b.time == pytest.approx(a.time - 1 / 48)
        b.step()
        assert b.frame == a.frame and b.time == a.time
        assert np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v)
        assert r1["iterations"] >= 1
    b.step()
    b.advance_frame()  # finishes the frame begun with step()
    a.advance_frame()
    assert np.array_equal(a.x, b.x)
    a.close(), b.close()


def test_x_is_a_view():
    sim = bigstep.Simulation(cube_scene())
    x = sim.x
    assert x.shape == (sim.n_vertices, 3) and x.dtype == np.float64
    assert not x.flags.owndata and not x.flags.writeable
    addr = x.__array_interface__["data"][0]
    assert sim.x.__array_interface__["data"][0] == addr  # the same memory each time: no copy
    assert np.shares_memory(x, sim.x)
    before = x.copy()
    sim.advance_frame()
    assert sim.x.__array_interface__["data"][0] == addr  # stays valid across steps...
    assert not np.array_equal(x, before)  # ...and shows the new state
    assert np.array_equal(x, sim.x)
    with pytest.raises(ValueError):
        x[0, 0] = 1.0  # read-only: writes go through set_state
    # the O(1) cost: a view of a large state costs what a small one does
    t0 = time.perf_counter()
    for _ in range(1000):
        sim.x
    assert (time.perf_counter() - t0) / 1000 < 1e-4
    sim.close()


def test_set_state():
    with bigstep.Simulation(cube_scene()) as sim:
        sim.advance_frame()
        x = sim.x.copy()
        x[:, 1] += 0.01
        sim.set_state(x=x)
        assert np.array_equal(sim.x, x)
        sim.set_state(v=np.ones((2, 3)), vertices=[0, 1])
        assert (sim.v[:2] == 1).all()
        bad = sim.x.copy()
        bad[5, 2] = np.nan
        with pytest.raises(bigstep.InputError, match="not finite at vertex 5"):
            sim.set_state(x=bad)
        with pytest.raises(bigstep.InputError, match="shape"):
            sim.set_state(x=np.zeros((3, 3)))
        sim.step()
        with pytest.raises(bigstep.InputError, match="between frames"):
            sim.set_state(x=x)
        sim.advance_frame()
        # from a frame callback, between frames
        sim.run(1, lambda s, f: s.set_state(v=np.zeros_like(s.v)))
        assert (sim.v == 0).all()


def test_closed_simulation_raises_and_views_stay_safe():
    sim = bigstep.Simulation(cube_scene())
    sim.advance_frame()
    x = sim.x
    keep = x.copy()
    sim.close()
    sim.close()  # idempotent
    assert sim.closed
    for f in (lambda: sim.x, lambda: sim.v, lambda: sim.time, lambda: sim.frame, sim.advance_frame, sim.step,
              sim.run, sim.qoi, sim.fields, sim.measure, lambda: sim.set_state(x=keep), sim.step_stats):
        with pytest.raises(bigstep.ClosedError):
            f()
    # the view taken before close keeps the memory alive: no read of freed memory
    gc.collect()
    assert np.array_equal(x, keep)
    del x
    gc.collect()


def test_fields_qoi_measures_statics(src):
    sc = bigstep.Scene(src + "/data/scenes/beam_sag.json", sets={"output.dir": ""})
    with bigstep.Simulation(sc) as sim:
        fs = sim.statics()
        assert fs["frame"] == 1 and fs["failed"] == 0
        q = sim.qoi()
        assert set(q) == {"tip_y", "clamp_y"} and q["tip_y"] < 0
        assert np.array_equal(sim.qoi(as_array=True), [q["tip_y"], q["clamp_y"]])
        f = sim.fields()
        nt = sim.mesh.n_tets
        assert f["von_mises"].shape == (nt,) and (f["von_mises"] >= 0).all()
        assert f["cauchy"].shape == (nt, 3, 3) and f["detF"].shape == (nt,)
        assert f["displacement"].shape == (sim.n_vertices, 3)
        assert np.allclose(f["displacement"], sim.x - sim.x0)
        f2 = sim.fields(["von_mises", "detF"])
        assert set(f2) == {"von_mises", "detF"} and np.array_equal(f2["von_mises"], f["von_mises"])
        with pytest.raises(bigstep.InputError, match="unknown field"):
            sim.fields(["nope"])
        m = sim.measure()
        assert m["inverted"] == 0 and m["elastic"] > 0
        with pytest.raises(bigstep.InputError):
            sim.statics()
        mesh = sim.mesh
        assert {"xmin", "xmax", "body"} <= set(mesh.groups)
        assert mesh.groups["xmax"].dim == 2 and mesh.vertices.shape == (sim.n_vertices, 3)


def test_gil_is_released():
    d = cube_scene()
    d["bodies"][0]["box"]["cells"] = [8, 8, 8]
    d["time"]["frames"] = 6
    sim = bigstep.Simulation(d)
    window = []

    def work():
        t0 = time.perf_counter()
        sim.run()
        window[:] = [t0, time.perf_counter()]

    ticks = []
    t = threading.Thread(target=work)
    t.start()
    while t.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.0005)
    t.join()
    assert sim.frame == 6
    # the main thread kept running while the other stepped in C (the GIL released)
    inside = [x for x in ticks if window[0] < x < window[1]]
    assert len(inside) >= 0.2 * (window[1] - window[0]) / 0.0005 or len(inside) >= 50, (len(inside), window)
    sim.close()


def test_busy_from_another_thread():
    d = cube_scene()
    d["bodies"][0]["box"]["cells"] = [8, 8, 8]
    sim = bigstep.Simulation(d)
    started = threading.Event()
    t = threading.Thread(target=lambda: sim.run(callback=lambda s, f: started.set()))
    t.start()
    started.wait(30)
    with pytest.raises(bigstep.BusyError):
        sim.advance_frame()
    t.join()
    sim.close()
