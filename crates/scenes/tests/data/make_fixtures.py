#!/usr/bin/env python3
"""Regenerates the malformed glTF/GLB/OBJ fixtures of crates/scenes/tests (run in this folder)."""
import base64, json, struct

def gltf(positions, indices, mode=4, pos_type=5126, pos_count=None, idx_count=None,
         idx_type=5125, extra_nodes=None, nodes=None, drop_position=False, view_len=None):
    pos = b"".join(struct.pack("<3f", *p) for p in positions) if pos_type == 5126 else \
        b"".join(struct.pack("<3H", *p) for p in positions)
    fmt = {5125: "<I", 5123: "<H", 5121: "<B"}[idx_type]
    idx = b"".join(struct.pack(fmt, i) for i in indices)
    while len(idx) % 4:
        idx += b"\0"
    data = pos + idx
    attrs = {} if drop_position else {"POSITION": 0}
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes or [{"name": "thing", "mesh": 0}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": attrs, "indices": 1, "mode": mode}]}],
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": view_len if view_len is not None else len(pos)},
            {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": pos_type, "type": "VEC3",
             "count": len(positions) if pos_count is None else pos_count},
            {"bufferView": 1, "componentType": idx_type, "type": "SCALAR",
             "count": len(indices) if idx_count is None else idx_count},
        ],
    }
    return doc

TRI = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]

def write(name, doc):
    with open(name, "w") as f:
        json.dump(doc, f, indent=1)

write("index_out_of_range.gltf", gltf(TRI, [0, 1, 7]))
write("nan_position.gltf", gltf([(0, 0, 0), (1, float("nan"), 0), (0, 1, 0)], [0, 1, 2]))
write("inf_position.gltf", gltf([(0, 0, 0), (1, 0, 0), (0, 1, float("inf"))], [0, 1, 2]))
write("zero_count.gltf", gltf(TRI, [0, 1, 2], idx_count=0))
write("lines_mode.gltf", gltf(TRI, [0, 1, 1, 2], mode=1))
write("partial_triangle.gltf", gltf(TRI, [0, 1, 2, 0]))
write("past_view.gltf", gltf(TRI, [0, 1, 2], pos_count=5))
write("integer_positions.gltf", gltf([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [0, 1, 2], pos_type=5123))
write("missing_position.gltf", gltf(TRI, [0, 1, 2], drop_position=True))
write("node_cycle.gltf", gltf(TRI, [0, 1, 2], nodes=[{"name": "a", "mesh": 0, "children": [1]},
                                                     {"name": "b", "children": [0]}]))
write("zero_scale.gltf", gltf(TRI, [0, 1, 2], nodes=[{"name": "flat", "children": [1], "scale": [1, 0, 1]},
                                                      {"name": "leaf", "mesh": 0}]))
doc = gltf(TRI, [0, 1, 2])
doc["buffers"][0]["uri"] = "missing.bin"
write("missing_buffer.gltf", doc)
with open("not_json.gltf", "w") as f:
    f.write('{"asset": {"version": "2.0"}, "nodes": [ oops ]}\n')

# A valid GLB of one triangle, then broken copies.
doc = gltf(TRI, [0, 1, 2])
blob = base64.b64decode(doc["buffers"][0].pop("uri").split(",", 1)[1])
js = json.dumps(doc).encode()
while len(js) % 4:
    js += b" "
glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(blob)) + \
    struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
with open("truncated.glb", "wb") as f:
    f.write(glb[: len(glb) - 20])
with open("bad_magic.glb", "wb") as f:
    f.write(b"glTX" + glb[4:])

with open("bad_number.obj", "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1.5.2 0\nf 1 2 3\n")
with open("index_out_of_range.obj", "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
with open("nan_position.obj", "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
with open("short_face.obj", "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n")
