"""Studies (bs_study.h) run in this process: the library plans the runs and
evaluates them; each run is a Simulation writing its run folder, as the
children of ``bigstep study`` do (no subprocess)."""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Union

from ._bigstep import ffi, lib
from ._errors import InputError, SceneError, check, new_error
from ._scene import Scene, SceneSource, Sets, _set_strings

__all__ = ["study", "StudyResult"]

Vary = Union[Mapping[str, Sequence[Any]], Sequence[str]]


@dataclass
class StudyResult:
    """What :func:`study` returns.

    rows: one dict per run (the columns of study.csv: the knobs' values,
        method, status, s_per_frame, errors against the reference, energy
        drift, reference/pareto marks, and per QoI its last value and errors).
    gci: one dict per (QoI, knob, method) along a refine or time knob with
        three or more complete levels: status, observed order p,
        extrapolated value, e_a, e_ext, gci_fine, gci_coarse, asymptotic
        (fractions, not %), the runs used and their h and values.
    out: the study folder (study.csv and the run folders).
    """
    rows: List[Dict[str, Any]]
    gci: List[Dict[str, Any]]
    out: str
    reference: Optional[str] = None
    n_not_compared: int = 0

    def column(self, name: str) -> List[Any]:
        """One column of the rows."""
        return [r.get(name) for r in self.rows]


def _knob_specs(vary: Vary) -> List[str]:
    if isinstance(vary, Mapping):
        out = []
        for k, vals in vary.items():
            if isinstance(vals, (str, bytes)) or not hasattr(vals, "__iter__"):
                raise InputError("vary[%r]: a list of values" % (k,))
            out.append("%s=%s" % (k, ",".join(v if isinstance(v, str) else json.dumps(v) for v in vals)))
        return out
    if isinstance(vary, str):
        return [vary]
    return [str(v) for v in vary]


def _num(x: float) -> Optional[float]:
    return None if x is None or (isinstance(x, float) and math.isnan(x)) else x


def _read_done(run, key: str) -> bool:
    """The `bigstep study` done marker of a run folder: present and made
    with this key (then the run's exit code etc. are read)."""
    p = os.path.join(ffi.string(run.dir).decode(), "done")
    try:
        with open(p) as f:
            lines = f.read().splitlines()
    except OSError:
        return False
    ok_key = False
    run.exit_code = -1
    for ln in lines:
        if ln.startswith("exit "):
            run.exit_code = int(ln[5:] or -1)
        elif ln.startswith("maxrss_kib "):
            run.maxrss_kib = int(ln[11:] or 0)
        elif ln.startswith("wall "):
            run.wall = float(ln[5:] or 0)
        elif ln.startswith("timeout "):
            run.timed_out = int(ln[8:] or 0)
        elif ln.startswith("key "):
            ok_key = ln[4:] == key
    return ok_key and run.exit_code >= 0


def _write_done(run, key: str) -> None:
    d = ffi.string(run.dir).decode()
    args = " ".join(ffi.string(run.sets[i]).decode() for i in range(run.n_sets))
    with open(os.path.join(d, "done"), "w") as f:
        f.write("exit %d\nmaxrss_kib %d\nwall %.6f\ntimeout %d\nkey %s\nargs %s\n"
                % (run.exit_code, run.maxrss_kib, run.wall, run.timed_out, key, args))


def _run_key(S, run) -> Optional[str]:
    key = ffi.new("char[]", lib.BS_STUDY_KEY_LEN + 1)
    err = new_error()
    if lib.bs_study_run_key(S, run, key, err):
        return None
    return ffi.string(key).decode()


def _run_one(S, run, progress) -> None:
    """Runs one planned run in this process: the scene with the run's
    settings, its folder replaced, every frame written (as `bigstep run
    --quiet --replace`)."""
    from ._sim import Simulation
    sets = [ffi.string(run.sets[i]).decode() for i in range(run.n_sets)]
    scene_path = ffi.string(S.scene_path).decode()
    run.exit_code, run.timed_out, run.maxrss_kib = 1, 0, 0
    t0 = lib.bs_seconds()
    log = os.path.join(ffi.string(run.dir).decode(), "run.log")
    err_msg = ""
    try:
        with Simulation(Scene(scene_path, sets), replace=True) as sim:
            sim.run()
            run.exit_code = 0 if sim.totals["failed"] == 0 else 1
    except KeyboardInterrupt:
        raise
    except Exception as e:  # a failed run is a row marked failed, as with the command line
        err_msg = str(e)
        run.exit_code = 1
    run.wall = lib.bs_seconds() - t0
    try:
        with open(log, "w") as f:
            f.write("bigstep.study (in process): %s\n" % (err_msg or "ok"))
    except OSError:
        pass


