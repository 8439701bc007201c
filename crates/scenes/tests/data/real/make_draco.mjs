// Writes OUT: IN (a KHR_draco_mesh_compression file) decoded by Google's Draco decoder (the
// draco3dgltf package, its official WebAssembly build) through glTF Transform, with the extension
// removed: the reference that the Rust decoder's output is compared against.
// Usage: node make_draco.mjs IN OUT (with @gltf-transform/core, @gltf-transform/extensions and
// draco3dgltf installed).
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import draco3d from 'draco3dgltf';

const [input, output] = process.argv.slice(2);
const io = new NodeIO()
  .registerExtensions(ALL_EXTENSIONS)
  .registerDependencies({ 'draco3d.decoder': await draco3d.createDecoderModule() });
const doc = await io.read(input);
for (const ext of doc.getRoot().listExtensionsUsed()) {
  if (ext.extensionName === 'KHR_draco_mesh_compression') ext.dispose();
}
await io.write(output, doc);
