#version 430
// Length pass (render/passes/length.py; docs/method.md, "The cloth's length"): no ring of
// the wrinkled surface draws more than the cloth's rest area around it.
//
// The crush law gives each vertex's wave the slope a |k| that restores its own
// compression. Inside a triangle the draw blends the three corner waves, each carried
// from its corner; where they disagree (directions, wavelengths, phases), the blend has
// slopes no corner asked for, and the coherence's gain (wave.glsl) adds more; where the
// mesh is stretched across the wave by less than STRETCH_ONSET the law restores the
// length along the wave, not the area. The converged referee's curtains drew 4-9% more
// than the cloth has below their rings (docs/physics.md, "Where our area goes, band by
// band"), the sheared panels 6-8% more than their rest area, the pillow 3%.
//
// Per vertex i, over the triangles around it (its ring), m x m points per triangle (the
// centroids of its m x m sub-triangles, each weighing a 1 / m^2 share of the triangle's
// posed area; m from the waves' phase advance across the triangle, 4 points a
// wavelength, at most what LENGTH_SAMPLES leaves each triangle of the ring), the blend's
// surface is sampled with its exact gradient over the flat triangle (wave.glsl, as the
// displaced geometry differentiates it): the ring draws sum w sqrt(1 + |s g + d|^2) at a
// scale s of its folds (g: the folds' gradient in the triangle's plane, d: the deepened
// pleats', which are not scaled). Where the ring is compressed (its posed area over its
// rest area, ratio, below 1 - slack), it may draw the rest area the slack leaves,
// restored = 1 - slack smoothstep(1 - SLACK_RAMP slack, 1 - slack, ratio) times the ring's
// rest area (crush's law for an area; at least the posed area), and LENGTH_TOLERANCE
// more (3%: the samples' own error). s is the largest in [0, 1] that keeps the ring
// within it (Newton steps kept inside their bracket, else
// bisected), ramped in as the law restores the whole rest area (from 1 - slack to
// 1 - SLACK_RAMP slack), so that a ring crossing the onset does not switch its scale.
// Only down: lifting the rings that draw less (the held edges' fade, the coherence floor)
// up to 2x over-drew the converged referee's leather curtain (1.084 on its 2 cm run) and
// the shirt where compressed one way (1.102).
//
// A blend that is a single plane wave over the ring (the analytic cases) keeps s = 1
// exactly: it is compared with the blend of corners that agree (each corner carrying
// vertex i's wave, its k and its phase carried to the corner, at the corner's own slope
// a_c |k_c|): sum |g - g_ref|^2 <= LENGTH_SNAP^2 sum |g_ref|^2. The crush law sized that
// wave, and sampling would only add its error. Only a ring that draws more than it may
// at s = 1 asks (a second walk over the same samples, with the folds' gradients kept from
// the first): elsewhere s is 1 either way. The reference blend on every ring took
// 17-42% of the pass's time on llvmpipe (the zeppelin, CesiumMan, the pillow); and the
// second walk stops where its partial sum already fails the test (main), which cut the
// pass by a third (the shirt 5.4 -> 3.6 ms a frame, CesiumMan 19.6 -> 14.3).
//
// Entry points:
//   (default) per vertex: its scale into the scale table (x; 1 where it has no fold)
//   APPLY     per vertex: its scale into its length texel (x), which the blend's
//             corner_waves multiply both systems' drawn amplitudes by (once every scale
//             is written: each vertex's samples read its neighbours' folds). The
//             amplitudes themselves stay the fold law's: the relaxation and the next
//             frame's seed weigh the phases by them
#include "include/common.glsl"
#include "include/topology.glsl"

layout(local_size_x = LOCAL_SIZE) in;

uniform int u_num_points;

#if defined APPLY

layout(binding = LENGTH_SCALE) uniform sampler2D scale_table;
// read and written: the scale goes into x, the relaxation's weights (yz) stay
layout(rgba32f, binding = LENGTH_FIELDS) uniform image2D fields_image;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec4 texel = imageLoad(fields_image, TABLE_TEXEL(FIELD_LENGTH(i)));
    imageStore(fields_image, TABLE_TEXEL(FIELD_LENGTH(i)),
               vec4(fetch(scale_table, i).x, texel.yzw));
}

#else

#include "include/wave.glsl"

layout(binding = LENGTH_REST_POINTS) uniform sampler2D length_rest_points;  // local space
layout(r32f, binding = LENGTH_SCALE_OUT) writeonly uniform image2D scale_out;
uniform float u_slack;  // wrinkle:slack

// one sample: the folds' gradient g and the pleats' d as |g|^2, g . d, |d|^2
vec3 samples[LENGTH_SAMPLES];
float sample_weight[LENGTH_SAMPLES];
vec3 folds_gradient[LENGTH_SAMPLES];  // g itself, for the second walk

vec3 in_plane(vec3 v, vec3 n) { return v - dot(v, n) * n; }

