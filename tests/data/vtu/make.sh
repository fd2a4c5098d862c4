#!/usr/bin/env bash
# tests/data/vtu/make.sh — makes the VTU files that tests/test_vtu_read.c
# reads: one frame written by bigstep and the same frame re-saved by meshio
# and by ParaView in the forms they write. The files are committed, so the
# tests need neither meshio nor ParaView; run this only to remake them. Needs
# a built bigstep, python3-meshio and python3-paraview (Debian packages):
#   bash tests/data/vtu/make.sh [BUILD_DIR]      (default: build)
#
#   bigstep.vtu              bigstep's own: appended raw, UInt64 headers
#   bigstep_be32.vtu         the same values BigEndian with UInt32 headers
#                            (bytes rearranged here in plain Python)
#   meshio_zlib.vtu          meshio's default: inline base64, zlib, UInt32
#   meshio_binary.vtu        inline base64, uncompressed
#   meshio_ascii.vtu         ascii (values rounded to 12 digits)
#   meshio_float32.vtu       zlib, with Float32 points
#   paraview_ascii.vtu       ParaView DataMode Ascii
#   paraview_binary_zlib.vtu DataMode Binary (inline base64), ZLib
#   paraview_appended.vtu    DataMode Appended, raw, uncompressed
#   paraview_appended_zlib.vtu         Appended, raw, ZLib
#   paraview_appended_base64_zlib.vtu  Appended, base64 (EncodeAppendedData), ZLib
#   bigstep_pushed.vtu       bigstep.vtu with one corner vertex pushed through
#                            the far face (its displacement too, so the rest
#                            shape stays): inverted tets, intersecting faces
#   meshio_pushed_zlib.vtu, paraview_pushed_appended_zlib.vtu   its re-saves
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
build=${1:-$root/build}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The stretched cube at 4 x 4 x 3 cells (100 points, 288 tets) after one
# frame: displacement, velocity, detF all non-trivial.
"$build/app/bigstep" run "$root/data/scenes/cube_stretch.json" --set 'bodies.0.box.cells=[4,4,3]' \
  --frames 1 --set output.vtu_every=1 --out "$tmp/run" --quiet >/dev/null
cp "$tmp/run/frame_00001.vtu" "$here/bigstep.vtu"

# bigstep_pushed.vtu and bigstep_be32.vtu from bigstep.vtu's raw appended
# blocks (offsets from the DataArray tags, UInt64 byte counts).
/usr/bin/python3 - "$here" <<'PY'
import re, struct, sys
d = sys.argv[1]
s = open(d + "/bigstep.vtu", "rb").read()
tag = b'<AppendedData encoding="raw">'
head, _, rest = s.partition(tag)
start = rest.index(b"_") + 1
tail = b"\n  </AppendedData>\n</VTKFile>\n"
assert rest.endswith(tail)
pre, raw = head + tag + rest[:start], bytearray(rest[start:-len(tail)])
size = {b"Int8": 1, b"UInt8": 1, b"Int16": 2, b"UInt16": 2, b"Int32": 4, b"UInt32": 4, b"Int64": 8, b"UInt64": 8,
        b"Float32": 4, b"Float64": 8}
arrays = {m.group(2): (size[m.group(1)], int(m.group(3)))
          for m in re.finditer(rb'type="(\w+)" Name="(\w+)"[^>]*offset="(\d+)"', head)}

def f64(name):
    off = arrays[name][1]
    n = struct.unpack_from("<Q", raw, off)[0] // 8
    return off + 8, list(struct.unpack_from("<%dd" % n, raw, off + 8))

# pushed: the vertex nearest the low corner of the bounding box moves to
# lo + (1.4, 0.45, 0.35) (hi - lo), through the opposite face
px, x = f64(b"Points")
pd, u = f64(b"displacement")
lo = [min(x[k::3]) for k in range(3)]
hi = [max(x[k::3]) for k in range(3)]
c = min(range(len(x) // 3), key=lambda i: sum(x[3 * i + k] - lo[k] for k in range(3)))
for k, t in enumerate((1.4, 0.45, 0.35)):
    new = lo[k] + t * (hi[k] - lo[k])
    u[3 * c + k] += new - x[3 * c + k]
    x[3 * c + k] = new
pushed = bytearray(raw)
struct.pack_into("<%dd" % len(x), pushed, px, *x)
struct.pack_into("<%dd" % len(u), pushed, pd, *u)
open(d + "/bigstep_pushed.vtu", "wb").write(pre + pushed + tail)

# big-endian with UInt32 headers: every block byte-swapped
out, offsets = b"", {}
for sz, off in sorted(arrays.values(), key=lambda a: a[1]):
    n = struct.unpack_from("<Q", raw, off)[0]
    offsets[off] = len(out)
    vals = raw[off + 8: off + 8 + n]
    out += struct.pack(">I", n) + b"".join(bytes(vals[i:i + sz][::-1]) for i in range(0, n, sz))
head = re.sub(rb'offset="(\d+)"', lambda m: b'offset="%d"' % offsets[int(m.group(1))], head)
head = head.replace(b'byte_order="LittleEndian"', b'byte_order="BigEndian"')
head = head.replace(b'header_type="UInt64"', b'header_type="UInt32"')
open(d + "/bigstep_be32.vtu", "wb").write(head + tag + b"\n   _" + out + tail)
PY

/usr/bin/python3 - "$here" "$tmp" <<'PY' 2>&1 | grep -v "only meant for debugging" || true
import sys
import meshio
import numpy as np
d, tmp = sys.argv[1], sys.argv[2]
m = meshio.read(d + "/bigstep.vtu")
m.write(d + "/meshio_zlib.vtu")  # meshio's default: binary, zlib
m.write(d + "/meshio_binary.vtu", compression=None)
m.write(d + "/meshio_ascii.vtu", binary=False)
m.points = m.points.astype(np.float32)
m.write(d + "/meshio_float32.vtu")
p = meshio.read(d + "/bigstep_pushed.vtu")
p.write(d + "/meshio_pushed_zlib.vtu")
p.write(tmp + "/pushed_binary.vtu", compression=None)
PY

# ParaView reads the meshio copies: Debian 12's ParaView 5.11 cannot read any
# appended VTU (its own included) with Debian 12's expat, which has the
# "reparse deferral" of expat 2.6 backported (VTK issue 19258).
/usr/bin/pvpython - "$here" "$tmp" <<'PY' 2>&1 | grep -v '^$' || true
import sys
from paraview.simple import OpenDataFile, SaveData
d, tmp = sys.argv[1], sys.argv[2]
src = OpenDataFile(d + "/meshio_binary.vtu")
for name, mode, comp, b64 in [("ascii", "Ascii", "None", 0), ("binary_zlib", "Binary", "ZLib", 0),
                              ("appended", "Appended", "None", 0), ("appended_zlib", "Appended", "ZLib", 0),
                              ("appended_base64_zlib", "Appended", "ZLib", 1)]:
    SaveData(d + "/paraview_%s.vtu" % name, proxy=src, DataMode=mode, CompressorType=comp, EncodeAppendedData=b64)
SaveData(d + "/paraview_pushed_appended_zlib.vtu", proxy=OpenDataFile(tmp + "/pushed_binary.vtu"),
         DataMode="Appended", CompressorType="ZLib")
PY
ls -l "$here"
