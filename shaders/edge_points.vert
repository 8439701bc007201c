#version 460
// shadowvol: one point primitive per (edge, light). The vertex index is the global edge index,
// the instance index the light index; the geometry shader (silhouette_gs.geom) does the work.
// Regenerate the SPIR-V with `cargo xtask shaders`.

layout(location = 0) flat out uint v_edge;
layout(location = 1) flat out uint v_light;

void main() {
    v_edge = uint(gl_VertexIndex);
    v_light = uint(gl_InstanceIndex);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
