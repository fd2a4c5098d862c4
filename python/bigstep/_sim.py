"""The simulation: stepping, its state as NumPy views, fields, QoIs and
statistics (bs_sim.h, bs_fields.h, bs_qoi.h, bs_runfolder.h)."""
from __future__ import annotations

import os
import signal
import threading
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

import numpy as np

from ._bigstep import ffi, lib
from ._errors import BusyError, ClosedError, InputError, SceneError, check, new_error
from ._mesh import Mesh
from ._scene import Scene, SceneSource, Sets, as_scene
from ._terms import BlockMatrix as _BlockMatrix, PythonTerm, _register_term

__all__ = ["Simulation", "STEP_DTYPE", "FrameCallback"]

FrameCallback = Callable[["Simulation", Dict[str, Any]], Optional[bool]]

#: The dtype of :meth:`Simulation.step_stats` (one record per time step).
STEP_DTYPE = np.dtype([
    ("time", "f8"), ("iterations", "i4"), ("cg_iterations", "i4"), ("ls_evaluations", "i4"),
    ("indefinite", "i4"), ("fallback_neg_dx", "i4"), ("fallback_neg_grad", "i4"), ("clamps", "i4"),
    ("cholmod_fallbacks", "i4"), ("alpha_min", "f8"), ("alpha_max", "f8"), ("grad_norm", "f8"), ("E", "f8"),
    ("failed", "?"), ("guess", "U10"), ("reason", "U160"), ("inverted", "i4"), ("t_eval", "f8"),
    ("t_assembly", "f8"), ("t_linear", "f8"), ("t_line_search", "f8"), ("seconds", "f8")])

_TOTALS = ("steps", "failed", "iterations", "cg", "ls", "indefinite", "fb_dx", "fb_grad", "clamps", "chol_fb",
           "downhill", "floor", "seconds", "max_grad", "first_fail_frame", "first_fail_step")


class _View:
    """What a NumPy view of the library's memory is made from: the
    ``__array_interface__`` and a reference to the owner of that memory, which
    NumPy keeps as the array's base (the memory lives as long as the view)."""

    def __init__(self, owner, ptr, shape, typestr, readonly):
        self._owner = owner
        self.__array_interface__ = {"data": (int(ffi.cast("uintptr_t", ptr)), readonly), "shape": shape,
                                    "typestr": typestr, "version": 3}


def _view(owner, ptr, shape, typestr="<f8", readonly=True) -> np.ndarray:
    return np.asarray(_View(owner, ptr, shape, typestr, readonly))


class _Owner:
    """Owns the bs_sim and what borrows it (its run folder, fields, QoIs, the
    Python terms); freed when the last reference goes: the Simulation's
    (dropped by close()) and those of the views of its memory."""

    def __init__(self, scene: Scene):
        self.scene = scene          # the simulation borrows the scene
        self.pp = ffi.new("bs_sim **")
        self.run = ffi.new("bspy_run *")
        self.run.measured_frame = -1
        self.run.last_frame = -1
        self.terms: List[Any] = []  # (term, handle): the C terms call them
        self.fields: Dict[int, Any] = {}
        self.qoi = None

    def __del__(self):
        try:
            self.free()
        except Exception:
            pass

    def free(self):
        if self.run is not None and self.run.folder != ffi.NULL:
            p = ffi.new("bs_runfolder **", self.run.folder)
            lib.bs_runfolder_destroy(p)
            self.run.folder = ffi.NULL
        for f in self.fields.values():
            lib.bs_fields_destroy(f)
        self.fields = {}
        if self.qoi is not None:
            lib.bs_qoi_destroy(self.qoi)
            self.qoi = None
        if self.pp is not None and self.pp[0] != ffi.NULL:
            lib.bs_sim_destroy(self.pp)
        self.terms = []


