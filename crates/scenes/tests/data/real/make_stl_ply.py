"""Writes the STL and PLY files of the corpus from reference.obj with real exporters:
trimesh (STL ASCII and binary) and plyfile (PLY ASCII, binary little- and big-endian).

* reference-ascii.stl, reference-binary.stl: trimesh's STL exporters (a triangle soup).
* reference-ascii.ply: float x y z, plus vertex normals and colours (extra properties the loader
  must ignore), triangles as `uchar int` lists.
* reference-binary-le.ply: as above in binary little-endian, with pairs of adjacent triangles
  (a, b, c), (a, c, d) written as one quad (a, b, c, d) (its fan gives back the two triangles),
  plus a face property that is not the index list.
* reference-binary-be.ply: binary big-endian with `double` coordinates and `uint` index lists.

Usage: python make_stl_ply.py DIR (reads DIR/reference.obj, writes into DIR).
"""
import os
import sys

import numpy as np
import plyfile
import trimesh

d = sys.argv[1]
mesh = trimesh.load(os.path.join(d, "reference.obj"), process=False, force="mesh")
V = np.asarray(mesh.vertices)
T = np.asarray(mesh.faces)
assert len(T) == 557 and len(V) == 292, (len(V), len(T))

mesh.export(os.path.join(d, "reference-ascii.stl"), file_type="stl_ascii")
mesh.export(os.path.join(d, "reference-binary.stl"), file_type="stl")

normals = np.asarray(mesh.vertex_normals, dtype=np.float32)


def vertices(coord="f4"):
    v = np.empty(
        len(V),
        dtype=[("x", coord), ("y", coord), ("z", coord), ("nx", "f4"), ("ny", "f4"),
               ("nz", "f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")],
    )
    v["x"], v["y"], v["z"] = V[:, 0], V[:, 1], V[:, 2]
    v["nx"], v["ny"], v["nz"] = normals[:, 0], normals[:, 1], normals[:, 2]
    v["red"], v["green"], v["blue"] = 200, 180, 160
    return plyfile.PlyElement.describe(v, "vertex")


def faces(lists, index="i4", extra=False):
    dt = [("vertex_indices", "O")] + ([("quality", "f4")] if extra else [])
    f = np.empty(len(lists), dtype=dt)
    f["vertex_indices"] = [np.asarray(c, dtype=index) for c in lists]
    if extra:
        f["quality"] = 1.0
    return plyfile.PlyElement.describe(f, "face", val_types={"vertex_indices": index},
                                       len_types={"vertex_indices": "u1"})


def quads(tris):
    """Merges triangle k and k + 1 into a quad when they are (a, b, c), (a, c, d)."""
    out, k = [], 0
    while k < len(tris):
        a, b, c = tris[k]
        if k + 1 < len(tris) and tris[k + 1][0] == a and tris[k + 1][1] == c:
            out.append([a, b, c, tris[k + 1][2]])
            k += 2
        else:
            out.append([a, b, c])
            k += 1
    return out


tris = [list(map(int, t)) for t in T]
# Rotate each triangle so that merging finds pairs sharing their first corner: for every pair of
# consecutive triangles sharing an edge, rotate both so that the shared edge is (a, c) / (a, c).
rot = []
k = 0
while k < len(tris):
    t = tris[k]
    if k + 1 < len(tris):
        u = tris[k + 1]
        found = None
        for i in range(3):
            for j in range(3):
                # t = (a, b, c) with edge c -> a; u = (a, c, d) with edge a -> c.
                ta = [t[(i + m) % 3] for m in range(3)]
                ua = [u[(j + m) % 3] for m in range(3)]
                if ua[0] == ta[0] and ua[1] == ta[2]:
                    found = (ta, ua)
        if found:
            rot += list(found)
            k += 2
            continue
    rot.append(t)
    k += 1
q = quads(rot)
assert any(len(f) == 4 for f in q)

plyfile.PlyData([vertices(), faces(tris)], text=True).write(os.path.join(d, "reference-ascii.ply"))
plyfile.PlyData([vertices(), faces(q, extra=True)], byte_order="<").write(
    os.path.join(d, "reference-binary-le.ply"))
plyfile.PlyData([vertices("f8"), faces(tris, index="u4")], byte_order=">").write(
    os.path.join(d, "reference-binary-be.ply"))
print(f"PLY: {sum(len(f) == 4 for f in q)} quads in reference-binary-le.ply")
