"""python/examples/cantilever_refinement.py runs and writes its plot."""
import os
import subprocess
import sys

import pytest


def test_cantilever_example(src, tmp_path):
    pytest.importorskip("matplotlib")
    script = os.path.join(src, "python", "examples", "cantilever_refinement.py")
    out = subprocess.run([sys.executable, script, str(tmp_path)], capture_output=True, text=True,
                         env=dict(os.environ, LEVELS="3"), timeout=600)
    assert out.returncode == 0, out.stderr
    assert "GCI along refine" in out.stdout
    png = tmp_path / "tip_deflection.png"
    assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