def _fs_dict(fs) -> Dict[str, Any]:
    return {"frame": int(fs.frame), "time": float(fs.time), "n_steps": int(fs.n_steps),
            "iterations": int(fs.iterations), "cg_iterations": int(fs.cg_iterations), "failed": int(fs.failed),
            "seconds": float(fs.seconds), "grad_max": float(fs.grad_max)}


class _FrameCtx:
    def __init__(self, sim, callback):
        self.sim, self.callback, self.exc = sim, callback, None


@ffi.def_extern()
def bspy_py_frame(s, fs, py):
    ctx = ffi.from_handle(py)
    sim = ctx.sim
    sim._in_callback = True
    try:
        if ctx.callback(sim, _fs_dict(fs)) is False:
            sim._owner.run.last_frame = fs.frame  # stop after this frame
        return 0
    except BaseException as e:  # KeyboardInterrupt too: re-raised after the run
        ctx.exc = e
        return 1
    finally:
        sim._in_callback = False


class Simulation:
    """A scene turned into a simulation (bs_sim_create), and stepping it.

    ``Simulation(scene, sets=None, output=None, replace=False)``: scene is a
    :class:`Scene` or anything Scene() takes (a dict, a path, JSON text), with
    optional overrides. ``output``: None writes the run folder the scene's
    output.dir names (as ``bigstep run`` does; none when it is ""), False
    writes none, a str writes that folder; ``replace`` removes an earlier run's
    files there (else such a folder is refused, as the command line does).

    State, as NumPy views of the library's memory (no copy):
      * ``sim.x``, ``sim.v``: (n, 3) float64 positions (m) and velocities
        (m/s), read-only views. The memory they view is the simulation's for
        its whole life: a view taken once stays valid and shows the current
        state after every step. Write the state through :meth:`set_state`.
        After :meth:`close`, ``sim.x`` raises ClosedError; a view taken before
        keeps the memory alive (never freed under it) until it is dropped.
      * ``sim.time`` (s), ``sim.frame`` (frames completed).

    Stepping: :meth:`step` (one time step), :meth:`advance_frame`,
    :meth:`run` (frames with a callback after each), :meth:`statics` (a static
    scene). The GIL is released during every C call; Ctrl-C during
    :meth:`run`, :meth:`advance_frame` or :meth:`statics` stops at the end of
    the last complete frame (a frame cut short is undone, as ``bigstep run``
    does) and raises KeyboardInterrupt; the simulation stays usable.

    Errors: SceneError for a scene or mesh the library refuses; Error (or a
    subclass) with the library's message for every other failure; ClosedError
    after close(); BusyError when used from another thread during a call, or
    stepped from its own frame callback.

    Use it as a context manager, or call :meth:`close` (which also writes the
    run folder's summary.txt).
    """

    def __init__(self, scene: SceneSource, sets: Sets = None, *, output: Union[None, bool, str] = None,
                 replace: bool = False):
        sc = as_scene(scene, sets)
        if isinstance(output, (str, os.PathLike)):
            sc = sc.with_sets({"output.dir": os.fspath(output)})
        elif output is not None and not isinstance(output, bool):
            raise TypeError("output: None, a bool or a folder path")
        self.scene: Scene = sc
        self._closed = False
        self._lock = threading.Lock()
        self._in_callback = False
        self._substep = 0
        self._reported0 = False
        self._interrupted = False
        self._mesh: Optional[Mesh] = None
        self._totals = ffi.new("bs_run_totals *")
        self._fs = ffi.new("bs_frame_stats *")
        owner = _Owner(sc)
        err = new_error()
        check(lib.bs_sim_create(sc._ptr, owner.pp, err), err, SceneError)
        self._owner = owner
        self._n = int(owner.pp[0].mesh.n_vertices)
        if output is not False and sc.output_dir:
            fo = ffi.new("bs_runfolder_opts *")
            fo.replace = int(bool(replace))
            cmd = ffi.new("char[]", b"(python: bigstep.Simulation)")
            fo.command_line = cmd
            rf = ffi.new("bs_runfolder **")
            check(lib.bs_runfolder_open(sc.output_dir.encode(), owner.pp[0], fo, rf, err), err)
            owner.run.folder = rf[0]

    # ---- access ------------------------------------------------------------
    def _s(self):
        if self._closed:
            raise ClosedError()
        return self._owner.pp[0]

    class _Guard:
        def __init__(self, sim, stepping):
            self.sim, self.stepping, self.locked = sim, stepping, False

        def __enter__(self):
            sim = self.sim
            if sim._closed:
                raise ClosedError()
            if sim._in_callback and sim._cb_thread == threading.get_ident():
                if self.stepping:
                    raise BusyError("the simulation is running: it cannot be stepped or closed from its own "
                                    "frame callback (return False to stop the run)")
                return sim._owner.pp[0]
            if not sim._lock.acquire(blocking=False):
                raise BusyError("the simulation is busy (a call in progress in another thread)")
            self.locked = True
            if sim._closed:  # closed while we waited
                sim._lock.release()
                self.locked = False
                raise ClosedError()
            return sim._owner.pp[0]

        def __exit__(self, *a):
            if self.locked:
                self.sim._lock.release()

    _cb_thread: Optional[int] = None

    def _guard(self, stepping: bool = False) -> "Simulation._Guard":
        return Simulation._Guard(self, stepping)

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._closed

    @property
    def n_vertices(self) -> int:
        """Vertices of the merged mesh of all bodies."""
        self._s()
        return self._n

    @property
    def x(self) -> np.ndarray:
        """Positions (n, 3), m: a read-only view of the library's memory
        (valid for the simulation's life; see the class)."""
        s = self._s()
        return _view(self._owner, s.x, (self._n, 3))

    @property
    def v(self) -> np.ndarray:
        """Velocities (n, 3), m/s: a read-only view (see :attr:`x`)."""
        s = self._s()
        return _view(self._owner, s.v, (self._n, 3))

    @property
    def x0(self) -> np.ndarray:
        """Positions at t = 0 (the transformed rest state), a read-only view."""
        s = self._s()
        return _view(self._owner, s.x0, (self._n, 3))

    @property
    def free_mask(self) -> np.ndarray:
        """(n,) bool: True for free vertices, False for scripted ones (a copy)."""
        s = self._s()
        return _view(self._owner, s.mask, (self._n,), "|u1").astype(bool)

    @property
    def vertex_offset(self) -> np.ndarray:
        """(n_bodies + 1,) int: body b's vertices are vertex_offset[b]:vertex_offset[b+1]."""
        s = self._s()
        return _view(self._owner, s.vertex_offset, (int(s.n_bodies) + 1,), "<i4").copy()

    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return float(self._s().time)

    @property
    def frame(self) -> int:
        """Frames completed (statics: 1 once solved)."""
        return int(self._s().frame)

    @property
    def dofs(self) -> int:
        """Free degrees of freedom (3 per free vertex)."""
        return int(lib.bs_sim_dofs(self._s()))

    @property
    def memory_estimate(self) -> float:
        """The run's estimated peak memory (bytes, bs_memory.h)."""
        return float(self._s().memory_bytes)

    @property
    def mesh(self) -> Mesh:
        """The merged mesh of all bodies at rest (a copy, as arrays; groups by name)."""
        s = self._s()
        if self._mesh is None:
            self._mesh = Mesh._wrap(s.mesh)
        return self._mesh

    @property
    def totals(self) -> Dict[str, Any]:
        """Sums over the frames run so far (steps, failed steps, Newton and
        CG iterations, line-search evaluations, solver seconds, the largest
        final |grad E|, the first failed step and its reason)."""
        self._s()
        T = self._totals
        d = {k: (float(getattr(T, k)) if k in ("seconds", "max_grad") else int(getattr(T, k))) for k in _TOTALS}
        d["first_fail_reason"] = ffi.string(T.first_fail_reason).decode("utf-8", "replace")
        return d

    # ---- stepping --------------------------------------------------------
    def _check_terms(self):
        for term, _h in self._owner.terms:
            e = term._exc
            if e is not None:
                term._exc = None
                raise e

    def _report0(self, s):
        """Frame 0 (the initial state) into the run folder, once."""
        if self._reported0:
            return
        self._reported0 = True
        r = self._owner.run
        if r.folder != ffi.NULL:
            lib.bs_frame_sums(0, s.time, 0, s.steps, self._fs)
            self._write_frame(s)

    def _write_frame(self, s):
        r = self._owner.run
        if r.folder == ffi.NULL:
            return
        lib.bs_sim_measure(s, 1, ffi.addressof(r, "last_m"))
        r.measured_frame = self._fs.frame
        err = new_error()
        check(lib.bs_runfolder_write(r.folder, s, self._fs, ffi.addressof(r, "last_m"), err), err)

    def step(self) -> Dict[str, Any]:
        """One time step of the current frame (dynamic scenes; bs_sim_take_step).

        Returns the step's statistics (a dict of :data:`STEP_DTYPE`'s fields).
        After the frame's last step the frame is complete (``sim.frame``
        advances, the run folder gets its row). Steps taken one by one give
        the state :meth:`advance_frame` gives, bit for bit.
        """
        with self._guard(stepping=True) as s:
            if self.scene.mode != "dynamic":
                raise InputError("%s: a static scene has no time steps (use statics())" % self.scene.path)
            if s.frame >= s.scene.frames:
                raise InputError("%s: the scene's %d frames are done" % (self.scene.path, s.scene.frames))
            self._report0(s)
            err = new_error()
            k, f = int(s.substep), int(s.frame) + 1
            got = ffi.new("int *")
            done = ffi.new("int *")
            st = lib.bspy_step_sig(s, int(_catch_sigint()), got, done, self._fs, err)
            if st == 0:
                rec = _step_record(s.steps[k])
                self._substep = int(s.substep)
                if done[0]:
                    lib.bs_run_totals_add(self._totals, self._fs)
                    self._write_frame(s)
            self._check_terms()
            check(st, err)
            if got[0]:  # Ctrl-C during the step: it was completed, then stop here
                raise KeyboardInterrupt("bigstep: stopped after step %d of frame %d" % (k + 1, f))
            return rec

    def advance_frame(self) -> Dict[str, Any]:
        """One frame (steps_per_frame steps); returns the frame's statistics
        (frame, time, n_steps, iterations, cg_iterations, failed, seconds,
        grad_max). Ctrl-C during it undoes the frame and raises
        KeyboardInterrupt."""
        if self.scene.mode != "dynamic":
            self._s()
            raise InputError("%s: a static scene has no frames to advance (use statics())" % self.scene.path)
        if self._substep:  # the rest of a frame begun with step()
            while self._substep:
                self.step()
            return _fs_dict(self._fs)
        with self._guard(stepping=True) as s:
            if s.frame >= s.scene.frames:
                raise InputError("%s: the scene's %d frames are done" % (self.scene.path, s.scene.frames))
            self._run_frames(s, int(s.frame) + 1, None)
            return self._last_frame_stats(s)

    def run(self, frames: Optional[int] = None, callback: Optional[FrameCallback] = None) -> Dict[str, Any]:
        """Runs `frames` more frames (default: to the scene's last; a static
        scene: the static solve), calling ``callback(sim, frame_stats)`` after
        each (and with frame 0, the initial state, on a run's first call). The
        callback may read the state (sim.x, fields(), qoi(), ...) and set it
        (set_state); returning False stops the run after that frame; an
        exception it raises stops the run and is raised here.

        Ctrl-C stops the run at the end of the last complete frame and raises
        KeyboardInterrupt (the run folder is left consistent, as by
        ``bigstep run``). Returns :attr:`totals`.
        """
        if frames is not None and (not isinstance(frames, int) or isinstance(frames, bool) or frames < 0):
            raise InputError("frames must be a non-negative int, got %r" % (frames,))
        if callback is not None and not callable(callback):
            raise TypeError("callback must be callable")
        while self._substep:
            self.step()
        with self._guard(stepping=True) as s:
            if self.scene.mode == "static":
                if s.frame >= 1:
                    raise InputError("%s: the static solve is done" % self.scene.path)
                last = -1
            else:
                if frames == 0 or s.frame >= s.scene.frames:
                    return self.totals
                last = -1 if frames is None else min(int(s.frame) + frames, int(s.scene.frames))
            self._run_frames(s, last, callback)
            return self.totals

    def statics(self) -> Dict[str, Any]:
        """The static solve of a scene in mode "static" (frame 1); returns
        its statistics as :meth:`advance_frame` does."""
        with self._guard(stepping=True) as s:
            if self.scene.mode != "static":
                raise InputError("%s: statics() needs a scene in mode \"static\" (solver.mode)" % self.scene.path)
            if s.frame >= 1:
                raise InputError("%s: the static solve is done" % self.scene.path)
            self._run_frames(s, -1, None)
            return self._last_frame_stats(s)

    def _last_frame_stats(self, s) -> Dict[str, Any]:
        n = 0 if s.frame == 0 else (1 if self.scene.mode == "static" else self.scene.steps_per_frame)
        lib.bs_frame_sums(s.frame, s.time, n, s.steps, self._fs)
        return _fs_dict(self._fs)

    def _run_frames(self, s, last_frame: int, callback):
        r = self._owner.run
        r.last_frame = last_frame
        ctx = handle = None
        if callback is not None:
            ctx = _FrameCtx(self, callback)
            handle = ffi.new_handle(ctx)
            r.py = handle
        else:
            r.py = ffi.NULL
        catch = _catch_sigint()
        err = new_error()
        self._cb_thread = threading.get_ident()
        try:
            st = lib.bspy_run_sim(s, r, 1 if self._reported0 else 0, self._totals, int(catch), err)
        finally:
            r.py = ffi.NULL
            self._cb_thread = None
        self._reported0 = True
        self._check_terms()
        if ctx is not None and ctx.exc is not None:
            raise ctx.exc
        check(st, err)
        if st == lib.BS_SIM_STOPPED and r.stop_reason > 0:
            self._interrupted = True
            if r.folder != ffi.NULL and s.scene.checkpoint_every > 0:
                check(lib.bs_runfolder_checkpoint(r.folder, s, err), err)
            raise KeyboardInterrupt("bigstep: run stopped at frame %d (the last complete frame)" % s.frame)
        self._interrupted = False

    # ---- state -----------------------------------------------------------
    def set_state(self, x=None, v=None, *, vertices=None) -> None:
        """Writes positions and/or velocities between frames (to restart from
        a state, or to move vertices by script between frames).

        x, v: (n, 3) arrays, or with `vertices` (indices) the rows of those
        vertices. A non-finite value is refused with the library's message
        (bs_sim_restore). Scripted vertices are put back on their script at
        the next step. Not between the steps of a frame (after step()).
        """
        with self._guard() as s:
            if self._substep:
                raise InputError("set_state: between frames only (%d of %d steps of frame %d taken)"
                                 % (self._substep, self.scene.steps_per_frame, s.frame + 1))
            n = self._n
            nx = np.array(_view(self._owner, s.x, (n, 3)))
            nv = np.array(_view(self._owner, s.v, (n, 3)))
            for new, cur, name in ((x, nx, "x"), (v, nv, "v")):
                if new is None:
                    continue
                a = np.asarray(new, dtype=np.float64)
                if vertices is None:
                    if a.shape != (n, 3):
                        raise InputError("set_state: %s must have shape (%d, 3), got %s" % (name, n, a.shape))
                    cur[:] = a
                else:
                    idx = np.asarray(vertices)
                    if idx.dtype.kind not in "iu" or (idx.size and (idx.min() < -n or idx.max() >= n)):
                        raise InputError("set_state: vertices must be indices in [0, %d)" % n)
                    cur[idx] = a
            err = new_error()
            if self.scene.mode == "dynamic":
                check(lib.bs_sim_restore(s, s.frame, ffi.cast("double *", ffi.from_buffer(nx)),
                                         ffi.cast("double *", ffi.from_buffer(nv)), err), err)
            else:
                bad = np.nonzero(~np.isfinite(nx).all(axis=1) | ~np.isfinite(nv).all(axis=1))[0]
                if bad.size:
                    raise InputError("%s: the state to set is not finite at vertex %d" % (self.scene.path, bad[0]))
                ffi.memmove(s.x, ffi.from_buffer(nx), nx.nbytes)
                ffi.memmove(s.v, ffi.from_buffer(nv), nv.nbytes)

    def measure(self, intersections: bool = False) -> Dict[str, Any]:
        """What a frames.csv row records of the current state: energies
        (kinetic, elastic, gravity, total; J), inverted tets, min det F,
        vertices inside obstacles and their depth, and with `intersections`
        the intersecting surface triangle pairs (else -1)."""
        with self._guard() as s:
            m = ffi.new("bs_sim_measures *")
            lib.bs_sim_measure(s, int(bool(intersections)), m)
            return {"kinetic": m.kinetic, "elastic": m.elastic, "gravity": m.gravity, "total": m.total,
                    "inverted": int(m.inverted), "min_detF": m.min_detF, "penetrating": int(m.penetrating),
                    "max_depth": m.max_depth, "self_intersections": int(m.self_intersections)}

    def fields(self, names: Optional[Sequence[str]] = None) -> Dict[str, np.ndarray]:
        """The fields of the current state (bs_fields_compute), as arrays
        (copies), by the names of output.fields: per tet "detF" (m,),
        "inverted" (m,) bool, "first_piola", "cauchy", "green_strain"
        (m, 3, 3), "von_mises", "energy_density" (m,), "stretches" (m, 3),
        "material", "body" (m,); per vertex "displacement", "velocity",
        "elastic_force", "contact_force" (N), "friction_impulse" (N s)
        (n, 3), "scripted" (n,) bool. names: a subset (default: all); an
        unknown name raises with the library's message."""
        if names is None:
            mask = (1 << lib.BS_FIELD_COUNT) - 1
        else:
            if isinstance(names, str):
                names = [names]
            c = [ffi.new("char[]", str(nm).encode()) for nm in names]
            setp = ffi.new("uint32_t *")
            err = new_error()
            check(lib.bs_fields_parse_names(len(c), ffi.new("const char *[]", c) if c else ffi.NULL, setp, err),
                  err)
            mask = int(setp[0])
        with self._guard() as s:
            o = self._owner
            if mask not in o.fields:
                fp = ffi.new("bs_fields **")
                err = new_error()
                check(lib.bs_fields_create(s, mask, fp, err), err)
                o.fields[mask] = fp
            f = o.fields[mask][0]
            lib.bs_fields_compute(f, s)
            nv, nt = int(f.n_vertices), int(f.n_tets)
            out: Dict[str, np.ndarray] = {}

            def put(name, ptr, shape, typestr="<f8", as_bool=False):
                if ptr != ffi.NULL:
                    a = np.array(_view(o, ptr, shape, typestr))
                    out[name] = a.astype(bool) if as_bool else a

            x = np.array(_view(o, s.x, (nv, 3)))
            want = lambda nm: names is None or nm in names  # noqa: E731
            if want("displacement"):
                out["displacement"] = x - np.array(_view(o, s.x0, (nv, 3)))
            if want("velocity"):
                out["velocity"] = np.array(_view(o, s.v, (nv, 3)))
            if want("scripted"):
                put("scripted", f.scripted, (nv,), "|u1", True)
            if want("body"):
                put("body", f.cell_body, (nt,), "<i4")
            if want("material"):
                put("material", f.material, (nt,), "<i4")
            put("detF", f.J, (nt,))
            put("inverted", f.inverted, (nt,), "|u1", True)
            put("first_piola", f.P, (nt, 3, 3))
            put("cauchy", f.cauchy, (nt, 3, 3))
            put("green_strain", f.green, (nt, 3, 3))
            put("von_mises", f.von_mises, (nt,))
            put("energy_density", f.psi, (nt,))
            put("stretches", f.stretch, (nt, 3))
            put("elastic_force", f.f_elastic, (nv, 3))
            put("contact_force", f.f_contact, (nv, 3))
            put("friction_impulse", f.friction, (nv, 3))
            if names is not None:
                out = {k: a for k, a in out.items() if k in names}
            return out

    def qoi(self, as_array: bool = False) -> Union[Dict[str, float], np.ndarray]:
        """The scene's quantities of interest at the current state
        (bs_qoi_eval), {name: value} in the scene's order (m, m/s, N or J),
        or with `as_array` a float64 array in the order of scene.qoi_names."""
        with self._guard() as s:
            o = self._owner
            err = new_error()
            if o.qoi is None:
                qp = ffi.new("bs_qoi **")
                check(lib.bs_qoi_create(s, qp, err), err)
                o.qoi = qp
            names = self.scene.qoi_names
            vals = ffi.new("double[]", max(1, len(names)))
            check(lib.bs_qoi_eval(o.qoi[0], s, vals, err), err)
            if as_array:
                return np.array([vals[i] for i in range(len(names))], dtype=np.float64)
            return {nm: float(vals[i]) for i, nm in enumerate(names)}

    def step_stats(self, as_dict: bool = False) -> Union[np.ndarray, Dict[str, np.ndarray]]:
        """The time steps of the last frame (or the steps taken so far of the
        current one), one record each: a NumPy structured array of
        :data:`STEP_DTYPE` (iterations, cg_iterations, grad_norm, E, failed,
        the minimizer's reason, phase timings, ...), or with `as_dict` a dict
        of its columns."""
        with self._guard() as s:
            if self._substep:
                n = self._substep
            elif s.frame == 0:
                n = 0
            else:
                n = 1 if self.scene.mode == "static" else self.scene.steps_per_frame
            a = np.zeros(n, STEP_DTYPE)
            for k in range(n):
                rec = _step_record(s.steps[k])
                a[k] = tuple(rec[nm] for nm in STEP_DTYPE.names)
            if as_dict:
                return {nm: a[nm] for nm in STEP_DTYPE.names}
            return a

    # ---- terms -------------------------------------------------------------
    def add_term(self, term: PythonTerm) -> None:
        """Adds an energy term written in Python (see :class:`PythonTerm`) to
        the objective. Before the first step only."""
        with self._guard(stepping=True) as s:
            if self._reported0 or s.frame:
                raise InputError("add_term: before the first step only")
            _register_term(self._owner, s, term, self._n)

    def check_term(self, term: PythonTerm, x=None, h: float = 1e-5, seed: int = 7) -> Dict[str, float]:
        """Checks a term's derivatives on this simulation's mesh, as every
        term of bigstep is checked (examples/02_spring): along a random
        direction p at x (default: x0 plus a random offset of 0.1 m), the
        gradient against central differences of E, and the Hessian against
        differences of the gradient. Returns {"gradient_error",
        "hessian_error"} (relative)."""
        with self._guard() as s:
            n = self._n
            rng = np.random.default_rng(seed)
            x0 = np.array(_view(self._owner, s.x0, (n, 3)))
            x = x0 + 0.1 * (rng.random((n, 3)) - 0.5) if x is None else np.array(x, dtype=np.float64)
            p = rng.random((n, 3)) - 0.5
            g, gp, gm = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
            term.gradient(x, g)
            gdotp = float(np.sum(g * p))
            Ep = term.gradient(x + h * p, gp)
            Em = term.gradient(x - h * p, gm)
            grad_err = abs((Ep - Em) / (2 * h) - gdotp) / abs(gdotp) if gdotp else abs((Ep - Em) / (2 * h))
            Hpp = ffi.new("bs_bsr **")
            err = new_error()
            check(lib.bs_fem_matrix(s.fem, Hpp, err), err)
            try:
                term.hessian(x, _BlockMatrix(Hpp[0], n))
                Hp = np.zeros((n, 3))
                pc = np.ascontiguousarray(p)
                lib.bs_bsr_mul(Hpp[0], ffi.NULL, ffi.cast("double *", ffi.from_buffer(pc)),
                               ffi.cast("double *", ffi.from_buffer(Hp)))
            finally:
                lib.bs_bsr_destroy(Hpp)
            fd = (gp - gm) / (2 * h)
            den = float(np.linalg.norm(Hp))
            hess_err = float(np.linalg.norm(fd - Hp)) / den if den else float(np.linalg.norm(fd))
            return {"gradient_error": float(grad_err), "hessian_error": hess_err}

    # ---- the end -------------------------------------------------------------
    def close(self) -> None:
        """Writes the run folder's summary.txt (when there is a folder) and
        releases the simulation: its memory is freed once no view of it
        (sim.x, ...) is left. Further use raises ClosedError. Idempotent."""
        if self._closed:
            return
        with self._guard(stepping=True) as s:
            o = self._owner
            r = o.run
            err = new_error()
            st = 0
            if r.folder != ffi.NULL:
                wall = lib.bspy_folder_wall(r)
                st = lib.bspy_finish(r, s, self._totals, int(self._interrupted), wall, err)
            self._closed = True
            self._mesh = None
            del self._owner
            self._owner = None  # type: ignore[assignment]
            check(st, err)

    def __enter__(self) -> "Simulation":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        try:
            if not self._closed and self._owner is not None:
                self.close()
        except Exception:
            pass

    def __repr__(self) -> str:
        if self._closed:
            return "<bigstep.Simulation (closed)>"
        return "<bigstep.Simulation %s: %d vertices, frame %d, t = %g s>" % (self.scene.path, self._n, self.frame,
                                                                           self.time)


