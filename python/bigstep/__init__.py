"""bigstep: finite elements for deformable solids at large time steps, from
Python.

A binding (cffi, API mode) of the installed C library libbigstep.so and its
public headers. Quick start::

    import bigstep
    scene = bigstep.Scene("data/scenes/beam_sag.json", sets={"output.dir": ""})
    with bigstep.Simulation(scene) as sim:
        sim.run()                       # the static solve of this scene
        print(sim.qoi()["tip_y"])       # a quantity of interest
        x = sim.x                       # (n, 3) view of the positions (no copy)

Public names:
    Scene, schema               scenes (dict, JSON text or file; overrides)
    Simulation, STEP_DTYPE      stepping, state views, fields, QoIs, statistics
    Mesh, Group, mesh           meshes as arrays; meshio conversion
    study, StudyResult          convergence studies in process (GCI)
    PythonTerm, FunctionTerm, BlockMatrix   energy terms in Python
    Error, SceneError, InputError, FileError, NumericError, ClosedError, BusyError
    version                     the C library's version
"""
from ._bigstep import ffi as _ffi, lib as _lib
from ._errors import BusyError, ClosedError, Error, FileError, InputError, NumericError, SceneError
from ._mesh import Group, Mesh, mesh
from ._scene import Scene, schema
from ._sim import STEP_DTYPE, Simulation
from ._study import StudyResult, study
from ._terms import BlockMatrix, FunctionTerm, PythonTerm

#: The C library's version ("MAJOR.MINOR.PATCH").
version: str = _ffi.string(_lib.bs_version()).decode()
__version__ = version

__all__ = ["Scene", "schema", "Simulation", "STEP_DTYPE", "Mesh", "Group", "mesh", "study", "StudyResult",
           "PythonTerm", "FunctionTerm", "BlockMatrix", "Error", "SceneError", "InputError", "FileError",
           "NumericError", "ClosedError", "BusyError", "version"]
