"""Exceptions of the bigstep package: every C error becomes one of these,
carrying the library's own one-line message."""
from __future__ import annotations

import re
from typing import Optional

from ._bigstep import ffi, lib

__all__ = ["Error", "SceneError", "InputError", "FileError", "NumericError", "ClosedError", "BusyError"]


class Error(Exception):
    """An error reported by the bigstep library.

    Attributes:
        code: the library's status code (negative ``BS_E*``).
        status: its name ("io", "input", "nomem", "numeric", "gmsh", "internal").
        message: the library's one-line message, unchanged.
    """

    def __init__(self, message: str, code: int = -6):
        super().__init__(message)
        self.message = message
        self.code = code
        self.status = ffi.string(lib.bs_status_name(code)).decode() if code < 0 else "python"


class SceneError(Error, ValueError):
    """A scene the library refused: an unknown key, a wrong type, an
    impossible value, a missing mesh or group file.

    Attributes:
        key: the key path the message names (e.g. ``"obstacles.0.friction"``),
            or None when the message names none.
        file: the scene file (or ``"<scene>"``/``"<dict>"``) the message names.
    """

    def __init__(self, message: str, code: int = -2):
        super().__init__(message, code)
        self.file, self.key = _split_key(message)


class InputError(Error, ValueError):
    """Malformed input other than a scene (a mesh, an argument)."""


class FileError(Error, OSError):
    """A file that is missing, unreadable or unwritable (BS_EIO)."""


class NumericError(Error, ArithmeticError):
    """NaN/Inf, or a singular or degenerate quantity (BS_ENUMERIC)."""


class ClosedError(Error, ValueError):
    """An operation on a closed Simulation."""

    def __init__(self, message: str = "the simulation is closed"):
        super().__init__(message, -2)


class BusyError(Error, RuntimeError):
    """A Simulation used while it is running (from another thread, or from
    its own frame callback)."""

    def __init__(self, message: str):
        super().__init__(message, -2)


_KEY = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.([A-Za-z0-9_]+|\*))*$")


def _split_key(message: str):
    """(file, key path) of a scene message "FILE: KEY.PATH: problem"."""
    parts = message.split(": ")
    if len(parts) < 2:
        return None, None
    file = parts[0]
    for p in parts[1:-1] or parts[1:2]:
        p = p.strip()
        if p.startswith("--set "):
            p = p[6:].strip("'\"").split("=", 1)[0]
        if _KEY.match(p) and not p.endswith((".json", ".msh")):
            return file, p
    return file, None


def raise_error(code: int, err, cls=None):
    """Raise the exception of a failed call (status `code`, bs_error `err`)."""
    msg = ffi.string(err.msg).decode("utf-8", "replace") if err is not None else ""
    if not msg:
        msg = "bigstep: %s error" % ffi.string(lib.bs_status_name(code)).decode()
    if cls is None:
        cls = {lib.BS_EIO: FileError, lib.BS_EINPUT: InputError, lib.BS_ENUMERIC: NumericError}.get(code, Error)
        if code == lib.BS_ENOMEM:
            raise MemoryError(msg)
    if cls is FileError:
        e = FileError(msg, code)
    else:
        e = cls(msg, code)
    raise e


def check(code: int, err, cls=None) -> int:
    """Raise for a negative status; return it otherwise."""
    if code < 0:
        raise_error(code, err, cls)
    return code


def new_error():
    err = ffi.new("bs_error *")
    return err


def message(err) -> str:
    return ffi.string(err.msg).decode("utf-8", "replace")


def key_of(message: str) -> Optional[str]:
    return _split_key(message)[1]
