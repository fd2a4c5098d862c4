"""Scenes: from a dict, JSON text or a file, with ``--set``-style overrides,
validated by the library (bs_scene_parse / bs_scene_load)."""
from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

from ._bigstep import ffi, lib
from ._errors import SceneError, check, new_error

__all__ = ["Scene", "SceneSource", "Sets", "schema"]

SceneSource = Union["Scene", Mapping[str, Any], str, "os.PathLike[str]"]
Sets = Union[None, Mapping[str, Any], Sequence[str]]


def _set_strings(sets: Sets) -> List[str]:
    """Overrides as the command line's "key.path=value" strings. A mapping's
    values are written as JSON (the library parses a value as JSON, else takes
    it as a string)."""
    if sets is None:
        return []
    if isinstance(sets, str):
        raise TypeError("sets: a list of 'key.path=value' strings or a dict, not a str")
    if isinstance(sets, Mapping):
        out = []
        for k, v in sets.items():
            if not isinstance(k, str):
                raise TypeError("sets: keys must be str, got %r" % (k,))
            out.append("%s=%s" % (k, v if isinstance(v, str) and not _json_like(v) else _dumps(v)))
        return out
    out = []
    for s in sets:
        if not isinstance(s, str):
            raise TypeError("sets: each override must be a 'key.path=value' str, got %r" % (s,))
        out.append(s)
    return out


def _json_like(s: str) -> bool:
    try:
        json.loads(s)
        return True
    except ValueError:
        return False


def _dumps(v: Any) -> str:
    try:
        return json.dumps(v, allow_nan=True)
    except (TypeError, ValueError) as e:
        raise TypeError("a scene value that is not JSON: %s" % e) from None


def _encode(s: str, what: str) -> bytes:
    b = s.encode("utf-8")
    if b"\0" in b:
        raise SceneError("%s: contains a NUL byte" % what, lib.BS_EINPUT)
    return b


