"""Studies in process: the table and the GCI, without a subprocess."""
import os
import subprocess
from unittest import mock

import pytest

import bigstep


def test_refinement_study_with_gci(src, tmp_path):
    scene = os.path.join(src, "data", "scenes", "beam_sag.json")
    with mock.patch.object(subprocess, "Popen", side_effect=AssertionError("no subprocess")):
        r = bigstep.study(scene, vary={"refine": [0, 1, 2]}, qoi=["tip_y"],
                          sets={"bodies.0.box.cells": [10, 1, 1], "output.vtu_every": 0},
                          out=str(tmp_path / "study"))
    assert len(r.rows) == 3 and all(row["status"] == "ok" for row in r.rows)
    assert [row["refine"] for row in r.rows] == [0, 1, 2]
    assert sum(row["reference"] for row in r.rows) == 1
    tips = r.column("tip_y")
    assert all(t < 0 for t in tips)
    assert os.path.exists(os.path.join(r.out, "study.csv"))
    g = [x for x in r.gci if x["qoi"] == "tip_y" and x["knob"] == "refine"]
    assert len(g) == 1
    g = g[0]
    assert g["status"] in ("monotone", "oscillatory", "divergent", "converged", "no_order")
    assert sorted(g["h"]) == [0.25, 0.5, 1.0]
    if g["status"] == "monotone":
        assert g["p"] > 0 and g["extrapolated"] < 0
    # a second call reuses the runs (the command line's done markers)
    seen = []
    r2 = bigstep.study(scene, vary={"refine": [0, 1, 2]}, qoi=["tip_y"],
                       sets={"bodies.0.box.cells": [10, 1, 1], "output.vtu_every": 0},
                       out=str(tmp_path / "study"), progress=lambda i, n, d: seen.append(d))
    assert all(d.get("cached") for d in seen) and r2.column("tip_y") == tips


def test_study_errors(src, tmp_path):
    scene = os.path.join(src, "data", "scenes", "beam_sag.json")
    with pytest.raises(bigstep.InputError):
        bigstep.study(scene, vary={"refine": []}, out=str(tmp_path / "s"))
    with pytest.raises(bigstep.InputError):
        bigstep.study(scene, vary={}, out=str(tmp_path / "s"))
    with pytest.raises(bigstep.Error):
        bigstep.study(scene, vary={"no.such.key": [1, 2]}, out=str(tmp_path / "s"))
    with pytest.raises(bigstep.SceneError):
        bigstep.study(str(tmp_path / "missing.json"), vary={"refine": [0, 1]}, out=str(tmp_path / "s"))
