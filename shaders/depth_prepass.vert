#version 460
// shadowvol: depth-only pre-pass of every scene triangle (no fragment shader).
// Triangle corners are read from a storage buffer of global vertex ids; each vertex knows its
// object, whose anchor-relative clip transform places it on screen.
// Regenerate the SPIR-V with `cargo xtask shaders`.

layout(std430, set = 0, binding = 0) readonly buffer Positions { float pos[]; };
struct ObjectXform {
    mat4 clip_from_anchor;
    vec4 anchor;
};
layout(std430, set = 0, binding = 4) readonly buffer Xforms { ObjectXform xf[]; };
layout(std430, set = 0, binding = 7) readonly buffer VertexObject { uint vertex_obj[]; };
layout(std430, set = 0, binding = 8) readonly buffer TriangleCorners { uint corners[]; };

layout(push_constant) uniform Push {
    uint mode;
    uint edge_count;
    uint light_count;
    uint uncertain_capacity;
    uint emit;
    uint pass;
} pc;

void main() {
    uint v = corners[gl_VertexIndex];
    uint o = vertex_obj[v];
    // Exactly the operations of silhouette_gs.geom's emit_quads, so shared vertices coincide.
    precise vec3 r = vec3(pos[3u * v], pos[3u * v + 1u], pos[3u * v + 2u]) - xf[o].anchor.xyz;
    precise vec4 clip = xf[o].clip_from_anchor * vec4(r, 1.0);
    gl_Position = clip;
}
