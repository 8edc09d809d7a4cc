// Shared helpers. Spaces are named at every step, as in usdSkelImaging's skinning.glslfx.
#ifndef USDWRINKLE_COMMON_GLSL
#define USDWRINKLE_COMMON_GLSL

const float PI = 3.14159265358979323846;
const float TWO_PI = 6.28318530717958647692;

// Tables (render/resources.py): element i of a table is texel (i % TABLE_WIDTH,
// i / TABLE_WIDTH) of a 2D texture. Read with fetch (texelFetch), write with STORE
// (imageStore). fetch is a function, not a macro: Mesa's preprocessor rejects a macro
// used inside its own argument, as in fetch(points, TRIANGLE_CORNER(t, 0)).
#define TABLE_TEXEL(i) ivec2((i) & (TABLE_WIDTH - 1), (i) >> TABLE_WIDTH_LOG2)
#define STORE(image, i, value) imageStore(image, TABLE_TEXEL(i), value)
vec4 fetch(sampler2D table, int i) { return texelFetch(table, TABLE_TEXEL(i), 0); }
ivec4 fetch(isampler2D table, int i) { return texelFetch(table, TABLE_TEXEL(i), 0); }

// Per-vertex wrinkle fields written by crush, read by relax and draw: FIELD_TEXELS texels
// of the fields table per vertex (layout and constants: src/usdwrinkle/contract.py).
#define FIELD_NORMAL(i) (FIELD_TEXELS * (i) + FIELD_NORMAL_TEXEL)
#define FIELD_WAVE(i) (FIELD_TEXELS * (i) + FIELD_WAVE_TEXEL)
#define FIELD_DIRECTION(i) (FIELD_TEXELS * (i) + FIELD_DIRECTION_TEXEL)
#define FIELD_DEEPEN(i) (FIELD_TEXELS * (i) + FIELD_DEEPEN_TEXEL)
#define FIELD_LENGTH(i) (FIELD_TEXELS * (i) + FIELD_LENGTH_TEXEL)
// wave system s (0: the strongest compression or tension, 1: the second compression)
#define FIELD_WAVE_OF(i, s) (FIELD_TEXELS * (i) + ((s) == 0 ? FIELD_WAVE_TEXEL : FIELD_WAVE2_TEXEL))

// A corner of a draw that is not indexed (corner = gl_VertexID = 3 t + c): its triangle t,
// its place c in the triangle, and the point i the triangles table gives it there.
struct DrawCorner { int t; int c; int i; };
DrawCorner draw_corner(isampler2D triangles, int corner) {
    DrawCorner dc;
    dc.t = corner / 3;
    dc.c = corner - 3 * dc.t;
    dc.i = fetch(triangles, dc.t)[dc.c];
    return dc;
}

// Which wave system of a vertex partners system ``own`` (wave vector k) of another: the
// one with an amplitude whose wave vector is most parallel to k (the two eigenvectors can
// swap between neighbours and between frames). With none within 60 degrees, the same
// index: a partner with no amplitude, which couples with the weight floor only.
int partner_system(vec3 k, int own, vec4 wave0, vec4 wave1) {
    float k_len = max(length(k), 1e-30);
    float c0 = wave0.w > 0.0 ? abs(dot(k, wave0.xyz)) / (k_len * max(length(wave0.xyz), 1e-30))
                             : -1.0;
    float c1 = wave1.w > 0.0 ? abs(dot(k, wave1.xyz)) / (k_len * max(length(wave1.xyz), 1e-30))
                             : -1.0;
    if (max(c0, c1) < 0.5) return own;
    return c1 > c0 ? 1 : 0;
}

vec3 safe_normalize(vec3 v, vec3 fallback) {
    float len = length(v);
    return len > 1e-30 ? v / len : fallback;
}

// Rotate v by the minimal rotation that takes unit a onto unit b (Rodrigues).
// Antiparallel a, b: rotate by pi about 'flip_axis' (a unit vector orthogonal to a).
vec3 minimal_rotation(vec3 a, vec3 b, vec3 v, vec3 flip_axis) {
    float c = dot(a, b);
    if (c < -0.999999) {
        return 2.0 * dot(flip_axis, v) * flip_axis - v;
    }
    vec3 axis = cross(a, b);
    return v * c + cross(axis, v) + axis * (dot(axis, v) / (1.0 + c));
}

#endif
