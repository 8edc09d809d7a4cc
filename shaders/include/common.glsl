// Shared helpers. Spaces are named at every step, as in usdSkelImaging's skinning.glslfx.
#ifndef USDWRINKLE_COMMON_GLSL
#define USDWRINKLE_COMMON_GLSL

const float PI = 3.14159265358979323846;
const float TWO_PI = 6.28318530717958647692;

// Per-vertex wrinkle fields written by crush, read by relax and draw.
struct WrinkleField {
    vec4 normal;      // xyz: posed unit normal (local space); w: 1 if the 1-ring is usable
    vec4 wave;        // xyz: wave vector k (local space, posed); w: amplitude h
    vec4 direction;   // xyz: rest-space unit direction d of strongest compression; w: r
};

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
