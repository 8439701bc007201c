// Writes OUT: IN with every POSITION accessor stored sparse by glTF Transform (its writer emits a
// sparse accessor without a base bufferView, i.e. zeros, plus indices and values of the non-zero
// elements). Usage: node make_sparse.mjs IN OUT (with @gltf-transform/core installed).
import { NodeIO } from '@gltf-transform/core';

const [input, output] = process.argv.slice(2);
const io = new NodeIO();
const doc = await io.read(input);
for (const mesh of doc.getRoot().listMeshes()) {
  for (const prim of mesh.listPrimitives()) {
    prim.getAttribute('POSITION').setSparse(true);
  }
}
await io.write(output, doc);
