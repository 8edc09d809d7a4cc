#version 430
// Skin pass: blend shapes, then geomBindTransform, then LBS or DQS, then skeleton
// space to prim (local) space. Arithmetic follows UsdSkel's ComputeSkinnedPoints.
// Matrices are USD row-vector matrices uploaded as-is, so GLSL sees their transpose
// and 'M * vec4(p, 1)' equals USD's 'p * M'.
#include "include/common.glsl"

layout(local_size_x = LOCAL_SIZE) in;

// Joints: 9 texels each.
//   0..2  LBS: the first three columns of the row-vector matrix geomBind * skinning
//         transform * skel-to-local, combined on the CPU in double precision (local rest ->
//         local posed): posed coordinate c = dot(column c, (p, 1))
//   3     unused
//   4     DQS rotation quaternion (xyz, w)
//   5     DQS dual part (xyz, w)
//   6..8  DQS scale/shear remainder, row-vector 3x3 rows, applied by LBS
#define JOINT(j, k) fetch(joints, JOINT_TEXELS * (j) + (k))

layout(binding = SKIN_REST_POINTS) uniform sampler2D rest_points;
// per influence: x = joint index (a float; -1 outside the skeleton), y = weight
layout(binding = SKIN_INFLUENCES) uniform sampler2D influences;
layout(binding = SKIN_JOINTS) uniform sampler2D joints;
layout(rgba32f, binding = SKIN_POSED_POINTS) writeonly uniform image2D posed_points;
layout(std430, binding = SKIN_SUBSHAPE_OFFSETS) readonly buffer SubShapeOffsets { vec4 subshape_offsets[]; };
layout(std430, binding = SKIN_SUBSHAPE_WEIGHTS) readonly buffer SubShapeWeights { float subshape_weights[]; };

uniform int u_num_points;
uniform int u_influences;      // influences per point
uniform int u_num_joints;
uniform int u_num_subshapes;
uniform int u_method;          // 0: no skinning, 1: LBS, 2: DQS
uniform int u_has_scale;       // DQS: any joint has scale or shear
uniform mat4 u_geom_bind;      // local (rest) -> skeleton bind space
uniform mat4 u_skel_to_local;  // skeleton space -> prim (local) space

vec3 quat_rotate(vec4 q, vec3 v) {
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;

    // rest (local) + blend shapes -> deformed rest (local)
    vec3 p = fetch(rest_points, i).xyz;
    for (int s = 0; s < u_num_subshapes; ++s) {
        float w = subshape_weights[s];
        if (w != 0.0) p += w * subshape_offsets[s * u_num_points + i].xyz;
    }
    if (u_method == 0) {
        STORE(posed_points, i, vec4(p, 1.0));
        return;
    }

    int base = i * u_influences;
    if (u_method == 1) {
        // LBS is linear in the matrices: sum_j w_j (p G J_j S) with the three matrices of
        // each joint premultiplied, local rest -> local posed in one product
        vec3 local_p = vec3(0.0);
        for (int k = 0; k < u_influences; ++k) {
            vec2 influence = fetch(influences, base + k).xy;
            int j = int(influence.x);
            float w = influence.y;
            if (w != 0.0 && j >= 0 && j < u_num_joints) {
                vec4 p1 = vec4(p, 1.0);
                local_p += vec3(dot(JOINT(j, 0), p1), dot(JOINT(j, 1), p1),
                                dot(JOINT(j, 2), p1)) * w;
            }
        }
        STORE(posed_points, i, vec4(local_p, 1.0));
        return;
    }

    // DQS: local -> skeleton bind space
    vec3 bind_p = (u_geom_bind * vec4(p, 1.0)).xyz;
    vec3 skel_p = vec3(0.0);
    // pivot = the joint with the largest weight (first on ties)
    int pivot = -1;
    float max_w = -1.0;
    for (int k = 0; k < u_influences; ++k) {
        vec2 influence = fetch(influences, base + k).xy;
        int j = int(influence.x);
        float w = influence.y;
        if (j >= 0 && j < u_num_joints && (pivot < 0 || max_w < w)) {
            max_w = w;
            pivot = j;
        }
    }
    vec4 pivot_q = pivot >= 0 ? JOINT(pivot, 4) : vec4(0.0);
    vec3 scaled_p = vec3(0.0);
    vec4 sum_real = vec4(0.0);
    vec4 sum_dual = vec4(0.0);
    for (int k = 0; k < u_influences; ++k) {
        vec2 influence = fetch(influences, base + k).xy;
        int j = int(influence.x);
        float w = influence.y;
        if (w == 0.0 || j < 0 || j >= u_num_joints) continue;
        if (u_has_scale != 0) {
            // scale/shear by LBS, row-vector 3x3
            scaled_p += (bind_p.x * JOINT(j, 6).xyz
                       + bind_p.y * JOINT(j, 7).xyz
                       + bind_p.z * JOINT(j, 8).xyz) * w;
        }
        vec4 real = JOINT(j, 4);
        if (dot(real, pivot_q) < 0.0) w = -w;  // same hemisphere as the pivot
        sum_real += real * w;
        sum_dual += JOINT(j, 5) * w;
    }
    if (u_has_scale == 0) scaled_p = bind_p;
    float len = length(sum_real);
    if (len > 0.0) {
        sum_real /= len;
        sum_dual /= len;
        vec3 t = 2.0 * (sum_real.w * sum_dual.xyz - sum_dual.w * sum_real.xyz
                        + cross(sum_real.xyz, sum_dual.xyz));
        skel_p = quat_rotate(sum_real, scaled_p) + t;
    } else {
        skel_p = scaled_p;
    }
    // skeleton space -> prim (local) space
    STORE(posed_points, i, vec4((u_skel_to_local * vec4(skel_p, 1.0)).xyz, 1.0));
}
