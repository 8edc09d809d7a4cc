#version 430
// Skin pass: blend shapes, then geomBindTransform, then LBS or DQS, then skeleton
// space to prim (local) space. Arithmetic follows UsdSkel's ComputeSkinnedPoints.
#include "include/common.glsl"
#include "include/skinning.glsl"

layout(local_size_x = LOCAL_SIZE) in;

layout(binding = SKIN_REST_POINTS) uniform sampler2D rest_points;
layout(rgba32f, binding = SKIN_POSED_POINTS) writeonly uniform image2D posed_points;
layout(std430, binding = SKIN_SUBSHAPE_OFFSETS) readonly buffer SubShapeOffsets { vec4 subshape_offsets[]; };
layout(std430, binding = SKIN_SUBSHAPE_WEIGHTS) readonly buffer SubShapeWeights { float subshape_weights[]; };

uniform int u_num_points;
uniform int u_num_subshapes;
uniform int u_method;          // 0: no skinning, 1: LBS, 2: DQS

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;

    // rest (local) + blend shapes -> deformed rest (local)
    vec3 p = fetch(rest_points, i).xyz;
    for (int s = 0; s < u_num_subshapes; ++s) {
        float w = subshape_weights[s];
        if (w != 0.0) p += w * subshape_offsets[s * u_num_points + i].xyz;
    }
    vec3 posed = u_method == 1 ? skin_lbs(i, p) : u_method == 2 ? skin_dqs(i, p) : p;
    STORE(posed_points, i, vec4(posed, 1.0));
}
