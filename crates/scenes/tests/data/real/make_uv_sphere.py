"""Writes OUT.glb: a UV sphere (24 x 12) with POSITION, NORMAL and TEXCOORD_0, the way DCC
exporters write textured meshes: the seam at u = 0/1 and the poles duplicate vertices with other
normals or texture coordinates, so a Draco encoder has attribute seams to carry.
Usage: python3 make_uv_sphere.py OUT.glb (standard library only)."""
import json, math, struct, sys

SEG, RING = 24, 12
pos, nrm, uv = [], [], []
for r in range(RING + 1):
    th = math.pi * r / RING
    for s in range(SEG + 1):
        ph = 2 * math.pi * s / SEG
        n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
        pos.append(tuple(round(c, 6) for c in n))
        nrm.append(n)
        uv.append((s / SEG, r / RING))
idx = []
for r in range(RING):
    for s in range(SEG):
        a, b = r * (SEG + 1) + s, (r + 1) * (SEG + 1) + s
        if r != 0:
            idx += [a, a + 1, b]
        if r != RING - 1:
            idx += [a + 1, b + 1, b]
blob = b"".join(struct.pack("<3f", *p) for p in pos)
blob += b"".join(struct.pack("<3f", *n) for n in nrm)
blob += b"".join(struct.pack("<2f", *t) for t in uv)
off_idx = len(blob)
blob += b"".join(struct.pack("<H", i) for i in idx)
blob += b"\0" * (-len(blob) % 4)
nv = len(pos)
doc = {
    "asset": {"version": "2.0", "generator": "make_uv_sphere.py"},
    "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0, "name": "uv-sphere"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                "indices": 3}]}],
    "buffers": [{"byteLength": len(blob)}],
    "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": 12 * nv, "target": 34962},
        {"buffer": 0, "byteOffset": 12 * nv, "byteLength": 12 * nv, "target": 34962},
        {"buffer": 0, "byteOffset": 24 * nv, "byteLength": 8 * nv, "target": 34962},
        {"buffer": 0, "byteOffset": off_idx, "byteLength": 2 * len(idx), "target": 34963},
    ],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": nv,
         "min": [min(p[i] for p in pos) for i in range(3)],
         "max": [max(p[i] for p in pos) for i in range(3)]},
        {"bufferView": 1, "componentType": 5126, "type": "VEC3", "count": nv},
        {"bufferView": 2, "componentType": 5126, "type": "VEC2", "count": nv},
        {"bufferView": 3, "componentType": 5123, "type": "SCALAR", "count": len(idx)},
    ],
}
js = json.dumps(doc, separators=(",", ":")).encode()
js += b" " * (-len(js) % 4)
out = struct.pack("<III", 0x46546C67, 2, 28 + len(js) + len(blob))
out += struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
open(sys.argv[1], "wb").write(out)
