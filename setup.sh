#!/usr/bin/env bash
# bigstep set-up on Debian 12 (as root): installs what is missing, builds, and
#   bash setup.sh run    runs the main job on the default scene
#   bash setup.sh test   runs the whole test suite (CTest)
#   bash setup.sh sanitize  builds with -fsanitize=address,undefined (Debug, in
#                        build-asan) and runs the suite's "sanitize" subset
#   bash setup.sh build  only installs and builds
# Environment: BUILD_DIR (default build), BUILD_TYPE (default Release), JOBS.
set -euo pipefail
cd "$(dirname "$0")"
mode=${1:-run}
if [ "$mode" = sanitize ]; then
  BUILD_DIR=${BUILD_DIR:-build-asan}
  BUILD_TYPE=${BUILD_TYPE:-Debug}
  CMAKE_ARGS="${CMAKE_ARGS:-} -DBS_SANITIZE=ON"
fi
BUILD_DIR=${BUILD_DIR:-build}
BUILD_TYPE=${BUILD_TYPE:-Release}
JOBS=${JOBS:-$(nproc)}

# Debian packages bigstep needs (build, run, tests, plots).
pkgs=(build-essential cmake pkg-config libgmsh-dev gmsh libmetis-dev libsuitesparse-dev
      libcgal-dev libeigen3-dev libcjson-dev libcriterion-dev libopenblas0-pthread libopenblas-dev
      gnuplot-nox libhypre-dev libopenmpi-dev libexpat1-dev zlib1g-dev
      petsc-dev openmpi-bin
      python3-dev python3-numpy python3-cffi python3-pytest python3-matplotlib python3-meshio)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Surfaces from the data archive of Debian's libcgal-demo (not committed):
# data/meshes/armadillo.off for data/scenes/paper/fig13_armadillo.json, and
# the corpus of tests/test_mesh_surface.c and bench/mesh_surface.c (fandisk:
# a CAD part with sharp edges; elephant, anchor, blobby; sphere .off/.stl).
# Optional: the tests and the bench skip what is missing.
cgal_meshes=(armadillo.off fandisk.off elephant.off anchor.off blobby.off sphere.off sphere.stl)
missing_meshes=()
for f in "${cgal_meshes[@]}"; do [ -f "data/meshes/$f" ] || missing_meshes+=("data/meshes/$f"); done
if [ ${#missing_meshes[@]} -gt 0 ]; then
  tmp=$(mktemp -d)
  if (cd "$tmp" && { apt-get download -q libcgal-demo >/dev/null 2>&1 ||
                     { apt-get update -q >/dev/null && apt-get download -q libcgal-demo >/dev/null 2>&1; }; } &&
      dpkg-deb -x libcgal-demo_*.deb x &&
      tar xzf x/usr/share/doc/libcgal-dev/data.tar.gz "${missing_meshes[@]}"); then
    mkdir -p data/meshes && mv "$tmp"/data/meshes/* data/meshes/
    echo "setup: extracted ${missing_meshes[*]} from libcgal-demo"
  else
    echo "setup: warning: could not extract ${missing_meshes[*]} from libcgal-demo (tests and scenes using them are skipped)" >&2
  fi
  rm -rf "$tmp"
fi

# The corpus of inputs that are not clean (tests/test_surface_repair.c,
# tests/test_cad_assembly.c; not committed): scans with self-intersections and
# holes from the same CGAL archive, a CAD gear (pinion.off,
# tests/test_mesh_surface.c), the cheese that crashes CGAL 5.5's ODT smoother
# (cheese.off, tests/test_mesh_surface.c), and Gmsh's STEP assembly demo from
# gmsh-doc, into data/corpus/.
corpus_cgal=(camel.off cow.off elk.off pig.off mech-holes-shark.off pinion.off cheese.off)
corpus_missing=0
for f in "${corpus_cgal[@]/#/cgal/}" gmsh/as1-tu-203.stp; do [ -f "data/corpus/$f" ] || corpus_missing=1; done
if [ "$corpus_missing" = 1 ]; then
  tmp=$(mktemp -d)
  if (cd "$tmp" && { apt-get download -q libcgal-demo gmsh-doc >/dev/null 2>&1 ||
                     { apt-get update -q >/dev/null && apt-get download -q libcgal-demo gmsh-doc >/dev/null 2>&1; }; } &&
      dpkg-deb -x libcgal-demo_*.deb x && dpkg-deb -x gmsh-doc_*.deb x &&
      tar xzf x/usr/share/doc/libcgal-dev/data.tar.gz "${corpus_cgal[@]/#/data/meshes/}"); then
    mkdir -p data/corpus/cgal data/corpus/gmsh
    for f in "${corpus_cgal[@]}"; do mv "$tmp/data/meshes/$f" data/corpus/cgal/; done
    zcat "$tmp"/x/usr/share/doc/gmsh-doc/doc/gmsh/demos/boolean/as1-tu-203.stp.gz > data/corpus/gmsh/as1-tu-203.stp
    echo "setup: extracted the repair corpus into data/corpus (libcgal-demo, gmsh-doc)"
  else
    echo "setup: warning: could not extract the repair corpus (test_surface_repair and test_cad_assembly will fail)" >&2
  fi
  rm -rf "$tmp"
fi

cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" ${CMAKE_ARGS:-} >/dev/null
cmake --build "$BUILD_DIR" -j "$JOBS"

# The library into /usr/local (libbigstep.so, headers, pkg-config) and the
# Python package bigstep built against it (python/build.py, cffi API mode)
# into /usr/local/lib/python3.X/dist-packages, for Debian's /usr/bin/python3
# (not a pyenv python3 on the PATH). Not for the sanitizer build.
if [ "$mode" != sanitize ]; then
  cmake --install "$BUILD_DIR" --prefix /usr/local >/dev/null
  ldconfig
  /usr/bin/python3 python/build.py --prefix /usr/local --build-dir "$BUILD_DIR/python/setup-cffi" --quiet
fi

case "$mode" in
  build) ;;
  run)  "$BUILD_DIR/app/bigstep" run data/scenes/cube_stretch.json --replace ;;
  test) ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS" ;;
  sanitize) ctest --test-dir "$BUILD_DIR" -L sanitize --output-on-failure -j "$JOBS" ;;
  *) echo "usage: bash setup.sh run|test|sanitize|build" >&2; exit 2 ;;
esac