def study(scene: Union[SceneSource, str], vary: Vary, qoi: Sequence[str] = (), *, sets: Sets = None,
          out: Optional[str] = None, reference: Optional[str] = None, force: bool = False,
          progress: Optional[Callable[[int, int, Dict[str, Any]], None]] = None) -> StudyResult:
    """A study (``bigstep study``) run in this process.

    scene: a scene file (or a dict/Scene: its resolved JSON is written to
        the study folder and used as the study's scene file).
    vary: ``{"refine": [0, 1, 2], "time.steps_per_frame": [1, 2]}`` or
        ``["refine=0,1,2"]``: the knobs (key paths or shorthands
        steps_per_frame, refine, method, tolerance).
    qoi: quantities of interest of the scene (qoi[].name) compared per run,
        with the GCI along each refine or time knob of three or more levels.
    sets: overrides applied to every run. out: the study folder (default
        out/study/<scene name>). reference: a run folder to compare with
        (default: the finest run). force: rerun runs a done marker says are
        complete (the marker is the command line's: a study folder is shared
        with ``bigstep study``).
    progress: called as progress(i, n_runs, row) after each run.

    The runs run one after another in this process (Ctrl-C stops the study
    with KeyboardInterrupt after the current run's last complete frame).
    Errors: InputError / SceneError with the library's message for a bad
    knob or setting.
    """
    specs = _knob_specs(vary)
    if not specs:
        raise InputError("study: nothing to vary")
    if len(specs) > lib.BS_STUDY_MAX_KNOBS:
        raise InputError("study: at most %d knobs" % lib.BS_STUDY_MAX_KNOBS)
    qoi = [qoi] if isinstance(qoi, str) else list(qoi)
    if len(qoi) > lib.BS_STUDY_MAX_QOI:
        raise InputError("study: at most %d quantities of interest" % lib.BS_STUDY_MAX_QOI)
    if isinstance(scene, (Scene, Mapping)) or (isinstance(scene, str) and scene.lstrip().startswith("{")):
        sc = scene if isinstance(scene, Scene) else Scene(scene)
        folder = out or os.path.join("out", "study", "python_scene")
        os.makedirs(folder, exist_ok=True)
        scene_path = os.path.join(folder, "scene.json")
        with open(scene_path, "w") as f:
            f.write(sc.to_json())
        out = folder
    else:
        scene_path = os.fspath(scene)
    err = new_error()
    knobs = ffi.new("bs_study_knob[]", len(specs))
    n_parsed = 0
    S_pp = ffi.new("bs_study **")
    try:
        for k, spec in enumerate(specs):
            check(lib.bs_study_knob_parse(spec.encode(), ffi.addressof(knobs, k), err), err, InputError)
            n_parsed += 1
            for j in range(k):
                if lib.bs_study_knob_same(ffi.addressof(knobs, j), ffi.addressof(knobs, k)):
                    raise InputError("study: '%s' varies the same key as '%s'" % (spec, specs[j]))
        user = [ffi.new("char[]", s.encode()) for s in _set_strings(sets)]
        qn = [ffi.new("char[]", q.encode()) for q in qoi]
        o = ffi.new("bs_study_opts *")
        sp = ffi.new("char[]", scene_path.encode())
        o.scene = sp
        o.n_sets = len(user)
        user_arr = ffi.new("const char *[]", user) if user else ffi.NULL
        o.sets = user_arr
        o.n_knobs = len(specs)
        o.knobs = knobs
        refp = ffi.new("char[]", reference.encode()) if reference else ffi.NULL
        o.reference = refp
        outp = ffi.new("char[]", out.encode()) if out else ffi.NULL
        o.out = outp
        o.n_qoi = len(qn)
        qarr = ffi.new("const char *[]", qn) if qn else ffi.NULL
        o.qoi = qarr
        check(lib.bs_study_create(o, S_pp, err), err, SceneError)
        S = S_pp[0]
        check(lib.bs_study_check_bodies(S, err), err, InputError)
        check(lib.bs_study_plan(S, err), err, SceneError)
        check(lib.bs_study_measure_bodies(S, err), err, SceneError)
        check(lib.bs_mkdir_p(S.out, err), err)
        n = int(S.n_runs)
        for i in range(n):
            rp = S.runs + i
            r = rp[0]
            key = _run_key(S, rp)
            if not force and key and _read_done(r, key) and (r.timed_out or lib.bs_study_run_complete(rp)
                                                               or r.exit_code != 0):
                if progress:
                    progress(i + 1, n, {"run": ffi.string(r.name).decode(), "cached": True})
                continue
            r.timed_out = 0
            check(lib.bs_mkdir_p(r.dir, err), err)
            _run_one(S, r, progress)
            if key:
                _write_done(r, key)
            if progress:
                progress(i + 1, n, {"run": ffi.string(r.name).decode(), "exit": int(r.exit_code),
                                    "wall": float(r.wall)})
        n_bad = lib.bs_study_evaluate(S)
        check(lib.bs_study_csv_write(S, err), err)
        lib.bs_study_plots_write(S, err)  # data files for gnuplot; not fatal
        return StudyResult(_rows(S), _gcis(S), ffi.string(S.out).decode(),
                           ffi.string(S.ref_dir).decode() or None, int(n_bad))
    finally:
        for k in range(n_parsed):
            lib.bs_study_knob_free(ffi.addressof(knobs, k))
        lib.bs_study_destroy(S_pp)


