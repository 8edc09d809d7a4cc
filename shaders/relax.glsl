#version 430
// Relax pass: one Jacobi step of phase alignment (ping-pong buffers).
//   phi_i <- arg( a_i e^{i phi_i} + sum_j a_j e^{i (phi~_j - kbar_ij . (x_j - x_i))} )
// with (k_j, phi_j) flipped to (-k_j, -phi_j) when k_i . k_j < 0 (cos is even).
#include "include/common.glsl"
#include "include/topology.glsl"

layout(local_size_x = LOCAL_SIZE) in;

layout(std430, binding = RELAX_POSED_POINTS) readonly buffer PosedPoints { vec4 posed_points[]; };
layout(std430, binding = RELAX_TOPOLOGY) readonly buffer Topology { int topology[]; };
layout(std430, binding = RELAX_FIELDS) readonly buffer Fields { WrinkleField fields[]; };
layout(std430, binding = RELAX_PHASE_IN) readonly buffer PhaseIn { float phase_in[]; };
layout(std430, binding = RELAX_PHASE_OUT) writeonly buffer PhaseOut { float phase_out[]; };

uniform int u_num_points;

// A tiny floor on the weights keeps arg() defined where no vertex is wrinkled.
const float WEIGHT_FLOOR = 1e-7;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec3 x_i = posed_points[i].xyz;
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
