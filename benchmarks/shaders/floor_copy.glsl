#version 430
// Copy points from one table to another: the least any skin pass does per point.
#include "include/common.glsl"
layout(local_size_x = LOCAL_SIZE) in;
layout(binding = 0) uniform sampler2D a;
layout(rgba32f, binding = 0) writeonly uniform image2D b;
uniform int n;
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= n) return;
    STORE(b, i, fetch(a, i));
}
