#version 430
// A 6-neighbour gather through storage buffers (the memory pattern of crush and relax).
layout(local_size_x = LOCAL_SIZE) in;
layout(std430, binding = 0) readonly buffer A { vec4 a[]; };
layout(std430, binding = 1) writeonly buffer B { vec4 b[]; };
layout(std430, binding = 2) readonly buffer C { int c[]; };
uniform int n;
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= n) return;
    vec4 s = vec4(0.0);
    for (int e = 0; e < 6; ++e) s += a[c[6 * i + e]];
    b[i] = s;
}
