#version 430
// Relax pass, two entry points selected by the loader's defines:
//
// SEED: the start of this frame's relaxation. With phase history, each vertex keeps
//   its previous phase, flipped when its wave vector flipped (k_prev . k < 0: (k, phi)
//   and (-k, -phi) are the same wave), so crests ride with the cloth from frame to
//   frame. Without history (the shot's first frame): crush's material-anchored phase.
//
// otherwise: one Jacobi step of phase alignment (ping-pong buffers)
//   phi_i <- arg( a_i e^{i phi_i} + sum_j a_j e^{i (phi~_j - kbar_ij . (x_j - x_i))} )
//   with (k_j, phi_j) flipped to (-k_j, -phi_j) when k_i . k_j < 0.
#include "include/common.glsl"
#include "include/topology.glsl"

layout(local_size_x = LOCAL_SIZE) in;

uniform int u_num_points;

layout(std430, binding = RELAX_FIELDS) readonly buffer Fields { WrinkleField fields[]; };

#if defined SEED

layout(std430, binding = RELAX_PREVIOUS_FIELDS) readonly buffer PreviousFields {
    WrinkleField previous_fields[];
};
layout(std430, binding = RELAX_ANCHOR) readonly buffer Anchor { float anchor_phase[]; };
// in place: this vertex's previous relaxed phase in, its seed out
layout(std430, binding = RELAX_PHASE_OUT) buffer Phase { float phase[]; };

uniform int u_has_history;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    if (u_has_history == 0) {
        phase[i] = anchor_phase[i];
        return;
    }
    float flip = dot(fields[i].wave.xyz, previous_fields[i].wave.xyz) < 0.0 ? -1.0 : 1.0;
    phase[i] = flip * phase[i];
}

#else

layout(std430, binding = RELAX_POSED_POINTS) readonly buffer PosedPoints { vec4 posed_points[]; };
layout(std430, binding = RELAX_TOPOLOGY) readonly buffer Topology { int topology[]; };
layout(std430, binding = RELAX_PHASE_IN) readonly buffer PhaseIn { float phase_in[]; };
layout(std430, binding = RELAX_PHASE_OUT) writeonly buffer PhaseOut { float phase_out[]; };

// A tiny floor on the weights keeps arg() defined where no vertex is wrinkled.
const float WEIGHT_FLOOR = 1e-7;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec3 x_i = posed_points[i].xyz;          // posed, local space
    vec3 k_i = fields[i].wave.xyz;
    float phi_i = phase_in[i];
    float w_i = fields[i].wave.w + WEIGHT_FLOOR;
    vec2 sum = w_i * vec2(cos(phi_i), sin(phi_i));
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        int j = NEIGHBOR(e);
        vec3 k_j = fields[j].wave.xyz;
        float phi_j = phase_in[j];
        if (dot(k_i, k_j) < 0.0) { k_j = -k_j; phi_j = -phi_j; }
        vec3 k_bar = 0.5 * (k_i + k_j);
        float predicted = phi_j - dot(k_bar, posed_points[j].xyz - x_i);
        float w_j = fields[j].wave.w + WEIGHT_FLOOR;
        sum += w_j * vec2(cos(predicted), sin(predicted));
    }
    phase_out[i] = dot(sum, sum) > 0.0 ? atan(sum.y, sum.x) : phi_i;
}

#endif
