#!/usr/bin/python3
"""The cost of driving bigstep from Python (not a test).

    /usr/bin/python3 bench/python_overhead.py [--cli build/app/bigstep] [--reps 5] [--force]

For data/scenes/cube_stretch.json and the paper's Figure 7
(data/scenes/paper/fig7_two_spheres.json), 24 frames each: the wall time of
`bigstep run` (a process: start, scene, mesh, run, its folder) against the
same run from Python in this process (Scene, Simulation, run(), close(): the
same folder written), median of --reps, alternating; then the cost of reading
sim.x once per frame (a view: O(1), independent of the vertex count) against
copying it, and the cost of a call into a Python energy term (a term that
adds nothing, counted). Prints a table with ratios and writes it to
bench/results/python-overhead.txt.

Timings are refused (the file says "not measured") when the 1-minute load
average is above 3 (other builds on the machine), unless --force.
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.dirname(HERE)
SCENES = [("cube_stretch", "data/scenes/cube_stretch.json"),
          ("fig7_two_spheres", "data/scenes/paper/fig7_two_spheres.json")]
FRAMES = 24


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=os.path.join(SRC, "build", "app", "bigstep"))
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "python-overhead.txt"))
    a = ap.parse_args()
    import bigstep

    load = os.getloadavg()[0]
    head = ["# bench/python_overhead.py: bigstep from Python against the command line",
            "# %s, bigstep %s, Python %s, OMP_NUM_THREADS=%s, %d cores, 1-min load %.2f"
            % (time.strftime("%Y-%m-%d %H:%M:%S"), bigstep.version, sys.version.split()[0],
               os.environ.get("OMP_NUM_THREADS", "(unset)"), os.cpu_count(), load)]
    if load > 3 and not a.force:
        lines = head + ["not measured: the machine is loaded (1-min load average %.2f > 3)" % load]
        _write(a.out, lines)
        return
    tmp = tempfile.mkdtemp(prefix="bs_pybench_")
    rows = []
    try:
        for name, rel in SCENES:
            scene = os.path.join(SRC, rel)
            sets = ["time.frames=%d" % FRAMES]
            t_cli, t_py = [], []
            for r in range(a.reps):
                d = os.path.join(tmp, "%s_cli_%d" % (name, r))
                t0 = time.perf_counter()
                subprocess.run([a.cli, "run", scene, "--quiet", "--set", sets[0], "--set", "output.dir=" + d],
                               check=True, stdout=subprocess.DEVNULL)
                t_cli.append(time.perf_counter() - t0)
                d = os.path.join(tmp, "%s_py_%d" % (name, r))
                t0 = time.perf_counter()
                with bigstep.Simulation(bigstep.Scene(scene, sets + ["output.dir=" + d])) as sim:
                    sim.run()
                    n = sim.n_vertices
                t_py.append(time.perf_counter() - t0)
            rows.append((name, n, statistics.median(t_cli), statistics.median(t_py)))

        # reading sim.x per frame: a view (O(1)) against a copy (O(n))
        reads = []
        for name, rel in SCENES:
            sim = bigstep.Simulation(bigstep.Scene(os.path.join(SRC, rel), ["output.dir="]))
            k = 20000
            t0 = time.perf_counter()
            for _ in range(k):
                x = sim.x
            t_view = (time.perf_counter() - t0) / k
            t0 = time.perf_counter()
            for _ in range(k // 10):
                x = sim.x.copy()
            t_copy = (time.perf_counter() - t0) / (k // 10)
            reads.append((name, sim.n_vertices, t_view, t_copy))
            sim.close()
            del x

        # a call into a Python term: a cube_stretch run with a term that adds nothing
        class Zero(bigstep.PythonTerm):
            name = "zero"
            calls = 0

            def value(self, x):
                Zero.calls += 1
                return 0.0

            def gradient(self, x, g):
                Zero.calls += 1
                return 0.0

            def hessian(self, x, H):
                Zero.calls += 1

        # a tiny scene (a 2^3-cell cube, 240 frames), where a step costs little
        # beside the calls, so that their cost shows
        scene = bigstep.Scene(os.path.join(SRC, SCENES[0][1]), ["time.frames=240", "output.dir=",
                                                               "bodies.0.box.cells=[2,2,2]"])
        best = [float("inf"), float("inf")]
        for r in range(max(a.reps, 3)):
            for with_term in (0, 1):
                sim = bigstep.Simulation(scene)
                if with_term:
                    Zero.calls = 0
                    sim.add_term(Zero())
                t0 = time.perf_counter()
                sim.run()
                best[with_term] = min(best[with_term], time.perf_counter() - t0)
                sim.close()
        calls = Zero.calls
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    lines = head + ["", "24-frame runs (wall seconds, median of %d; both write the scene's run folder)" % a.reps,
                    "%-18s %9s %12s %12s %8s" % ("scene", "vertices", "cli s", "python s", "py/cli")]
    for name, n, c, p in rows:
        lines.append("%-18s %9d %12.3f %12.3f %8.3f" % (name, n, c, p, p / c))
    lines += ["", "reading the state once per frame",
              "%-18s %9s %14s %14s %8s" % ("scene", "vertices", "sim.x (us)", "copy (us)", "copy/x")]
    for name, n, tv, tc in reads:
        lines.append("%-18s %9d %14.2f %14.2f %8.1f" % (name, n, 1e6 * tv, 1e6 * tc, tc / tv))
    lines += ["", "a Python energy term (cube_stretch on a 2^3-cell cube, 240 frames, a term that adds nothing)",
              "without %.3f s, with %.3f s, %d calls: %.1f us per call into Python"
              % (best[0], best[1], calls, 1e6 * (best[1] - best[0]) / max(calls, 1))]
    end = os.getloadavg()[0]
    lines += ["", "1-min load at the end %.2f%s" % (end, " (above 3: other work ran meanwhile; the figures are "
                                                     "disturbed)" if end > 3 else "")]
    _write(a.out, lines)


def _write(path, lines):
    text = "\n".join(lines) + "\n"
    print(text, end="")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