class Scene:
    """A validated scene (what to simulate, how, and what to write).

    Build one from
      * a dict (the JSON layout of README "Scenes"), e.g.
        ``Scene({"bodies": [{"mesh": "box", ...}], ...})``;
      * a path to a JSON scene file (``str`` or ``os.PathLike``);
      * JSON text (a ``str`` starting with ``{``);
      * another Scene (its resolved JSON, re-read with new overrides).

    ``sets`` are overrides applied before validation, as ``bigstep run --set``:
    a list of ``"key.path=value"`` strings or a dict ``{"key.path": value}``.
    ``base_dir`` is the folder a dict's or a text's relative mesh paths are
    resolved against (default: the current folder).

    Errors: :class:`bigstep.SceneError` (a ValueError) with the library's
    message and ``.key``, the key path it names.

    The scene is immutable from Python; a :class:`Simulation` borrows it (and
    keeps it alive).
    """

    def __init__(self, source: SceneSource, sets: Sets = None, *, base_dir: Optional[str] = None):
        set_list = _set_strings(sets)
        if isinstance(source, Scene):
            text, name = source.to_json(), source._name
        elif isinstance(source, Mapping):
            text, name = _dumps(dict(source)), None
        elif isinstance(source, os.PathLike) or (isinstance(source, str) and not source.lstrip().startswith("{")):
            text, name = None, os.fspath(source)
        elif isinstance(source, str):
            text, name = source, None
        else:
            raise TypeError("a scene is a dict, a JSON text, a path or a Scene, not %s" % type(source).__name__)
        if text is not None and name is None:
            name = os.path.join(base_dir, "<scene>") if base_dir else None
        self._text, self._name, self._sets = text, name, set_list
        c_sets = [ffi.new("char[]", _encode(s, "--set")) for s in set_list]
        arr = ffi.new("const char *[]", c_sets) if c_sets else ffi.NULL
        out = ffi.new("bs_scene **")
        err = new_error()
        if text is None:
            st = lib.bs_scene_load(_encode(name, "the scene path"), len(c_sets), arr, out, err)
        else:
            st = lib.bs_scene_parse(_encode(text, "the scene text"), _encode(name, "the name") if name else ffi.NULL,
                                    len(c_sets), arr, out, err)
        check(st, err, SceneError)
        self._ptr = ffi.gc(out[0], _destroy_scene)

    # ---- what it says -------------------------------------------------
    @property
    def path(self) -> str:
        """The scene file ("<scene>" for one from a dict or text)."""
        return ffi.string(self._ptr.path).decode()

    @property
    def description(self) -> Optional[str]:
        """The scene's "description", or None."""
        d = self._ptr.description
        return ffi.string(d).decode() if d != ffi.NULL else None

    @property
    def fps(self) -> float:
        """Frames per second (time.fps)."""
        return float(self._ptr.fps)

    @property
    def frames(self) -> int:
        """Frames of a run (time.frames)."""
        return int(self._ptr.frames)

    @property
    def steps_per_frame(self) -> int:
        """Time steps per frame (time.steps_per_frame)."""
        return int(self._ptr.steps_per_frame)

    @property
    def dt(self) -> float:
        """The time step (s): 1 / (fps * steps_per_frame)."""
        return float(self._ptr.dt)

    @property
    def mode(self) -> str:
        """"dynamic" or "static" (solver.mode)."""
        return "static" if lib.bspy_scene_mode(self._ptr) == lib.BS_MODE_STATIC else "dynamic"

    @property
    def n_bodies(self) -> int:
        """Bodies in the scene."""
        return int(self._ptr.n_bodies)

    @property
    def qoi_names(self) -> List[str]:
        """The quantities of interest (qoi[].name), in the scene's order."""
        return [ffi.string(self._ptr.qoi[i].name).decode() for i in range(self._ptr.n_qoi)]

    @property
    def output_dir(self) -> str:
        """output.dir ("" : no output folder)."""
        return ffi.string(self._ptr.out_dir).decode()

    def to_json(self) -> str:
        """The resolved scene as JSON text (every key, defaults filled in,
        mesh paths absolute): bs_scene_write_json."""
        out = ffi.new("char **")
        err = new_error()
        check(lib.bs_scene_write_json(self._ptr, out, err), err)
        try:
            return ffi.string(out[0]).decode()
        finally:
            lib.free(out[0])

    def to_dict(self) -> Dict[str, Any]:
        """The resolved scene as a dict (see :meth:`to_json`)."""
        return json.loads(self.to_json())

    def with_sets(self, sets: Sets) -> "Scene":
        """A new Scene: this one's source with more overrides."""
        if self._text is None:
            return Scene(self._name, self._sets + _set_strings(sets))
        s = Scene.__new__(Scene)
        Scene.__init__(s, self._text, self._sets + _set_strings(sets),
                       base_dir=os.path.dirname(self._name) if self._name else None)
        return s

    def __repr__(self) -> str:
        return "<bigstep.Scene %s: %s, %d bodies, %d frames at %g fps>" % (
            self.path, self.mode, self.n_bodies, self.frames, self.fps)


def _destroy_scene(p):
    pp = ffi.new("bs_scene **", p)
    lib.bs_scene_destroy(pp)


def as_scene(scene: SceneSource, sets: Sets = None) -> Scene:
    """A Scene from any source; a Scene with no sets is returned as is."""
    if isinstance(scene, Scene) and not sets:
        return scene
    return Scene(scene, sets)


def schema() -> Dict[str, Any]:
    """The scene schema (JSON Schema draft-07) as a dict: bs_scene_schema_json."""
    out = ffi.new("char **")
    err = new_error()
    check(lib.bs_scene_schema_json(out, err), err)
    try:
        return json.loads(ffi.string(out[0]).decode())
    finally:
        lib.free(out[0])
