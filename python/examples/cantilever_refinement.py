#!/usr/bin/python3
"""A cantilever sagging under gravity, refined until its tip deflection
converges: bigstep from Python, read top to bottom.

    /usr/bin/python3 python/examples/cantilever_refinement.py [OUT_DIR]

writes OUT_DIR/tip_deflection.png (default out/python_cantilever) and prints
the table of the study and its grid convergence index (GCI).

The scene is data/scenes/beam_sag.json: a 1 m x 0.1 m x 0.1 m beam of
fixed-corotated material (E = 1e8 Pa, nu = 0.3, rho = 1000 kg/m^3) clamped
at x = 0, solved statically under gravity. Its quantity of interest "tip_y"
is the mean vertical displacement of the free end (the group "xmax").
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import bigstep  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "..", "data", "scenes", "beam_sag.json")
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join("out", "python_cantilever")
LEVELS = int(os.environ.get("LEVELS", "4"))  # refinement levels (the tests run 3)
os.makedirs(OUT, exist_ok=True)

# Step 1: the scene. A file, with overrides as `bigstep run --set` takes them
# (here as a dict: no output folder, no VTU frames). Bad keys or values raise
# bigstep.SceneError with the library's message and the key path.
scene = bigstep.Scene(SCENE, sets={"output.dir": ""})
print(scene)
print("  %s" % scene.description)

# Step 2: one simulation, to look at it. The state is a NumPy view of the
# library's memory (no copy): sim.x is (n, 3) positions in metres.
with bigstep.Simulation(scene) as sim:
    stats = sim.statics()
    x = sim.x
    print("static solve: %d Newton iterations, |grad E| %.2e N" % (stats["iterations"], stats["grad_max"]))
    print("tip deflection %.6g m, clamp reaction %.6g N" % (sim.qoi()["tip_y"], sim.qoi()["clamp_y"]))
    vm = sim.fields(["von_mises"])["von_mises"]
    print("largest von Mises stress %.4g Pa over %d tets" % (vm.max(), len(vm)))
    print("lowest vertex at y = %.6g m" % x[:, 1].min())

# Step 3: the refinement study. Each level splits every tet into 8
# (h = 2^-refine); the library plans the runs, each run writes its own run
# folder, and the study compares them with the finest and fits the GCI of
# the tip deflection (Richardson extrapolation, Roache's safety factor 1.25).
# A coarser base mesh than the scene's keeps the example quick.
result = bigstep.study(SCENE, vary={"refine": list(range(LEVELS))}, qoi=["tip_y"],
                       sets={"bodies.0.box.cells": [10, 1, 1], "output.vtu_every": 0},
                       out=os.path.join(OUT, "study"),
                       progress=lambda i, n, d: print("  run %d/%d %s" % (i, n, d["run"])))

print("\n%-10s %14s %12s %12s" % ("run", "tip_y (m)", "s/frame", "error"))
for row in result.rows:
    print("%-10s %14.8f %12.4g %12.3g" % (row["run"], row["tip_y"], row["s_per_frame"] or float("nan"),
                                          row["tip_y_err_last"] if row["tip_y_err_last"] is not None
                                          else float("nan")))
gci = [g for g in result.gci if g["qoi"] == "tip_y" and g["knob"] == "refine"][0]
print("\nGCI along refine (the three finest levels): %s convergence" % gci["status"])
if gci["status"] == "monotone":
    print("  observed order p = %.3g, extrapolated tip_y = %.8g m, GCI_fine = %.3g%%"
          % (gci["p"], gci["extrapolated"], 100 * gci["gci_fine"]))

# Step 4: the plot. Tip deflection against h, with the extrapolated value.
h = np.array([2.0 ** -row["refine"] for row in result.rows])
tip = np.array([row["tip_y"] for row in result.rows])
fig, ax = plt.subplots(figsize=(5.5, 4))
ax.semilogx(h, -tip, "o-", label="bigstep (fixed corotated P1 tets)")
if gci["status"] == "monotone":
    ax.axhline(-gci["extrapolated"], color="gray", ls="--", label="Richardson extrapolation")
# Euler-Bernoulli's tip deflection q L^4 / (8 E I) of the same beam, for
# scale (q = rho g A, I = b t^3 / 12; it leaves out shear, which the
# solid model has).
q, L, E, b, t = 1000 * 9.8 * 0.1 * 0.1, 1.0, 1e8, 0.1, 0.1
ax.axhline(q * L**4 / (8 * E * b * t**3 / 12), color="C2", ls=":", label="Euler-Bernoulli beam theory")
ax.set_xticks(h)
ax.set_xticklabels(["%g" % v for v in h])
ax.minorticks_off()
ax.set_xlabel("h (relative cell size, 2^-refine)")
ax.set_ylabel("tip deflection (m)")
ax.set_title("Cantilever under gravity: refinement study")
ax.invert_xaxis()
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
png = os.path.join(OUT, "tip_deflection.png")
fig.savefig(png, dpi=120)
print("\nwrote %s" % png)
