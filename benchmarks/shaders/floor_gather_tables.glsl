#version 430
// The same gather through tables, addressed as the passes address them (common.glsl).
#include "include/common.glsl"
layout(local_size_x = LOCAL_SIZE) in;
layout(binding = 0) uniform sampler2D a;
layout(binding = 1) uniform isampler2D c;
layout(rgba32f, binding = 0) writeonly uniform image2D b;
uniform int n;
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= n) return;
    vec4 s = vec4(0.0);
    for (int e = 0; e < 6; ++e) s += fetch(a, fetch(c, 6 * i + e).x);
    STORE(b, i, s);
}
