#!/usr/bin/env python3
"""Writes a glTF soup whose every triangle lies in a plane through its point light, as written:
one vertex pair on a line through the light. Rounding the vertices to f32 leaves each plane a
hair off the light, so each triangle casts a shadow wedge some 10^-6 of a pixel wide.

  scripts/soup_through_light.py OUT.gltf [TRIANGLES (400)] [SEED (1)]

The buffer goes next to it (OUT.bin). `shadowvol render OUT.gltf --mode exact --reference`
puts a ground under it (--ground auto); the camera looks down from (1, 9, 7)."""
import json, math, os, random, struct, sys

out = sys.argv[1]
n = int(sys.argv[2]) if len(sys.argv) > 2 else 400
rng = random.Random(int(sys.argv[3]) if len(sys.argv) > 3 else 1)
f32 = lambda x: struct.unpack("<f", struct.pack("<f", x))[0]
light = [f32(0.37), f32(6.1), f32(-0.23)]
verts = []
for _ in range(n):
    p0 = [rng.uniform(-3, 3), rng.uniform(0.5, 3.0), rng.uniform(-3, 3)]
    s = rng.uniform(0.05, 0.15)
    p1 = [p0[k] + (p0[k] - light[k]) * s for k in range(3)]
    d = [rng.uniform(-0.4, 0.4) for _ in range(3)]
    p2 = [p0[k] + d[k] for k in range(3)]
    verts += [p0, p1, p2]
EYE = [1.0, 9.0, 7.0]


def look_at(eye, target):
    """The unit quaternion [x, y, z, w] that turns the camera's -z towards target (y up)."""
    f = [t - e for t, e in zip(target, eye)]
    n = math.sqrt(sum(c * c for c in f))
    f = [c / n for c in f]
    r = [f[1] * 0 - f[2] * 1, f[2] * 0 - f[0] * 0, f[0] * 1 - f[1] * 0]
    n = math.sqrt(sum(c * c for c in r))
    r = [c / n for c in r]
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    b = [-c for c in f]
    m = [[r[0], u[0], b[0]], [r[1], u[1], b[1]], [r[2], u[2], b[2]]]
    t = m[0][0] + m[1][1] + m[2][2]
    if t > 0:
        s = math.sqrt(t + 1) * 2
        return [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4]
    if m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1 + m[0][0] - m[1][1] - m[2][2]) * 2
        return [s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
    if m[1][1] > m[2][2]:
        s = math.sqrt(1 + m[1][1] - m[0][0] - m[2][2]) * 2
        return [(m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
    s = math.sqrt(1 + m[2][2] - m[0][0] - m[1][1]) * 2
    return [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4, (m[1][0] - m[0][1]) / s]


blob = b"".join(struct.pack("<3f", *v) for v in verts)
lo = [min(f32(v[k]) for v in verts) for k in range(3)]
hi = [max(f32(v[k]) for v in verts) for k in range(3)]
bin_name = os.path.splitext(os.path.basename(out))[0] + ".bin"
with open(os.path.join(os.path.dirname(out) or ".", bin_name), "wb") as f:
    f.write(blob)
doc = {
    "asset": {"version": "2.0"},
    "extensionsUsed": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 1, 1], "intensity": 100.0}]}},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2]}],
    "nodes": [{"mesh": 0},
              {"translation": light, "extensions": {"KHR_lights_punctual": {"light": 0}}},
              {"camera": 0, "translation": EYE, "rotation": look_at(EYE, [0, 0, 0])}],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(verts),
                   "type": "VEC3", "min": lo, "max": hi}],
    "bufferViews": [{"buffer": 0, "byteLength": len(blob)}],
    "buffers": [{"byteLength": len(blob), "uri": bin_name}],
}
with open(out, "w") as f:
    json.dump(doc, f)