def _rows(S) -> List[Dict[str, Any]]:
    rows = []
    for i in range(S.n_runs):
        rp = S.runs + i
        r = rp[0]
        d: Dict[str, Any] = {"run": ffi.string(r.name).decode(), "dir": ffi.string(r.dir).decode()}
        for k in range(S.n_knobs):
            kn = S.knobs[k]
            v = ffi.string(kn.vals[r.idx[k]]).decode()
            try:
                v = json.loads(v)
            except ValueError:
                pass
            d[ffi.string(kn.key).decode()] = v
        d.update({
            "method": ffi.string(r.method).decode(), "status": ffi.string(lib.bs_study_run_status(rp)).decode(),
            "exit": int(r.exit_code), "failed_steps": int(r.failed_steps),
            "frames": int(r.n_rows - 1) if r.n_rows > 0 else 0, "steps_per_frame": int(r.spf),
            "fps": float(r.fps), "static": bool(r.is_static), "wall": float(r.wall),
            "s_per_frame": _num(r.s_per_frame), "newton_per_step": _num(r.newton_per_step),
            "cg_per_step": _num(r.cg_per_step), "pos_err_max": _num(r.pos_max), "pos_err_last": _num(r.pos_last),
            "vel_err_max": _num(r.vel_max), "vel_err_last": _num(r.vel_last), "energy_drift": _num(r.drift),
            "inverted_max": int(r.inv_max), "penetration_max": _num(r.pen_max), "reference": bool(r.is_ref),
            "pareto": bool(r.pareto)})
        for q in range(S.n_qoi):
            name = ffi.string(S.qoi[q]).decode()
            d[name] = _num(r.q_last[q])
            d[name + "_err_last"] = _num(r.q_err_last[q])
            d[name + "_err_max"] = _num(r.q_err_max[q])
        rows.append(d)
    return rows


def _gcis(S) -> List[Dict[str, Any]]:
    names = ffi.new("const char *[]", 64)
    nm = lib.bs_study_methods(S, names, 64)
    methods = [ffi.string(names[m]).decode() for m in range(nm)]
    out = []
    for q in range(S.n_qoi):
        qname = ffi.string(S.qoi[q]).decode()
        for k in range(S.n_knobs):
            kn = ffi.addressof(S.knobs, k)
            if not (S.knobs[k].kind == lib.BS_KNOB_REFINE or lib.bs_study_knob_is_time(kn)):
                continue
            for m in methods:
                g = ffi.new("bs_gci *")
                used = ffi.new("int[3]")
                skipped = ffi.new("int *")
                st = lib.bs_study_qoi_gci(S, k, m.encode(), q, g, used, skipped)
                runs = [int(used[j]) for j in range(3)]
                h = [float(lib.bs_study_knob_h(S, S.runs + j, k)) if j >= 0 else None for j in runs]
                f = [float(S.runs[j].q_last[q]) if j >= 0 else None for j in runs]
                out.append({"qoi": qname, "knob": ffi.string(S.knobs[k].key).decode(), "method": m,
                            "status": ffi.string(lib.bs_gci_status_name(st)).decode(), "p": _num(g.p),
                            "extrapolated": _num(g.extrapolated), "e_a": _num(g.e_a), "e_ext": _num(g.e_ext),
                            "gci_fine": _num(g.gci_fine), "gci_coarse": _num(g.gci_coarse),
                            "asymptotic": _num(g.asymptotic),
                            "runs": [ffi.string(S.runs[j].name).decode() if j >= 0 else None for j in runs],
                            "h": h, "values": f, "skipped": int(skipped[0])})
    return out
