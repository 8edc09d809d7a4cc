#version 430
// Relax pass. The phases live as unit phasors z = e^{i phi} during the iterations, so a
// Jacobi step is complex multiply-adds only: no sin, cos or atan per edge.
//
//   phi_i <- arg( a_i e^{i phi_i} + sum_j a_j e^{i (phi~_j - kbar_ij . (x_j - x_i))} )
//   e^{i (phi~_j - d_ij)} = z~_j * e^{-i d_ij},  z~_j = conj(z_j) when (k, phi) flips
//
// Entry points, selected by the loader's defines:
//   SEED      per vertex: the start phasor (previous frame's phase, sign-aligned, or the
//             material-anchored phase on a shot's first frame) and, per outgoing edge,
//             the rotation e^{-i d_ij}, the flip and the neighbour's weight.
//   (default) one Jacobi step on the phasors (ping-pong); the last step also writes phi.
#include "include/common.glsl"
#include "include/topology.glsl"

layout(local_size_x = LOCAL_SIZE) in;

uniform int u_num_points;

layout(binding = RELAX_FIELDS) uniform sampler2D fields;
// Per directed edge (CSR order): xy = e^{-i d_ij}, z = flip * a_j (the neighbour's weight,
// negative where its wave is flipped; a_j > 0 thanks to the floor), w = j as a float (exact
// below 2^24 points). One fetch per edge: the step needs no topology lookup for j.
// SEED writes them (image), the steps read them (texture).

// WEIGHT_FLOOR (contract.py): a tiny floor on the weights keeps arg() defined where no
// vertex is wrinkled.

vec2 complex_mul(vec2 a, vec2 b) { return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }

#if defined SEED

layout(binding = RELAX_PREVIOUS_FIELDS) uniform sampler2D previous_fields;
layout(binding = RELAX_ANCHOR) uniform sampler2D anchor_phase;
// in place: each vertex reads its own last-frame phase and writes its seed (the result
// when there are no iterations)
layout(r32f, binding = RELAX_PHASE) uniform image2D phase;
layout(binding = RELAX_POSED_POINTS) uniform sampler2D posed_points;
layout(rg32f, binding = RELAX_Z_OUT) writeonly uniform image2D z_out;
layout(rgba32f, binding = RELAX_EDGES_OUT) writeonly uniform image2D edges;

uniform int u_has_history;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec3 k_i = fetch(fields, FIELD_WAVE(i)).xyz;
    float start = fetch(anchor_phase, i).x;
    if (u_has_history != 0) {
        // keep last frame's phase; flip it where the wave vector flipped
        float flip = dot(k_i, fetch(previous_fields, FIELD_WAVE(i)).xyz) < 0.0 ? -1.0 : 1.0;
        start = flip * imageLoad(phase, TABLE_TEXEL(i)).x;
    }
    STORE(phase, i, vec4(start));
    STORE(z_out, i, vec4(cos(start), sin(start), 0.0, 0.0));
    vec3 x_i = fetch(posed_points, i).xyz;  // posed, local space
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        int j = NEIGHBOR(e);
        vec4 wave_j = fetch(fields, FIELD_WAVE(j));
        float flip = dot(k_i, wave_j.xyz) < 0.0 ? -1.0 : 1.0;
        vec3 k_bar = 0.5 * (k_i + flip * wave_j.xyz);
        float drift = dot(k_bar, fetch(posed_points, j).xyz - x_i);
        STORE(edges, e, vec4(cos(drift), -sin(drift), flip * (wave_j.w + WEIGHT_FLOOR),
                             float(j)));
    }
}

#else

layout(binding = RELAX_EDGES) uniform sampler2D edges;
layout(binding = RELAX_Z_IN) uniform sampler2D z_in;
layout(rg32f, binding = RELAX_Z_OUT) writeonly uniform image2D z_out;
layout(r32f, binding = RELAX_PHASE) writeonly uniform image2D phase;

uniform int u_write_phase;  // the last iteration also stores phi = arg z

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec2 z_i = fetch(z_in, i).xy;
    vec2 sum = (fetch(fields, FIELD_WAVE(i)).w + WEIGHT_FLOOR) * z_i;
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        vec4 edge = fetch(edges, e);
        vec2 z_j = fetch(z_in, int(edge.w)).xy;
        if (edge.z < 0.0) z_j.y = -z_j.y;  // conjugate when the neighbour's wave is flipped
        sum += abs(edge.z) * complex_mul(z_j, edge.xy);
    }
    float len2 = dot(sum, sum);
    vec2 z = len2 > 0.0 ? sum * inversesqrt(len2) : z_i;
    STORE(z_out, i, vec4(z, 0.0, 0.0));
    if (u_write_phase != 0) STORE(phase, i, vec4(atan(z.y, z.x)));
}

#endif
