#!/usr/bin/env bash
# Regenerates the real-exporter corpus in this folder from assets/bunny.obj with the real tools:
#   reference.obj           make_reference.py: the bunny's head and ears on an integer grid
#   obj2gltf.glb            obj2gltf
#   gltfpack.glb            gltfpack (default: KHR_mesh_quantization, 14-bit positions)
#   gltfpack-c.glb          gltfpack -c  (quantized + EXT_meshopt_compression, fallback buffer)
#   gltfpack-cc.glb         gltfpack -cc (the same, higher compression level)
#   gltfpack-noq.glb        gltfpack -noq (float positions, no quantization)
#   sparse.glb              glTF Transform: POSITION as a sparse accessor without bufferView
#   draco*.glb              glTF Transform `draco` (Google's encoder): default (edgebreaker),
#                           --method sequential, --encode-speed 0 --decode-speed 0
#   draco*-decoded.glb      make_draco.mjs: each decoded by Google's decoder (draco3dgltf)
#   scene-draco.glb         `shadowvol scene export hard-multi-object-transforms` through
#                           glTF Transform `draco`; scene-draco-decoded.glb its decoded twin
#   uv-sphere-draco.glb     make_uv_sphere.py (POSITION, NORMAL, TEXCOORD_0 with seams) through
#                           glTF Transform `draco`; uv-sphere-draco-decoded.glb its decoded twin
#   reference-*.stl         trimesh: ASCII and binary STL
#   reference-*.ply         plyfile: ASCII, binary little-endian (with quads), binary big-endian
# The npm and PyPI packages are installed into a temporary folder (nothing is installed here).
# Needs node/npm and python3 with venv. Usage: bash make.sh
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../../../../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

(cd "$tmp" && npm init -y >/dev/null &&
  npm install --silent obj2gltf@3.2.0 gltfpack@1.3.0 @gltf-transform/cli@4.5.1 \
    @gltf-transform/core@4.5.1 @gltf-transform/extensions@4.5.1 draco3dgltf@1.5.7 \
    gltf-validator@2.0.0-dev.3.10 >/dev/null)
python3 -m venv "$tmp/py"
"$tmp/py/bin/pip" install --quiet numpy==2.4.6 trimesh==5.2.0 plyfile==1.1.5
bin="$tmp/node_modules/.bin"

cd "$here"
python3 make_reference.py "$repo/assets/bunny.obj" reference.obj
"$bin/obj2gltf" -i reference.obj -o obj2gltf.glb >/dev/null
"$bin/gltfpack" -i obj2gltf.glb -o gltfpack.glb >/dev/null
"$bin/gltfpack" -i obj2gltf.glb -o gltfpack-c.glb -c >/dev/null
"$bin/gltfpack" -i obj2gltf.glb -o gltfpack-cc.glb -cc >/dev/null
"$bin/gltfpack" -i obj2gltf.glb -o gltfpack-noq.glb -noq >/dev/null
cp make_sparse.mjs "$tmp/"
node "$tmp/make_sparse.mjs" obj2gltf.glb sparse.glb 2>/dev/null
"$bin/gltf-transform" draco obj2gltf.glb draco.glb >/dev/null
"$bin/gltf-transform" draco obj2gltf.glb draco-sequential.glb --method sequential >/dev/null
"$bin/gltf-transform" draco obj2gltf.glb draco-speed0.glb --encode-speed 0 --decode-speed 0 \
  >/dev/null
cp make_draco.mjs "$tmp/"
(cd "$repo" && cargo run -q --release -p shadowvol -- scene export hard-multi-object-transforms \
  "$tmp/scene.glb" >/dev/null)
"$bin/gltf-transform" draco "$tmp/scene.glb" scene-draco.glb >/dev/null
python3 make_uv_sphere.py "$tmp/uv-sphere.glb"
"$bin/gltf-transform" draco "$tmp/uv-sphere.glb" uv-sphere-draco.glb >/dev/null
for f in draco draco-sequential draco-speed0 scene-draco uv-sphere-draco; do
  node "$tmp/make_draco.mjs" "$f.glb" "$f-decoded.glb"
done
"$tmp/py/bin/python" make_stl_ply.py . 2>/dev/null

# Every glTF file must be free of errors for the Khronos validator.
cat >"$tmp/validate.cjs" <<'JS'
const fs = require('fs');
const validator = require('gltf-validator');
(async () => {
  for (const f of process.argv.slice(2)) {
    const r = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)));
    console.log(`${f}: ${r.issues.numErrors} errors, ${r.issues.numWarnings} warnings`);
    if (r.issues.numErrors > 0) process.exitCode = 1;
  }
})();
JS
node "$tmp/validate.cjs" ./*.glb