def _catch_sigint() -> bool:
    """Whether a C call should catch SIGINT (to stop cleanly and raise
    KeyboardInterrupt): in the main thread, when Python handles SIGINT."""
    return (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) not in (signal.SIG_IGN, signal.SIG_DFL, None))


def _step_record(rec) -> Dict[str, Any]:
    st = rec.st
    mn = st.min
    return {"time": float(rec.time), "iterations": int(mn.iterations), "cg_iterations": int(mn.cg_iterations),
            "ls_evaluations": int(mn.ls_evaluations), "indefinite": int(mn.indefinite_exits),
            "fallback_neg_dx": int(mn.fallback_neg_dx), "fallback_neg_grad": int(mn.fallback_neg_grad),
            "clamps": int(mn.clamps), "cholmod_fallbacks": int(mn.cholmod_fallbacks),
            "alpha_min": float(mn.alpha_min), "alpha_max": float(mn.alpha_max), "grad_norm": float(mn.grad_norm),
            "E": float(mn.E), "failed": bool(st.failed), "guess": ffi.string(lib.bs_guess_name(st.guess)).decode(),
            "reason": ffi.string(rec.reason).decode("utf-8", "replace"), "inverted": int(rec.inverted),
            "t_eval": float(mn.t_eval), "t_assembly": float(mn.t_assembly), "t_linear": float(mn.t_linear),
            "t_line_search": float(mn.t_line_search), "seconds": float(st.seconds)}
