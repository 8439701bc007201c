"""Writes reference.obj: the head and ears of assets/bunny.obj (every triangle whose three
vertices have y > 7), its vertices snapped to an integer grid.

The grid is chosen so that the real exporters reproduce the positions exactly: coordinates are
integers (exact in f32 and f64, so no tool's decimal parsing can round them differently), the
largest axis spans exactly 0..16383 = 2^14 - 1 before the offset, so gltfpack's default 14-bit
position quantization has a scale of exactly 1 and its integers are the coordinates themselves.
"""
import sys

src, out = sys.argv[1], sys.argv[2]
V, F = [], []
for line in open(src):
    p = line.split()
    if not p:
        continue
    if p[0] == "v":
        V.append(tuple(map(float, p[1:4])))
    elif p[0] == "f":
        F.append(tuple(int(x.split("/")[0]) - 1 for x in p[1:4]))
sel = [f for f in F if all(V[i][1] > 7.0 for i in f)]
used = sorted({i for f in sel for i in f})
remap = {old: new for new, old in enumerate(used)}
mn = [min(V[i][a] for i in used) for a in range(3)]
ext = max(max(V[i][a] for i in used) - mn[a] for a in range(3))
offset = (1000, -2000, 500)
Q = [tuple(round((V[i][a] - mn[a]) / ext * 16383) + offset[a] for a in range(3)) for i in used]
tris = [tuple(remap[i] for i in f) for f in sel]
# Snapping must not weld two corners of one triangle together.
for t in tris:
    assert len({Q[i] for i in t}) == 3, t
with open(out, "w") as f:
    f.write("# Head and ears of assets/bunny.obj (triangles with y > 7), snapped to an integer grid\n")
    f.write(f"# by crates/scenes/tests/data/real/make_reference.py: {len(Q)} vertices, {len(tris)} triangles\n")
    for q in Q:
        f.write("v %d %d %d\n" % q)
    for t in tris:
        f.write("f %d %d %d\n" % tuple(i + 1 for i in t))
