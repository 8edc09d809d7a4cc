#version 430
// The smallest real wave pass (tests/passes/motion.py): each point's motion from its
// rest position, posed - rest, and its length.
#include "include/common.glsl"

layout(local_size_x = LOCAL_SIZE) in;

layout(binding = MOTION_REST_POINTS) uniform sampler2D rest_points;
layout(binding = MOTION_POSED_POINTS) uniform sampler2D posed_points;
layout(rgba32f, binding = MOTION_OUT) writeonly uniform image2D motion;

uniform int u_num_points;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec3 moved = fetch(posed_points, i).xyz - fetch(rest_points, i).xyz;
    STORE(motion, i, vec4(moved, length(moved)));
}
