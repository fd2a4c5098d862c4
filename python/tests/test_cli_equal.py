"""A scene built as a dict gives the command line's frames.csv, bit for bit."""
import csv
import json
import os
import subprocess

import bigstep
from conftest import cube_scene


def _rows(path):
    with open(path) as f:
        return list(csv.reader(f))


def _compare(a, b):
    ra, rb = _rows(a), _rows(b)
    assert ra[0] == rb[0] and len(ra) == len(rb) > 1
    # every column but `seconds` (the solver's wall time) as written, character for character
    skip = ra[0].index("seconds")
    for x, y in zip(ra[1:], rb[1:]):
        assert [v for i, v in enumerate(x) if i != skip] == [v for i, v in enumerate(y) if i != skip]


def test_dict_scene_frames_csv_equals_cli(cli, tmp_path):
    d = cube_scene()
    d["output"] = {"dir": str(tmp_path / "py"), "stats": True, "states": True}
    # the command line on the same scene (a file of the same dict), into another folder
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(d))
    subprocess.run([cli, "run", str(p), "--quiet", "--set", "output.dir=%s" % (tmp_path / "cli")], check=True,
                   env=dict(os.environ, OMP_NUM_THREADS="2"))
    with bigstep.Simulation(d) as sim:
        sim.run()
    _compare(tmp_path / "py" / "frames.csv", tmp_path / "cli" / "frames.csv")
    # the states too, bit for bit (state.bin: x and v of every frame)
    assert (tmp_path / "py" / "state.bin").read_bytes() == (tmp_path / "cli" / "state.bin").read_bytes()
    assert (tmp_path / "py" / "summary.txt").exists()


def test_frames_by_hand_equal_cli(cli, tmp_path):
    """advance_frame() and step() write the same folder as run()."""
    d = cube_scene()
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(d))
    subprocess.run([cli, "run", str(p), "--quiet", "--set", "output.dir=%s" % (tmp_path / "cli")], check=True)
    with bigstep.Simulation(d, output=str(tmp_path / "py")) as sim:
        sim.step()
        sim.advance_frame()
        sim.run(2)
        sim.run()
    _compare(tmp_path / "py" / "frames.csv", tmp_path / "cli" / "frames.csv")


def test_cube_stretch_file_equals_cli(cli, src, tmp_path):
    scene = os.path.join(src, "data", "scenes", "cube_stretch.json")
    sets = ["time.frames=3", "output.vtu_every=0"]
    subprocess.run([cli, "run", scene, "--quiet", "--set", "output.dir=%s" % (tmp_path / "cli")] +
                   sum((["--set", s] for s in sets), []), check=True)
    with bigstep.Simulation(bigstep.Scene(scene, sets), output=str(tmp_path / "py")) as sim:
        sim.run()
    _compare(tmp_path / "py" / "frames.csv", tmp_path / "cli" / "frames.csv")


def test_existing_folder_is_refused_like_cli(tmp_path):
    d = cube_scene()
    with bigstep.Simulation(d, output=str(tmp_path / "o")) as sim:
        sim.run(1)
    try:
        bigstep.Simulation(d, output=str(tmp_path / "o"))
    except bigstep.InputError as e:
        assert "earlier run" in str(e) or "holds" in str(e)
    else:
        raise AssertionError("an earlier run's folder was not refused")
    with bigstep.Simulation(d, output=str(tmp_path / "o"), replace=True) as sim:
        sim.run(1)
