"""Energy terms written in Python (bs_term_create with callbacks into
Python), for prototyping.

Cost: every call of value, gradient or hessian crosses from C into Python:
the GIL is taken, NumPy views of x (and g) are made (no copy), and the
Python code runs; about 5-20 microseconds of overhead per call on top of
the NumPy work, and the minimizer calls gradient and hessian once per Newton
iteration and value/gradient once per line-search trial. A term over all
vertices in vectorized NumPy costs a few passes over 3n doubles per call;
a Python loop over vertices costs about 1 microsecond per vertex per call.
For production, write the term in C (examples/02_spring)."""
from __future__ import annotations

import weakref
from typing import Callable, Optional

import numpy as np

from ._bigstep import ffi, lib
from ._errors import InputError, check, new_error

__all__ = ["PythonTerm", "FunctionTerm", "BlockMatrix"]


class BlockMatrix:
    """The Hessian a term adds into: 3x3 blocks on the mesh's pattern (one
    block per pair of vertices that share a tet, and the diagonal). Valid
    only during the hessian() call that receives it."""

    def __init__(self, H, n):
        self._H = H
        self.n = n

    def add(self, i, j, blocks) -> None:
        """H[i_k, j_k] += blocks[k] (blocks: (m, 3, 3), row-major: block
        (i, j)'s entry (a, b) is d2E / dx_i,a dx_j,b). A pair (i, j) that
        shares no tet is not in the pattern: InputError."""
        if self._H is None:
            raise InputError("BlockMatrix: used after the hessian() call that received it")
        i = np.ascontiguousarray(i, dtype=np.int32).ravel()
        j = np.ascontiguousarray(j, dtype=np.int32).ravel()
        B = np.ascontiguousarray(blocks, dtype=np.float64).reshape(-1, 3, 3)
        if not (len(i) == len(j) == len(B)):
            raise InputError("BlockMatrix.add: %d rows, %d columns and %d blocks" % (len(i), len(j), len(B)))
        if not len(i):
            return
        r = lib.bspy_bsr_add(self._H, len(i), ffi.cast("int32_t *", ffi.from_buffer(i)),
                             ffi.cast("int32_t *", ffi.from_buffer(j)), ffi.cast("double *", ffi.from_buffer(B)))
        if r < 0:
            k = -1 - r
            raise InputError("BlockMatrix.add: block (%d, %d) is not in the mesh's pattern (the vertices share no "
                             "tet, or an index is outside [0, %d))" % (i[k], j[k], self.n))

    def add_diagonal(self, vertices, blocks) -> None:
        """H[v, v] += blocks[k] for v = vertices[k] (blocks (m, 3, 3), or a
        scalar s for s I on each)."""
        v = np.asarray(vertices, dtype=np.int64).ravel()
        if v.size and (v.min() < 0 or v.max() >= self.n):
            raise InputError("BlockMatrix.add_diagonal: a vertex outside [0, %d)" % self.n)
        B = np.asarray(blocks, dtype=np.float64)
        if B.ndim == 0:
            B = np.broadcast_to(B * np.eye(3), (len(v), 3, 3))
        self.add(v, v, np.broadcast_to(B, (len(v), 3, 3)))


class PythonTerm:
    """An energy term E(x) written in Python, added to a simulation's
    objective with :meth:`Simulation.add_term` (before its first step).

    Subclass it and define (x is a read-only (n, 3) view of the iterate, m;
    E in J):
      * ``value(x) -> E``
      * ``gradient(x, g) -> E``: ADD dE/dx into g, a writable (n, 3) view
        (it holds the other terms' gradients);
      * ``hessian(x, H)``: ADD d2E/dx2 into H (a :class:`BlockMatrix`:
        ``H.add_diagonal(vertices, blocks)``, ``H.add(i, j, blocks)``).
    Raise an exception to report an error: the call is then reported to the
    minimizer as "not evaluable" (the step goes on as it does for such a
    point), and once the stepping call (step, advance_frame, run, statics)
    is over the exception is raised from it. To say that x is outside the term's
    domain (the line search then shrinks the step) return ``None`` from value
    or gradient.

    Attributes (set before add_term): ``name``; ``dynamic_only`` (skipped in
    static solves); ``quadratic`` (E is a polynomial of degree <= 2 in x);
    ``external`` (an external load: gradient independent of x).

    Cost: see the module's docstring (a crossing into Python per call, a few
    to tens of microseconds, plus the NumPy work).
    """

    name: str = "python"
    dynamic_only: bool = False
    quadratic: bool = False
    external: bool = False
    _exc: Optional[BaseException] = None
    _n: int = 0
    _owner_ref = None

    def value(self, x: np.ndarray) -> Optional[float]:
        """The energy at x (J)."""
        raise NotImplementedError

    def gradient(self, x: np.ndarray, g: np.ndarray) -> Optional[float]:
        """Adds dE/dx into g; returns E."""
        raise NotImplementedError

    def hessian(self, x: np.ndarray, H: BlockMatrix) -> None:
        """Adds d2E/dx2 into H."""
        raise NotImplementedError


