#version 430
// Displaced render geometry (geometry/evaluate.py): per fine vertex of the subdivided
// rest mesh, the same wave blend as the draw pass (include/wave.glsl), at the vertex's
// barycentric position in its coarse triangle. The posed point p is the barycentric mix
// of the coarse triangle's posed corners; it is displaced by h along the interpolated
// coarse normal n. The normal is the analytic normal of that surface S = p + h n over the
// triangle, from the wrinkle gradient (not a finite difference): with p = P0 + u e1 + v e2,
//   dS/du = e1 + (grad h . e1) n + h dn/du,   likewise for v,   N = dS/du x dS/dv.
#include "include/common.glsl"
#include "include/wave.glsl"

layout(local_size_x = LOCAL_SIZE) in;

// per fine vertex: its range [x, y) of entries; per entry, one coarse triangle the vertex
// lies in: x = the triangle (a float, exact below 2^24), yzw = barycentrics there. The
// first entry places the vertex; the normal is averaged over all of them, as a surface's
// normal is where two facets of the coarse mesh meet.
layout(binding = GEOMETRY_RANGES) uniform highp isampler2D ranges;
layout(binding = GEOMETRY_ENTRIES) uniform sampler2D entries;
layout(binding = GEOMETRY_POINTS, rgba32f) writeonly uniform image2D points_out;  // xyz, w: h
layout(binding = GEOMETRY_NORMALS, rgba32f) writeonly uniform image2D normals_out;  // xyz
uniform int u_count;
uniform int u_wrinkles;

// The displaced point of entry e (xyz) with its h (w), and its surface normal.
vec4 displaced(int e, out vec3 normal, out float amplitude) {
    vec4 row = fetch(entries, e);
    int t = int(row.x);
    vec3 bary = row.yzw;
    ivec3 corners = fetch(triangles, t).xyz;
    vec3 P[3];
    vec3 N[3];
    vec3 p = vec3(0.0);
    vec3 m = vec3(0.0);
    for (int c = 0; c < 3; ++c) {
        P[c] = fetch(posed_points, corners[c]).xyz;                  // local space
        N[c] = fetch(fields, FIELD_NORMAL(corners[c])).xyz;
        p += bary[c] * P[c];
        m += bary[c] * N[c];
    }
    float length_m = length(m);
    vec3 face = safe_normalize(cross(P[1] - P[0], P[2] - P[0]), vec3(0.0, 0.0, 1.0));
    vec3 n = length_m > 1e-30 ? m / length_m : face;
    Wave wave = Wave(0.0, vec3(0.0), 0.0);
    if (u_wrinkles != 0) {
        wave = wave_blend(t, bary, p, n, true);
    }
    float h = wave.height;
    vec3 e1 = P[1] - P[0];
    vec3 e2 = P[2] - P[0];
    // d(normalize(m))/du = (dm/du - n (n . dm/du)) / |m|, dm/du = N1 - N0
    vec3 dm_du = N[1] - N[0];
    vec3 dm_dv = N[2] - N[0];
    vec3 dn_du = length_m > 1e-30 ? (dm_du - n * dot(n, dm_du)) / length_m : vec3(0.0);
    vec3 dn_dv = length_m > 1e-30 ? (dm_dv - n * dot(n, dm_dv)) / length_m : vec3(0.0);
    vec3 s_u = e1 + dot(wave.gradient, e1) * n + h * dn_du;
    vec3 s_v = e2 + dot(wave.gradient, e2) * n + h * dn_dv;
    normal = safe_normalize(cross(s_u, s_v), n);
    if (dot(normal, n) < 0.0) normal = -normal;  // the side the coarse normal faces
    amplitude = wave.amplitude;
    return vec4(p + h * n, h);
}

void main() {
    int v = int(gl_GlobalInvocationID.x);
    if (v >= u_count) return;
    ivec2 range = fetch(ranges, v).xy;
    vec3 normal;
    float amplitude;
    vec4 point = displaced(range.x, normal, amplitude);
    vec3 normal_sum = normal;
    for (int e = range.x + 1; e < range.y; ++e) {
        float other_amplitude;
        vec3 other;
        displaced(e, other, other_amplitude);
        normal_sum += other;
    }
    STORE(points_out, v, point);
    STORE(normals_out, v, vec4(safe_normalize(normal_sum, normal), amplitude));
}
