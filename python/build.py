#!/usr/bin/env python3
"""Builds the Python package bigstep against an installed libbigstep and
installs it.

    /usr/bin/python3 python/build.py --prefix /usr/local [--dest DIR] [--build-dir DIR]

--prefix  where libbigstep is installed (PREFIX/include/bigstep, PREFIX/lib)
--dest    the folder the package `bigstep` goes into (default: for the prefix
          /usr/local, /usr/local/lib/python3.X/dist-packages, on the path of
          Debian's /usr/bin/python3; for another prefix, PREFIX/python)
--build-dir  cffi's scratch folder (default: build/python under the source tree)

Needs Debian's python3-dev and python3-cffi (and python3-numpy at run time).
Run it with the Python that will import the package (/usr/bin/python3).
"""
import argparse
import glob
import os
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--prefix", default="/usr/local")
    ap.add_argument("--dest")
    ap.add_argument("--build-dir", default=os.path.join(HERE, "..", "build", "python"))
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args()
    prefix = os.path.abspath(a.prefix)
    if not os.path.exists(os.path.join(prefix, "include", "bigstep", "bigstep.h")):
        sys.exit("build.py: no %s/include/bigstep/bigstep.h: install the library first "
                 "(cmake --install build --prefix %s)" % (prefix, prefix))
    dest = a.dest
    if not dest:
        if prefix == "/usr/local":
            dest = "/usr/local/lib/python3.%d/dist-packages" % sys.version_info[1]
        else:
            dest = os.path.join(prefix, "python")
    sys.path.insert(0, os.path.join(HERE, "bigstep"))
    from _build_ffi import make_ffi  # noqa: E402
    ffi = make_ffi(prefix)
    bdir = os.path.abspath(a.build_dir)
    os.makedirs(bdir, exist_ok=True)
    so = ffi.compile(tmpdir=bdir, verbose=not a.quiet)
    pkg = os.path.join(dest, "bigstep")
    tmp = pkg + ".tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    for f in glob.glob(os.path.join(HERE, "bigstep", "*")):
        name = os.path.basename(f)
        if name.endswith((".py", ".pyi", ".typed")) and name != "_build_ffi.py":
            shutil.copy2(f, tmp)
    shutil.copy2(so, tmp)
    shutil.rmtree(pkg, ignore_errors=True)
    os.replace(tmp, pkg)
    print("build.py: installed the package bigstep into %s (library %s/lib)" % (pkg, prefix))


if __name__ == "__main__":
    main()
