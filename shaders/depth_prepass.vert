#version 460
// shadowvol: depth-only pre-pass of every scene triangle (no fragment shader).
// Triangle corners are read from a storage buffer of global vertex ids; each vertex knows its
// object, whose world-from-object matrix places it in the world.
// Regenerate the SPIR-V with `cargo xtask shaders`.

layout(std430, set = 0, binding = 0) readonly buffer Positions { float pos[]; };
layout(std430, set = 0, binding = 5) readonly buffer Models { mat4 models[]; };
layout(std430, set = 0, binding = 8) readonly buffer VertexObject { uint vertex_obj[]; };
layout(std430, set = 0, binding = 9) readonly buffer TriangleCorners { uint corners[]; };

layout(push_constant) uniform Push {
    mat4 view_proj;
    uint mode;
    uint edge_count;
    uint light_count;
    uint uncertain_capacity;
    uint emit;
} pc;

void main() {
    uint v = corners[gl_VertexIndex];
    vec3 p = vec3(pos[3u * v], pos[3u * v + 1u], pos[3u * v + 2u]);
    gl_Position = pc.view_proj * (models[vertex_obj[v]] * vec4(p, 1.0));
}
