#!/usr/bin/env python3
"""Regenerates the malformed-input corpus of crates/cli/tests/reliability.rs (run in this folder).

Fixtures that crates/scenes/tests/data already has (index_out_of_range.gltf, zero_count.gltf,
nan_position.gltf, inf_position.gltf, past_view.gltf, truncated.glb, bad_magic.glb,
short_face.obj, nan_position.obj, ...) are referenced from there, not copied.
"""
import base64, json, random, struct

TRI = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]


def blob(positions, indices):
    pos = b"".join(struct.pack("<3f", *p) for p in positions)
    idx = b"".join(struct.pack("<I", i) for i in indices)
    return pos, idx


def doc(positions=TRI, indices=(0, 1, 2), byte_length=None, pos_accessor=0, extra=None,
        translation=None, scale=None):
    pos, idx = blob(positions, indices)
    data = pos + idx
    node = {"name": "thing", "mesh": 0}
    if translation is not None:
        node["translation"] = translation
    if scale is not None:
        node["scale"] = scale
    d = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [node],
        "meshes": [{"name": "tri", "primitives": [
            {"attributes": {"POSITION": pos_accessor}, "indices": 1, "mode": 4}]}],
        "buffers": [{"byteLength": len(data) if byte_length is None else byte_length,
                     "uri": "data:application/octet-stream;base64,"
                            + base64.b64encode(data).decode()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
            {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": len(positions)},
            {"bufferView": 1, "componentType": 5125, "type": "SCALAR", "count": len(indices)},
        ],
    }
    if extra:
        d.update(extra)
    return d


def write_json(name, d):
    with open(name, "w") as f:
        json.dump(d, f, indent=1)


def write(name, data, mode="w"):
    with open(name, mode) as f:
        f.write(data)


# --- glTF ---
full = json.dumps(doc(), indent=1)
write("truncated.gltf", full[: len(full) // 2])
rng = random.Random(20261122)
write("garbage.gltf", bytes(rng.randrange(256) for _ in range(512)), "wb")
write("garbage.glb", b"glTF" + struct.pack("<II", 2, 512) + bytes(rng.randrange(256) for _ in range(500)), "wb")
# An accessor index that does not exist (POSITION -> accessor 5 of 2).
write_json("missing_accessor.gltf", doc(pos_accessor=5))
# The data URI holds 48 bytes but the buffer claims 4096 (and one that claims fewer).
write_json("uri_longer_claim.gltf", doc(byte_length=4096))
write_json("uri_shorter_claim.gltf", doc(byte_length=8))
# A required extension this loader does not implement.
write_json("required_extension.gltf", doc(extra={
    "extensionsUsed": ["EXT_mesh_gpu_instancing"],
    "extensionsRequired": ["EXT_mesh_gpu_instancing"]}))


def draco_variant(name, edit):
    """The real corpus' draco.glb (one buffer holding only its Draco stream, one view) with
    edit(json, view, stream) applied; edit returns the new stream bytes."""
    data = open("../../../../scenes/tests/data/real/draco.glb", "rb").read()
    n = struct.unpack_from("<I", data, 12)[0]
    j = json.loads(data[20:20 + n])
    view = j["bufferViews"][j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["bufferView"]]
    start = 20 + n + 8 + view.get("byteOffset", 0)
    stream = bytearray(data[start:start + view["byteLength"]])
    stream = edit(j, view, stream)
    if view["byteLength"] == len(data) - start or view["byteLength"] > len(stream):
        view["byteLength"] = min(view["byteLength"], len(stream))
    j["buffers"][0]["byteLength"] = len(stream)
    bin_chunk = bytes(stream) + b"\0" * (-len(stream) % 4)
    js = json.dumps(j, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    out = (struct.pack("<III", 0x46546C67, 2, 28 + len(js) + len(bin_chunk))
           + struct.pack("<II", len(js), 0x4E4F534A) + js
           + struct.pack("<II", len(bin_chunk), 0x004E4942) + bin_chunk)
    write(name, out, "wb")


def corrupt(j, view, stream):
    # One flipped bit in the edgebreaker symbols: draco-oxide indexes out of bounds (a panic
    # the loader catches).
    stream[24] ^= 0x01
    return stream


def cut(j, view, stream):
    # The stream's view cut to half its length: the decoder runs out of data.
    view["byteLength"] //= 2
    return stream


def huge_counts(j, view, stream):
    # Fuzz regression (draco_decode, crash-13fa6078): the edgebreaker header's encoded-vertex
    # count (the varint after the traversal byte at offset 11) made about 2.6e18; the decoder
    # allocated a table of that many entries and aborted.
    assert stream[12:14] == bytes([164, 2]), "292 encoded vertices expected"
    stream[12:14] = bytes([255] * 8 + [164, 2])
    view["byteLength"] = len(stream)
    return stream


draco_variant("draco_corrupted.glb", corrupt)
draco_variant("draco_cut.glb", cut)
draco_variant("draco_huge_counts.glb", huge_counts)
# f32 overflow: a node translation of 1e39 (JSON number beyond f32), and a finite scale that
# takes finite positions past f32's range in the world transform.
write_json("overflow_translation.gltf", doc(translation=[1e39, 0, 0]))
write_json("overflow_world.gltf", doc(positions=[(0, 0, 0), (3e38, 0, 0), (0, 1, 0)], scale=[10, 1, 1]))

# --- OBJ ---
write("truncated.obj", "v 0 0 0\nv 1 0 0\nv 0 1")
write("garbage.obj", bytes(rng.randrange(256) for _ in range(512)), "wb")
write("face_one_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1\n")
write("face_no_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf\n")
write("index_beyond_u32.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967296\n")
write("index_far_beyond_u32.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n")
write("relative_off_start.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n")
write("inf_position.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n")
write("overflow_position.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n")

# Fuzz regression (gltf_loader, crash-330f0110): a relative buffer URI whose percent escapes
# decode to bytes that are not UTF-8 made the gltf crate's import panic.
d = doc()
d["buffers"][0]["uri"] = "bad%AAescape.bin"
write_json("uri_bad_percent_escape.gltf", d)

# More out-of-range accessors: a dangling bufferView of an accessor, a dangling indices accessor,
# a count far beyond the data, and a sparse accessor whose count is beyond its views.
d = doc()
d["accessors"][0]["bufferView"] = 9
write_json("accessor_dangling_view.gltf", d)
d = doc()
d["meshes"][0]["primitives"][0]["indices"] = 7
write_json("dangling_indices.gltf", d)
d = doc()
d["accessors"][0]["count"] = 4000000000
write_json("huge_count.gltf", d)
d = doc()
d["accessors"][0]["sparse"] = {"count": 2000000000,
                               "indices": {"bufferView": 1, "componentType": 5125},
                               "values": {"bufferView": 0}}
write_json("sparse_beyond_views.gltf", d)
# no bufferView (zeros) with a count no memory holds: refused before it is allocated.
d = doc()
del d["accessors"][0]["bufferView"]
d["accessors"][0]["count"] = 4000000000000
write_json("viewless_huge_count.gltf", d)