// what the ring draws at scale s of its folds, less ``target``, and its derivative
vec2 drawn_over(float s, int count, float target) {
    vec2 out_ = vec2(-target, 0.0);
    for (int j = 0; j < count; ++j) {
        vec3 q = samples[j];
        float root = sqrt(max(1.0 + s * s * q.x + 2.0 * s * q.y + q.z, 1e-30));
        out_ += sample_weight[j] * vec2(root, (s * q.x + q.y) / root);
    }
    return out_;
}

// Walks the ring's samples, the same points in the same order on every walk. With
// against_agreeing false: each sample's |g|^2, g . d, |d|^2 and weight into samples and
// sample_weight, and g itself into folds_gradient; returns their count. With it true
// (after such a walk): sums |g - g_ref|^2 (x) and |g_ref|^2 (y) over the same samples
// into totals, g from folds_gradient and g_ref the blend of the corners that agree (each
// carrying vertex i's wave, its k and its phase carried to the corner, at the corner's
// own slope a_c |k_c|); it stops as soon as the sum of |g - g_ref|^2 passes ``apart_max``
// (returning -1), where the ring can no longer be that plane wave (main, below).
int walk_ring(int i, int begin, int end, bool against_agreeing, float apart_max,
              out vec2 totals) {
    int per_triangle = max(int(floor(sqrt(float(LENGTH_SAMPLES) / float(end - begin)))), 1);
    int count = 0;
    totals = vec2(0.0);
    for (int e = begin; e < end; ++e) {
        int t = INCIDENT_TRIANGLE(e);
        CornerWaves cw = corner_waves(t);
        ivec3 corners = fetch(triangles, t).xyz;
        int mine = corners.x == i ? 0 : (corners.y == i ? 1 : 2);
        vec3 P0 = cw.corner[0];
        vec3 P1 = cw.corner[1];
        vec3 P2 = cw.corner[2];
        vec3 face = cross(P1 - P0, P2 - P0);
        float area = 0.5 * length(face);
        if (!(area > 0.0)) continue;
        vec3 n = face / (2.0 * area);
        // the waves' phase advance across the triangle: 4 samples a wavelength
        float reach = max(max(length(P1 - P0), length(P2 - P1)), length(P0 - P2));
        float k_max = 0.0;
        for (int w = 0; w < WAVE_SLOTS; ++w) {
            if (cw.wave[w].w > 0.0) k_max = max(k_max, length(cw.wave[w].xyz));
        }
        int m = min(max(int(ceil(4.0 * k_max * reach / TWO_PI)), 2), per_triangle);
        // the folds alone (the pleats apart)
        CornerWaves folds = cw;
        for (int c = 0; c < 3; ++c) folds.deepen[c] = vec4(0.0);
        vec3 grad_b[3];
        for (int c = 0; c < 3; ++c) grad_b[c] = weight_gradient(c, P0, P1, P2);
        // the corners that agree: each carries vertex i's wave (its k, its phase carried
        // to the corner) at the corner's own slope a_c |k_c|
        CornerWaves agree = folds;
        for (int system = 0; against_agreeing && system < SYSTEMS; ++system) {
            vec3 k_i = cw.wave[3 * system + mine].xyz;
            float k_len = length(k_i);
            for (int c = 0; c < 3; ++c) {
                vec4 wave_c = cw.wave[3 * system + c];
                float a = k_len > 0.0 ? wave_c.w * length(wave_c.xyz) / k_len : 0.0;
                agree.wave[3 * system + c] = vec4(k_i, a);
                agree.phase[system][c] = cw.phase[system][mine]
                                       + dot(k_i, cw.corner[c] - cw.corner[mine]);
            }
        }
        Footprint none = Footprint(vec3(0.0), vec3(0.0), 0.0);
        for (int a = 0; a < m; ++a) {
            for (int b = 0; b < m - a; ++b) {
                // the two sub-triangles of cell (a, b): up, and down where there is one
                for (int down = 0; down < 2; ++down) {
                    if (down == 1 && a + b + 1 >= m) continue;
                    if (count >= LENGTH_SAMPLES) continue;
                    vec2 uv = (vec2(float(a), float(b))
                               + vec2(down == 0 ? 1.0 / 3.0 : 2.0 / 3.0)) / float(m);
                    vec3 bary = vec3(1.0 - uv.x - uv.y, uv.x, uv.y);
                    vec3 p = bary.x * P0 + bary.y * P1 + bary.z * P2;
                    if (against_agreeing) {
                        vec3 g = folds_gradient[count];
                        vec3 g_ref = in_plane(blend_corner_waves(agree, bary, p, n, true,
                                                                 none).gradient, n);
                        vec3 apart = g - g_ref;
                        totals += vec2(dot(apart, apart), dot(g_ref, g_ref));
                        if (totals.x > apart_max) return -1;
                        ++count;
                        continue;
                    }
                    float weight = area / float(m * m);
                    // the pleats' gradient (as blend_corner_waves carries them)
                    vec3 d = vec3(0.0);
                    for (int c = 0; c < 3; ++c) {
                        float carried = cw.deepen[c].x
                                      + dot(cw.deepen[c].yzw, p - cw.corner[c]);
                        d += bary[c] * cw.deepen[c].yzw + carried * grad_b[c];
                    }
                    d = in_plane(d, n);
                    vec3 g = in_plane(blend_corner_waves(folds, bary, p, n, true, none)
                                      .gradient, n);
                    folds_gradient[count] = g;
                    samples[count] = vec3(dot(g, g), dot(g, d), dot(d, d));
                    sample_weight[count] = weight;
                    ++count;
                }
            }
        }
    }
    return count;
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec4 wave1 = fetch(fields, FIELD_WAVE(i));  // the length texel still says 1 here
    vec4 wave2 = SYSTEMS > 1 ? fetch(fields, FIELD_WAVE_OF(i, 1)) : vec4(0.0);
    float own = wave1.w * drawn_share(i);
    int begin = TRIANGLE_BEGIN(i);
    int end = TRIANGLE_END(i);
    // a fold of slope below LENGTH_MIN_SLOPE draws nothing (a 1e-8 of the length), and
    // its scale would be float32's noise
    if (!(own * length(wave1.xyz) >= LENGTH_MIN_SLOPE
          || wave2.w * length(wave2.xyz) >= LENGTH_MIN_SLOPE) || end <= begin) {
        imageStore(scale_out, TABLE_TEXEL(i), vec4(1.0));
        return;
    }
    // the ring's compression, and how much of it the law restores
    float rest_area = 0.0;
    float posed_area = 0.0;
    for (int e = begin; e < end; ++e) {
        ivec3 corners = fetch(triangles, INCIDENT_TRIANGLE(e)).xyz;
        vec3 R0 = fetch(length_rest_points, corners.x).xyz;
        vec3 P0 = fetch(posed_points, corners.x).xyz;
        rest_area += 0.5 * length(cross(fetch(length_rest_points, corners.y).xyz - R0,
                                        fetch(length_rest_points, corners.z).xyz - R0));
        posed_area += 0.5 * length(cross(fetch(posed_points, corners.y).xyz - P0,
                                         fetch(posed_points, corners.z).xyz - P0));
    }
    float ratio = posed_area / max(rest_area, 1e-30);
    // the drawn folds' slack (crush.glsl's): their allowance
    float slack = DRAWN_SLACK * u_slack;
    float onset = slack > 0.0
        ? smoothstep(1.0 - SLACK_RAMP * slack, 1.0 - slack, ratio)
        : (ratio < 1.0 ? 0.0 : 1.0);
    float ramp = 1.0 - onset;
    if (!(ramp > 0.0)) {
        imageStore(scale_out, TABLE_TEXEL(i), vec4(1.0));
        return;
    }
    float target = max((1.0 - slack * onset) * rest_area, posed_area);

    vec2 totals;
    int count = walk_ring(i, begin, end, false, 0.0, totals);
    float s = 1.0;
    // the samples' own error (4 a wavelength, a ring a few wavelengths wide) is no reason
    // to scale: a ring may draw LENGTH_TOLERANCE more
    target *= 1.0 + LENGTH_TOLERANCE;
    vec2 f = count > 0 ? drawn_over(1.0, count, target) : vec2(0.0);
    // a single plane wave over the ring keeps the law's own s = 1 (above): asked only of
    // a ring that draws more than it may, where it decides something
    //
    // The walk stops early where it can only fail: with G^2 = sum |g|^2 (the first walk's)
    // and D^2 = sum |g - g_ref|^2, Minkowski's sqrt(sum |g_ref|^2) <= G + D, so the ring
    // passes only with D <= SNAP (G + D), D <= SNAP G / (1 - SNAP); a partial sum of D^2
    // beyond that (and a 1% margin for float32's sums) fails it whatever the rest add.
    // A real ring's walk ends at its first samples that part from the plane wave
    if (f.x > 0.0) {
        float g_total = 0.0;
        for (int j = 0; j < count; ++j) g_total += samples[j].x;
        float bound = LENGTH_SNAP * sqrt(g_total) / (1.0 - LENGTH_SNAP);
        if (walk_ring(i, begin, end, true, 1.01 * bound * bound, totals) >= 0
                && totals.x <= LENGTH_SNAP * LENGTH_SNAP * totals.y) {
            f = vec2(0.0);
        }
    }
    if (f.x > 0.0) {
        // the ring draws more than it may at s = 1: the s in [0, 1] at which it draws
        // that (0 where the pleats alone draw more); the first step starts from s = 1's
        float low = 0.0, high = 1.0;
        for (int step = 0; step < LENGTH_STEPS; ++step) {
            if (step > 0) f = drawn_over(s, count, target);
            if (f.x > 0.0) high = s; else low = s;
            float next = f.y > 0.0 ? s - f.x / f.y : 0.5 * (low + high);
            // within the bracket, its ends included: at the root the step moves s by
            // nothing, and s is one of the ends (a strict test bisected away from the
            // root there, and a ring's scale depended on where LENGTH_STEPS stopped
            // that cycle: up to a quarter of it off on a random cloth)
            s = next >= low && next <= high ? next : 0.5 * (low + high);
        }
        s = mix(1.0, s, float(LENGTH_LAW) * ramp);
    }
    imageStore(scale_out, TABLE_TEXEL(i), vec4(s));
}

#endif
