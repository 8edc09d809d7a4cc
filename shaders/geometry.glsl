#version 430
// Displaced render geometry (geometry/evaluate.py): per fine vertex of the subdivided
// rest mesh, the same wave blend as the draw pass (include/wave.glsl), at the vertex's
// barycentric position in its coarse triangle. The posed point is the barycentric mix of
// the coarse triangle's posed corners; it is displaced by h along the interpolated coarse
// normal, and its normal comes from the wrinkle gradient: normalize(n - grad h).
#include "include/common.glsl"
#include "include/wave.glsl"

layout(local_size_x = LOCAL_SIZE) in;

// per fine vertex: x = coarse triangle (a float, exact below 2^24), yzw = barycentrics
layout(binding = GEOMETRY_VERTICES) uniform sampler2D fine_vertices;
layout(binding = GEOMETRY_POINTS, rgba32f) writeonly uniform image2D points_out;  // xyz, w: h
layout(binding = GEOMETRY_NORMALS, rgba32f) writeonly uniform image2D normals_out;  // xyz
uniform int u_count;
uniform int u_wrinkles;

void main() {
    int v = int(gl_GlobalInvocationID.x);
    if (v >= u_count) return;
    vec4 row = fetch(fine_vertices, v);
    int t = int(row.x);
    vec3 bary = row.yzw;
    ivec3 corners = fetch(triangles, t).xyz;
    vec3 p = vec3(0.0);
    vec3 n = vec3(0.0);
    for (int c = 0; c < 3; ++c) {
        p += bary[c] * fetch(posed_points, corners[c]).xyz;          // local space
        n += bary[c] * fetch(fields, FIELD_NORMAL(corners[c])).xyz;
    }
    n = safe_normalize(n, vec3(0.0, 0.0, 1.0));
    Wave wave = Wave(0.0, vec3(0.0), 0.0);
    if (u_wrinkles != 0) {
        wave = wave_blend(t, bary, p, n);
    }
    STORE(points_out, v, vec4(p + wave.height * n, wave.height));
    STORE(normals_out, v, vec4(safe_normalize(n - wave.gradient, n), wave.amplitude));
}
