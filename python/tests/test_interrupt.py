"""Ctrl-C stops a run at the end of a frame, as the command line does."""
import os
import signal
import subprocess
import sys
import time

SCRIPT = r"""
import sys, bigstep, numpy as np
d = {"time": {"fps": 24, "frames": 400, "steps_per_frame": 1},
     "solver": {"tolerance": 1e-8},
     "gravity": [0, -9.8, 0],
     "bodies": [{"mesh": "box", "box": {"cells": [10, 10, 10], "size": [1, 1, 1]},
                 "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3, "density": 1000},
                 "scripted": [{"group": "xmin", "fixed": True}]}],
     "output": {"dir": ""}}
sim = bigstep.Simulation(d)
def cb(s, f):
    if f["frame"] == 2:
        print("running", flush=True)
try:
    sim.run(callback=cb)
    print("finished")
except KeyboardInterrupt:
    print("interrupted", sim.frame, repr(sim.time), repr(sim.frame / 24.0), flush=True)
    sim.advance_frame()  # still usable
    print("continued", sim.frame, flush=True)
"""


def test_sigint_stops_at_a_frame_end():
    p = subprocess.Popen([sys.executable, "-c", SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=dict(os.environ, OMP_NUM_THREADS="1"))
    line = p.stdout.readline()
    assert line.strip() == "running", line + p.stderr.read()
    time.sleep(0.3)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    words = out.split()
    assert words[0] == "interrupted", out + err
    frame = int(words[1])
    assert 2 <= frame < 400
    assert words[2] == words[3]  # the time of a whole frame: a frame cut short was undone
    assert "continued %d" % (frame + 1) in out


STEP_SCRIPT = r"""
import bigstep
d = {"time": {"fps": 24, "frames": 400, "steps_per_frame": 3},
     "solver": {"tolerance": 1e-8},
     "bodies": [{"mesh": "box", "box": {"cells": [8, 8, 8], "size": [1, 1, 1]},
                 "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3, "density": 1000},
                 "scripted": [{"group": "xmin", "fixed": True}]}],
     "output": {"dir": ""}}
sim = bigstep.Simulation(d)
n = 0
try:
    while True:
        sim.step()
        n += 1
        if n == 3:
            print("running", flush=True)
except KeyboardInterrupt:
    f = sim.frame
    print("interrupted", f, flush=True)
    sim.advance_frame()  # the rest of the frame (the interrupted step was completed and counted)
    print("continued", sim.frame, sim.time == (f + 1) / 24.0, flush=True)
"""


def test_sigint_during_steps_keeps_the_count():
    p = subprocess.Popen([sys.executable, "-c", STEP_SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert p.stdout.readline().strip() == "running"
    time.sleep(0.3)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    w = out.split()
    assert w[0] == "interrupted", out + err
    frame = int(w[1])
    assert "continued %d True" % (frame + 1) in out
