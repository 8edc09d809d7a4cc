#version 430
// Displaced render geometry (geometry/evaluate.py): per fine vertex of the subdivided
// rest mesh, the same wave blend as the draw pass (include/wave.glsl), at the vertex's
// barycentric position in its coarse triangle. The posed point p is the barycentric mix
// of the coarse triangle's posed corners; it is displaced by h along n, the interpolated
// shading normal of the coarse mesh (the normals the draw pass shades it with). The
// normal is that of a height field h over the smooth surface n describes, from the
// wrinkle gradient (not a finite difference): N = normalize(n - g), g the 3D gradient of h
// over the coarse triangle taken into n's tangent plane. Where h = 0 it is n itself: the
// fine mesh is shaded as smoothly as the coarse one (the flat coarse facets' own normals
// jumped by up to 35 degrees at their edges).
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
// the coarse mesh's shading normals (normals pass) and each triangle corner's entry
layout(binding = GEOMETRY_SHADING_NORMALS) uniform sampler2D shading_normals;
layout(binding = GEOMETRY_NORMAL_CORNERS) uniform isampler2D normal_corners;
uniform int u_count;
uniform int u_wrinkles;
// band limit: 2 fine edges (local space), no wave shorter than the fine mesh can carry
uniform float u_min_wavelength;

// The displaced point of entry e, and its surface normal.
vec3 displaced(int e, out vec3 normal) {
    vec4 row = fetch(entries, e);
    int t = int(row.x);
    vec3 bary = row.yzw;
    ivec3 corners = fetch(triangles, t).xyz;
    vec3 P[3];
    vec3 p = vec3(0.0);
    vec3 m = vec3(0.0);
    for (int c = 0; c < 3; ++c) {
        P[c] = fetch(posed_points, corners[c]).xyz;                  // local space
        vec4 shading = fetch(shading_normals, fetch(normal_corners, 3 * t + c).x);
        vec3 corner_normal = shading.w > 0.0 ? shading.xyz
                                             : fetch(fields, FIELD_NORMAL(corners[c])).xyz;
        p += bary[c] * P[c];
        m += bary[c] * corner_normal;
    }
    vec3 face = safe_normalize(cross(P[1] - P[0], P[2] - P[0]), vec3(0.0, 0.0, 1.0));
    vec3 n = safe_normalize(m, face);
    Wave wave = Wave(0.0, vec3(0.0), 0.0);
    if (u_wrinkles != 0) {
        wave = wave_blend(t, bary, p, n, true, Footprint(vec3(0.0), vec3(0.0),
                                                         u_min_wavelength));
    }
    float h = wave.height;
    vec3 g = wave.gradient - dot(wave.gradient, n) * n;
    normal = safe_normalize(n - g, n);
    return p + h * n;
}

void main() {
    int v = int(gl_GlobalInvocationID.x);
    if (v >= u_count) return;
    ivec2 range = fetch(ranges, v).xy;
    vec3 normal;
    vec3 point = displaced(range.x, normal);
    vec3 normal_sum = normal;
    for (int e = range.x + 1; e < range.y; ++e) {
        vec3 other;
        displaced(e, other);
        normal_sum += other;
    }
    STORE(points_out, v, vec4(point, 1.0));
    STORE(normals_out, v, vec4(safe_normalize(normal_sum, normal), 0.0));
}
