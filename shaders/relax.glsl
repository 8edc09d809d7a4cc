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

layout(std430, binding = RELAX_FIELDS) readonly buffer Fields { WrinkleField fields[]; };
// per directed edge (CSR order): xy = e^{-i d_ij}, z = +1 or -1 (flip), w = weight a_j
layout(std430, binding = RELAX_EDGES) buffer Edges { vec4 edges[]; };
layout(std430, binding = RELAX_TOPOLOGY) readonly buffer Topology { int topology[]; };

// A tiny floor on the weights keeps arg() defined where no vertex is wrinkled.
const float WEIGHT_FLOOR = 1e-7;

vec2 complex_mul(vec2 a, vec2 b) { return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }

#if defined SEED

layout(std430, binding = RELAX_PREVIOUS_FIELDS) readonly buffer PreviousFields {
    WrinkleField previous_fields[];
};
layout(std430, binding = RELAX_ANCHOR) readonly buffer Anchor { float anchor_phase[]; };
// in place: each vertex reads its own last-frame phase and writes its seed (the result
// when there are no iterations)
layout(std430, binding = RELAX_PHASE) buffer Phase { float phase[]; };
layout(std430, binding = RELAX_POSED_POINTS) readonly buffer PosedPoints { vec4 posed_points[]; };
layout(std430, binding = RELAX_Z_OUT) writeonly buffer ZOut { vec2 z_out[]; };

uniform int u_has_history;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec3 k_i = fields[i].wave.xyz;
    float start = anchor_phase[i];
    if (u_has_history != 0) {
        // keep last frame's phase; flip it where the wave vector flipped
        float flip = dot(k_i, previous_fields[i].wave.xyz) < 0.0 ? -1.0 : 1.0;
        start = flip * phase[i];
    }
    phase[i] = start;
    z_out[i] = vec2(cos(start), sin(start));
    vec3 x_i = posed_points[i].xyz;  // posed, local space
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        int j = NEIGHBOR(e);
        vec3 k_j = fields[j].wave.xyz;
        float flip = dot(k_i, k_j) < 0.0 ? -1.0 : 1.0;
        vec3 k_bar = 0.5 * (k_i + flip * k_j);
        float drift = dot(k_bar, posed_points[j].xyz - x_i);
        edges[e] = vec4(cos(drift), -sin(drift), flip, fields[j].wave.w + WEIGHT_FLOOR);
    }
}

#else

layout(std430, binding = RELAX_Z_IN) readonly buffer ZIn { vec2 z_in[]; };
layout(std430, binding = RELAX_Z_OUT) writeonly buffer ZOut { vec2 z_out[]; };
layout(std430, binding = RELAX_PHASE) writeonly buffer Phase { float phase[]; };

uniform int u_write_phase;  // the last iteration also stores phi = arg z

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec2 z_i = z_in[i];
    vec2 sum = (fields[i].wave.w + WEIGHT_FLOOR) * z_i;
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        vec4 edge = edges[e];
        vec2 z_j = z_in[NEIGHBOR(e)];
        z_j.y *= edge.z;  // conjugate when the neighbour's wave is flipped
        sum += edge.w * complex_mul(z_j, edge.xy);
    }
    float len2 = dot(sum, sum);
    vec2 z = len2 > 0.0 ? sum * inversesqrt(len2) : z_i;
    z_out[i] = z;
    if (u_write_phase != 0) phase[i] = atan(z.y, z.x);
}

#endif