class FunctionTerm(PythonTerm):
    """A PythonTerm from three callables: value(x) -> E, gradient(x, g) -> E
    (adding into g), hessian(x, H)."""

    def __init__(self, value: Callable, gradient: Callable, hessian: Callable, name: str = "python", *,
                 dynamic_only: bool = False, quadratic: bool = False, external: bool = False):
        self._v, self._g, self._h = value, gradient, hessian
        self.name, self.dynamic_only, self.quadratic, self.external = name, dynamic_only, quadratic, external

    def value(self, x):
        """Calls the value callable."""
        return self._v(x)

    def gradient(self, x, g):
        """Calls the gradient callable (it adds into g)."""
        return self._g(x, g)

    def hessian(self, x, H):
        """Calls the hessian callable (it adds into H)."""
        return self._h(x, H)


def _arr(term, ptr, readonly=True):
    """An (n, 3) view of a vector the integrator hands the term. The view
    keeps the simulation's memory alive (a reference to its owner, as
    Simulation.x does), so one kept past the call never reads freed memory
    (it shows whatever the integrator put there later)."""
    from ._sim import _view
    owner = term._owner_ref() if term._owner_ref is not None else None
    if owner is None:  # not in a simulation (check_term on plain arrays does not come here)
        raise RuntimeError("the term's simulation is gone")
    return _view(owner, ptr, (term._n, 3), "<f8", readonly)


def _fail(term, e):
    if term._exc is None:
        term._exc = e
    return lib.BS_TERM_NOT_EVALUABLE


@ffi.def_extern()
def bspy_py_value(py, t, x, E):
    term = ffi.from_handle(py)
    try:
        e = term.value(_arr(term, x))
        if e is None:
            return lib.BS_TERM_NOT_EVALUABLE
        E[0] = float(e)
        return lib.BS_TERM_OK
    except BaseException as exc:
        return _fail(term, exc)


@ffi.def_extern()
def bspy_py_gradient(py, t, x, E, g):
    term = ffi.from_handle(py)
    try:
        e = term.gradient(_arr(term, x), _arr(term, g, readonly=False))
        if e is None:
            return lib.BS_TERM_NOT_EVALUABLE
        E[0] = float(e)
        return lib.BS_TERM_OK
    except BaseException as exc:
        return _fail(term, exc)


@ffi.def_extern()
def bspy_py_hessian(py, t, x, H):
    term = ffi.from_handle(py)
    Hm = BlockMatrix(H, term._n)
    try:
        term.hessian(_arr(term, x), Hm)
        return lib.BS_TERM_OK
    except BaseException as exc:
        return _fail(term, exc)
    finally:
        Hm._H = None  # valid during the call only


def _register_term(owner, s, term, n):
    if not isinstance(term, PythonTerm):
        raise TypeError("add_term: a bigstep.PythonTerm, not %s" % type(term).__name__)
    if getattr(term, "_n", 0):
        raise InputError("add_term: this term is already in a simulation")
    term._n = n
    term._exc = None
    term._owner_ref = weakref.ref(owner)
    h = ffi.new_handle(term)
    owner.terms.append((term, h))  # before the C term exists: it calls through h
    err = new_error()
    check(lib.bspy_add_term(s, str(term.name).encode()[:127], h, int(bool(term.dynamic_only)),
                            int(bool(term.quadratic)), int(bool(term.external)), err), err)
