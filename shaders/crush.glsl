#version 430
// Crush pass (Loviscach 2006, sec. 3): per vertex, fit the 2x2 map M of the local
// deformation over the 1-ring, bias it with the painted q, and turn the strongest
// compression into a plane wave (amplitude, wave vector, rest direction) and a
// material-anchored initial phase. Beyond the paper (docs/method.md), both off by default:
// a second wave along the other principal direction where it is compressed too
// (wrinkle:biaxial), and tension wrinkles across a stretch (wrinkle:tension).
#include "include/common.glsl"
#include "include/topology.glsl"

layout(local_size_x = LOCAL_SIZE) in;

layout(binding = CRUSH_POSED_POINTS) uniform sampler2D posed_points;  // local space
layout(binding = CRUSH_REST_POINTS) uniform sampler2D rest_points;    // local space

#if defined FACE_NORMALS
layout(binding = CRUSH_TRIANGLES) uniform highp isampler2D triangles;  // corners of each
// area-weighted face normal of each triangle (posed, local space)
layout(rgba32f, binding = CRUSH_FACE_NORMALS_OUT) writeonly uniform image2D face_normals;
#elif defined DEEPEN_GRADIENT
// the fields crush wrote: each point's deepening offset (FIELD_DEEPEN x) is read over its
// ring and its gradient written beside it (yzw); x is written back unchanged, so a
// neighbour reads the same offset before and after
layout(rgba32f, binding = CRUSH_FIELDS) uniform image2D fields;
#elif defined FROM_BAKE
// Baked wave fields (scene/baked.py): [5i] = (k, amplitude), [5i+1] = (direction, r),
// [5i+2], [5i+3]: the same for the second system, [5i+4] x: the deepening offset.
layout(binding = CRUSH_BAKED) uniform sampler2D baked;
layout(binding = CRUSH_REST_FRAME) uniform sampler2D rest_frame;
layout(binding = CRUSH_FACE_NORMALS) uniform sampler2D face_normals;
layout(rgba32f, binding = CRUSH_FIELDS) writeonly uniform image2D fields;
#else
// Rest frame per vertex: [2i] = rest normal N0, [2i+1] = rest tangent T1 (unit, orthogonal).
layout(binding = CRUSH_REST_FRAME) uniform sampler2D rest_frame;
// xyz: painted q (rest space, |q| <= 1); w: rest wavelength W.
layout(binding = CRUSH_Q_WIDTH) uniform sampler2D q_width;
layout(binding = CRUSH_FACE_NORMALS) uniform sampler2D face_normals;
// held edges (wrinkle:held, scene/params.py held_weights): x the damping strength in
// [0, 1], yzw the unit rest vector u from the holder to the point (0 on a held point)
layout(binding = CRUSH_HOLD) uniform sampler2D hold;
// x: the most the mesh's compression coarsens the point's folds (method/folds.py
// coarsening_cap: COARSENING_MAX on flat cloth, 1 where the rest surface curves one way
// at its tube's own wavelength or tighter)
layout(binding = CRUSH_COARSENING) uniform sampler2D coarsening;
// the waves' start phases (method/anchor.py): xyz the unit direction of the stripe pattern
// (rest space; the painted q's, else where nothing is painted the direction a surface
// that curves one way curves along; zero where there is none), w the start phase along it
layout(binding = CRUSH_ANCHOR) uniform sampler2D anchor;
// xy: the damped rest direction d (T1, T2 coordinates), z: 1 once written. Read from the
// wave state of the shot's previous grid frame, written into this frame's state
layout(binding = CRUSH_DAMPED_IN) uniform sampler2D damped_in;
layout(rgba32f, binding = CRUSH_DAMPED) writeonly uniform image2D damped;
layout(rgba32f, binding = CRUSH_FIELDS) writeonly uniform image2D fields;
layout(rg32f, binding = CRUSH_PHASE) writeonly uniform image2D phase;  // x, y: systems 1, 2
#endif

uniform int u_num_points;
uniform int u_num_triangles;
uniform float u_amplitude_scale;    // s
uniform float u_biaxial;            // wrinkle:biaxial, the second system's weight (0: off)
uniform float u_tension;            // wrinkle:tension, the tension wave's factor (0: off)
uniform float u_tension_threshold;  // wrinkle:tensionThreshold, the onset strain
uniform float u_slack;              // wrinkle:slack, compression taken in-plane
// crest damping (wrinkle:crestDamping, docs/method.md): d turns towards the strain's
// only by as much as the two lie more than u_damping_band radians apart (a play: it
// holds while the strain turns within the band), at once where by twice
// u_damping_deadband; 0: off
uniform float u_damping_band;
uniform float u_damping_deadband;
uniform int u_has_history;          // damped_in holds the previous grid frame's directions
// the mesh's profile's length-exact slope a|k| at u = sqrt(rho^2 - 1) = i * SLOPE_STEP
// (profiles.slope_table): the inextensible wave of that profile
uniform float u_slope[SLOPE_SAMPLES];

#if defined FACE_NORMALS

// Each triangle's normal once, so that a vertex sums its triangles' normals with one
// load each instead of three corner lookups and three points.
void main() {
    int t = int(gl_GlobalInvocationID.x);
    if (t >= u_num_triangles) return;
    ivec3 corner = fetch(triangles, t).xyz;
    vec3 p0 = fetch(posed_points, corner.x).xyz;
    vec3 p1 = fetch(posed_points, corner.y).xyz;
    vec3 p2 = fetch(posed_points, corner.z).xyz;
    STORE(face_normals, t, vec4(cross(p1 - p0, p2 - p0), 0.0));
}

#elif defined DEEPEN_GRADIENT

// The gradient of the deepening offset over the posed surface (method/deepen.py
// offset_gradient): least squares of o_j - o_i against the ring's edges in the tangent
// plane of n_i, along which the blend carries each corner's offset (include/wave.glsl).
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec4 own = imageLoad(fields, TABLE_TEXEL(FIELD_DEEPEN(i)));
    vec3 n = imageLoad(fields, TABLE_TEXEL(FIELD_NORMAL(i))).xyz;
    vec3 x_i = fetch(posed_points, i).xyz;
    mat3 ete = mat3(0.0);
    vec3 etb = vec3(0.0);
    bool any = own.x != 0.0;
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        int j = NEIGHBOR(e);
        float o_j = imageLoad(fields, TABLE_TEXEL(FIELD_DEEPEN(j))).x;
        vec3 edge = fetch(posed_points, j).xyz - x_i;
        edge -= dot(edge, n) * n;
        ete += outerProduct(edge, edge);
        etb += edge * (o_j - own.x);
        any = any || o_j != 0.0;
    }
    float scale = ete[0][0] + ete[1][1] + ete[2][2];
    mat3 system = ete + scale * outerProduct(n, n);
    vec3 gradient = vec3(0.0);
    if (any && scale > 0.0 && abs(determinant(system)) > 1e-6 * scale * scale * scale) {
        gradient = inverse(system) * etb;
    }
    STORE(fields, FIELD_DEEPEN(i), vec4(own.x, gradient));
}

#else

// Posed normal of vertex i: the area-weighted sum of its triangles' normals (local
// space), the rest normal N0 where they cancel. One function for the computed and the
// baked path, so both draw with the same normals.
vec3 posed_normal(int i, vec3 N0, out bool usable) {
    vec3 n_sum = vec3(0.0);
    for (int e = TRIANGLE_BEGIN(i); e < TRIANGLE_END(i); ++e) {
        n_sum += fetch(face_normals, INCIDENT_TRIANGLE(e)).xyz;
    }
    usable = length(N0) > 0.5 && length(n_sum) > 0.0;
    return safe_normalize(n_sum, N0);
}

#if defined FROM_BAKE

// A frame drawn from a bake: the posed normals are geometry and are computed here; the
// waves are read as baked (no fit, no relax: the bake holds the relaxed phases).
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    bool usable;
    vec3 n = posed_normal(i, fetch(rest_frame, 2 * i).xyz, usable);
    // a bake holds the drawn amplitude: all of it is drawn
    STORE(fields, FIELD_NORMAL(i), vec4(n, usable ? 2.0 : 0.0));
    STORE(fields, FIELD_WAVE(i), fetch(baked, 5 * i));
    STORE(fields, FIELD_DIRECTION(i), fetch(baked, 5 * i + 1));
    STORE(fields, FIELD_TEXELS * i + FIELD_WAVE2_TEXEL, fetch(baked, 5 * i + 2));
    STORE(fields, FIELD_TEXELS * i + FIELD_DIRECTION2_TEXEL, fetch(baked, 5 * i + 3));
    // the offset as baked; its gradient, from the posed points, by DEEPEN_GRADIENT
    STORE(fields, FIELD_DEEPEN(i), vec4(fetch(baked, 5 * i + 4).x, 0.0, 0.0, 0.0));
    // the length pass's scale: in the baked amplitudes already; no relaxation weighs them
    STORE(fields, FIELD_LENGTH(i), vec4(1.0, fetch(baked, 5 * i).w, fetch(baked, 5 * i + 2).w,
                                        0.0));
}

#else

// A rest tangent direction (2D, in T1, T2) in local space, with a deterministic sign:
// its largest component positive.
vec3 rest_direction(vec2 d, vec3 T1, vec3 T2) {
    vec3 d3 = d.x * T1 + d.y * T2;
    vec3 ad = abs(d3);
    float lead = ad.x >= ad.y && ad.x >= ad.z ? d3.x : (ad.y >= ad.z ? d3.y : d3.z);
    return lead < 0.0 ? -d3 : d3;
}

// The posed wave vector of a wave of rest (material) wavelength L along the rest
// direction d, carried by the fitted map M of the mesh alone: k = M^-T (2pi/L) d, the
// posed gradient of the material phase (2pi/L) d.X. With M = U S V^T, M^-T = U S^-1 V^T;
// each singular value is floored at r_min so that |k| <= 2pi/(L r_min) stays finite.
vec3 wave_vector(mat2 M, vec2 d, float L, vec3 t1, vec3 t2) {
    mat2 S = transpose(M) * M;
    float sa = S[0][0], sb = S[1][0], sc = S[1][1];
    float mean = 0.5 * (sa + sc);
    float radius = sqrt(max(0.25 * (sa - sc) * (sa - sc) + sb * sb, 0.0));
    float l1 = max(mean - radius, 0.0), l2 = mean + radius;
    vec2 v1;
    vec2 c1 = vec2(l1 - sc, sb), c2 = vec2(sb, l1 - sa);
    if (max(dot(c1, c1), dot(c2, c2)) > 1e-24 * max(mean * mean, 1e-30)) {
        v1 = normalize(dot(c1, c1) >= dot(c2, c2) ? c1 : c2);
    } else {
        v1 = sa <= sc ? vec2(1.0, 0.0) : vec2(0.0, 1.0);
    }
    vec2 v2 = vec2(-v1.y, v1.x);
    float s2 = sqrt(l2);
    vec2 u2 = s2 > 1e-12 ? (M * v2) / s2 : v2;
    // U is orthonormal with det U = sign(det M) (V = [v1 v2] turns by +90 degrees), so u1
    // is u2 turned back; and s1 = |M v1|. Not (M v1) / sqrt(l1): where M is nearly
    // singular, float32's mean - radius leaves l1 as noise of order 1e-7 l2 (2.4e-7 for
    // a true 1.7e-10), which made u1 0.03 long and k 37x too short
    vec2 u1 = vec2(u2.y, -u2.x) * sign(determinant(M) + 1e-30);
    float s1 = length(M * v1);
    vec2 k2 = (TWO_PI / L) * (dot(v1, d) / max(s1, MIN_RATIO) * u1
                              + dot(v2, d) / max(s2, MIN_RATIO) * u2);
    return k2.x * t1 + k2.y * t2;  // posed tangent coords -> local space
}

// a|k| of the profile's inextensible wave for the excess length rho (u_slope's table,
// linear between samples and beyond the last)
float profile_slope(float rho) {
    float u = sqrt(max(rho * rho - 1.0, 0.0)) / SLOPE_STEP;
    int i = min(int(floor(u)), SLOPE_SAMPLES - 2);
    return mix(u_slope[i], u_slope[i + 1], u - float(i));
}

// The length per posed length of the profile's wave at slope s = a|k|: sqrt(1 + u^2) at
// the u where u_slope reaches s (its inverse, linear between samples and along the last
// segment beyond them; method/deepen.py length_at)
float profile_length(float s) {
    int i = 0;
    for (int j = 1; j < SLOPE_SAMPLES - 1; ++j) {
        if (u_slope[j] <= s) i = j;
    }
    float low = u_slope[i], high = u_slope[i + 1];
    float u = (float(i) + (s - low) / max(high - low, 1e-30)) * SLOPE_STEP;
    return sqrt(1.0 + u * u);
}

// The fold law (docs/method.md, "Folds that read as cloth"). r is the compression along
// d with the painted q, r_geo the mesh's alone, across the mesh's along the other
// principal direction (1 where it is not compressed, at least ACROSS_MIN). rho is the
// length the wave restores per posed length: the mesh's compression beyond the slack
// (the cloth takes the first of it in-plane), times what the painted gather adds. The
// material wavelength coarsens with rho; the slope is the profile's inextensible one for
// the area's excess, rho with r_geo * across in place of r_geo (one wave restores the
// area where the cloth is compressed both ways); where the fold would rise beyond
// the room the posed surface's curvature leaves (``room``; the height after the
// amplitude scale), it is lowered to the room: its wave unchanged, so that the phases
// and crests stay as they are (a shorter wave that kept the length moved crests).
struct Fold {
    vec3 k;
    float amplitude;   // before the amplitude scale and the held edges
    float full;        // the same before the room lowered it (the deepening's)
    float wavelength;  // material (rest space): what the anchored phase counts
    // the share of the amplitude the surface draws: below 1 where the mesh is stretched
    // across d (it holds that share of the cloth's area already); the relaxation weighs
    // the phases by ``weight``, never by this share (weighing by it moved the crests)
    float drawn;
    // the fold the relaxation weighs the phases by: the law with the crests' slack
    // (wrinkle:slack) in place of the drawn folds' (DRAWN_SLACK of it), within the room;
    // 0 where the compression is within the slack
    float weight;
};

// the slack c: the first of the compression is taken in-plane; the folds begin at a
// compression of c (restoring all but c) and restore the whole rest length from SLACK_RAMP c
// on (a smooth onset, so that a compression that comes and goes near it does not make
// crests appear and vanish). What the mesh's compression r_geo asks the folds to restore.
float excess_of(float r_geo, float c) {
    if (!(c > 0.0)) return max(1.0, 1.0 / r_geo);
    float restored = 1.0 - c * smoothstep(1.0 - SLACK_RAMP * c, 1.0 - c, r_geo);
    return max(1.0, restored / r_geo);
}

// The fold of compression r (r_geo the mesh's alone) drawn with the slack c_fold, its wave
// (coarsening) and its relaxation weight with the crests' slack c_wave (>= c_fold): the
// folds are drawn from a compression of c_fold, and the crests are set by the folds beyond
// c_wave, where the compression has a direction of its own (docs/method.md, "The fold law")
Fold fold(mat2 M_geo, vec2 d, float r, float r_geo, float across, float stretched,
          float W, float cap, float room, float scale, vec3 t1, vec3 t2, float c_wave,
          float c_fold) {
    Fold f;
    f.drawn = 1.0;
    // r == r_geo where nothing is painted: exactly 1 there (a GPU's division, a * rcp(b),
    // may give 1 + 1 ulp, and a fold of 1e-4 W at every point within the slack: an H200
    // drew them at random points, whose waves switched on and off under a 0.01 degree
    // change of a joint and moved the crests)
    float gather = r == r_geo ? 1.0 : min(r_geo / r, PAINT_GATHER_MAX);
    float rho = excess_of(r_geo, c_wave) * gather;
    float rho_fold = excess_of(r_geo, c_fold) * gather;
    if (!(rho_fold > 1.0)) {
        f.k = wave_vector(M_geo, d, W, t1, t2);
        f.amplitude = 0.0;
        f.full = 0.0;
        f.wavelength = W;
        f.weight = 0.0;
        return f;
    }
    // coarsening up to the point's cap (COARSENING_MAX on flat cloth, 1 where the rest
    // surface curves one way: folds.coarsening_cap), by the crests' excess (W within it)
    float L = W * min(pow(max(rho, 1.0), COARSENING_EXPONENT), cap);
    f.k = wave_vector(M_geo, d, L, t1, t2);
    float lowest = room / max(scale, 1e-30);
    f.weight = rho > 1.0
        ? min(profile_slope(max(rho, excess_of(r_geo * across, c_wave) * gather))
              / max(length(f.k), 1e-30), lowest)
        : 0.0;
    float rho_area = max(rho_fold, excess_of(r_geo * across, c_fold) * gather);
    f.amplitude = profile_slope(rho_area) / max(length(f.k), 1e-30);
    // the fold that restores the area the stretched mesh lacks (its slope for the excess
    // with r_geo * across * stretched in place of r_geo), within the same room
    float lowered = profile_slope(excess_of(r_geo * across * stretched, c_fold) * gather)
                    / max(length(f.k), 1e-30);
    f.full = f.amplitude;
    f.amplitude = min(f.amplitude, lowest);
    lowered = min(lowered, lowest);
    f.drawn = f.amplitude > 0.0 ? min(lowered / f.amplitude, 1.0) : 1.0;
    f.wavelength = L;
    return f;
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;

    vec3 x_i = fetch(posed_points, i).xyz;       // posed, local space
    vec3 X_i = fetch(rest_points, i).xyz;        // rest, local space
    vec3 N0 = fetch(rest_frame, 2 * i).xyz;      // rest normal
    vec3 T1 = fetch(rest_frame, 2 * i + 1).xyz;  // rest tangent
    vec3 T2 = cross(N0, T1);
    vec4 q_w = fetch(q_width, i);
    float W = q_w.w;

    bool usable;
    vec3 n = posed_normal(i, N0, usable);

    // posed tangent frame: the rest frame carried by the minimal rotation N0 -> n
    vec3 t1 = safe_normalize(minimal_rotation(N0, n, T1, T1), T1);
    vec3 t2 = cross(n, t1);

    // least squares M a_j ~ b_j over the 1-ring: M = (sum b a^T)(sum a a^T)^-1
    mat2 AA = mat2(0.0);
    mat2 BA = mat2(0.0);
    int count = 0;
    float bend = 0.0;  // the posed surface's largest normal curvature over the ring
    // the second fundamental form's fit (method/deepen.py fit_form): normal equations of
    // kappa_e = 2 (e.n) / |e|^2 against (x^2, 2xy, y^2) of each edge's unit direction
    mat3 form_aa = mat3(0.0);
    vec3 form_ab = vec3(0.0);
    int form_count = 0;
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        int j = NEIGHBOR(e);
        vec3 rest_edge = fetch(rest_points, j).xyz - X_i;     // rest, local space
        vec3 posed_edge = fetch(posed_points, j).xyz - x_i;   // posed, local space
        vec2 a = vec2(dot(rest_edge, T1), dot(rest_edge, T2));  // rest tangent coords
        vec2 b = vec2(dot(posed_edge, t1), dot(posed_edge, t2)); // posed tangent coords
        AA += outerProduct(a, a);
        BA += outerProduct(b, a);
        ++count;
        // how fast the posed normals turn along this edge: a fold displaced along them
        // that rises beyond 1 / turn on the inner side meets its neighbour (the normals
        // converge there); and the circle through both points tangent to the plane of n
        // (2 |e.n| / |e|^2), which a coarse ring of a cylinder gives exactly
        float e2 = dot(posed_edge, posed_edge);
        float tangent_length = length(b);
        if (e2 > 0.0 && tangent_length > 0.0) {
            vec2 u = b / tangent_length;
            vec3 row = vec3(u.x * u.x, 2.0 * u.x * u.y, u.y * u.y);
            form_aa += outerProduct(row, row);
            form_ab += row * (2.0 * dot(posed_edge, n) / e2);
            ++form_count;
        }
        if (e2 > 0.0) {
            bool usable_j;
            vec3 n_j = posed_normal(j, fetch(rest_frame, 2 * j).xyz, usable_j);
            bend = max(bend, max(2.0 * abs(dot(posed_edge, n)), length(n_j - n) * sqrt(e2))
                             / e2);
        }
    }
    float det_a = determinant(AA);
    float trace_a = AA[0][0] + AA[1][1];
    // fewer than 2 independent edges (collinear, coincident, isolated): no wrinkle
    usable = usable && count >= 2 && trace_a > 0.0 && det_a > 1e-6 * trace_a * trace_a;
    // the mesh's own map, before the painted bias: the posed waves ride on it
    mat2 M_geo = usable ? BA * inverse(AA) : mat2(1.0);
    mat2 M = M_geo;

    // painted bias: M <- M (I - q q^T), q projected to the rest tangent plane
    vec3 q3 = q_w.xyz;
    vec2 q = vec2(dot(q3, T1), dot(q3, T2));
    float q_len = length(q);
    if (q_len > 1.0) q /= q_len;
    M = M * (mat2(1.0) - outerProduct(q, q));

    // eigenpairs of the symmetric S = M^T M: the smallest (the strongest compression) and,
    // at right angles in the rest tangent plane, the largest
    mat2 S = transpose(M) * M;
    float sa = S[0][0], sb = S[1][0], sc = S[1][1];
    float mean = 0.5 * (sa + sc);
    float radius = sqrt(max(0.25 * (sa - sc) * (sa - sc) + sb * sb, 0.0));
    float lambda = max(mean - radius, 0.0);
    float lambda2 = mean + radius;
    vec2 d;
    vec2 v1 = vec2(lambda - sc, sb);
    vec2 v2 = vec2(sb, lambda - sa);
    if (max(dot(v1, v1), dot(v2, v2)) > 1e-24 * max(mean * mean, 1e-30)) {
        d = normalize(dot(v1, v1) >= dot(v2, v2) ? v1 : v2);
    } else {
        d = sa <= sc ? vec2(1.0, 0.0) : vec2(0.0, 1.0);
    }
    // Crest damping (docs/method.md): the rest direction turns towards the strain's only
    // by as much as the two lie more than u_damping_band radians apart, so it holds while
    // the strain trembles within the band, follows a steady turn with a lag of the band,
    // and stops the frame the strain stops (an exponential lag, as before 2026-12-06,
    // caught up over the frames after a pose stopped: the referee's held 25 cm sleeve's
    // crests moved 3.9x the cloth's in its first held frame; docs/method.md); at once
    // when they lie u_damping_deadband apart or more, fully from twice that; r is then
    // the compression along it
    vec4 before = u_has_history != 0 ? fetch(damped_in, i) : vec4(0.0);
    if (u_has_history != 0 && u_damping_band > 0.0 && before.z > 0.5) {
        vec2 d_before = dot(before.xy, d) < 0.0 ? -before.xy : before.xy;
        float turn = acos(clamp(dot(d_before, d), 0.0, 1.0));
        // the share of the turn that rotates d_before by turn - band (slerp's weight)
        float played = max(turn - u_damping_band, 0.0);
        float share = played <= 0.0 ? 0.0
                    : sin(played) / (sin(played) + sin(turn - played));
        float follow = mix(share, 1.0,
                           smoothstep(u_damping_deadband, 2.0 * u_damping_deadband, turn));
        // ... where there are crests to damp: where the strain compresses the cloth no
        // further than the slack (no fold), d follows it at once, from none to fully
        // damped over the slack's onset (the fold law's). An isotropic or barely
        // compressed strain has no direction of its own; damped, rounding's direction of
        // the frames before carried into the first folds (the shirt's elbow: 2 degrees
        // apart under a 0.01 degree change of a joint, which moved 18% of its crests;
        // docs/method.md, "Crest damping")
        if (u_slack > 0.0) {
            follow = mix(follow, 1.0, smoothstep(1.0 - SLACK_RAMP * u_slack, 1.0 - u_slack,
                                                 sqrt(lambda)));
        }
        vec2 turned = mix(d_before, d, follow);
        d = dot(turned, turned) > 1e-24 ? normalize(turned) : d;
    }
    vec3 d3 = rest_direction(d, T1, T2);
    if (dot(d3, d.x * T1 + d.y * T2) < 0.0) d = -d;
    vec2 e = vec2(-d.y, d.x);  // the other principal direction
    vec3 e3 = rest_direction(e, T1, T2);
    if (dot(e3, e.x * T1 + e.y * T2) < 0.0) e = -e;

    // r in [r_min, 1]: a ring crushed flat still has a finite wavelength
    bool any_wave = usable || q_len > 0.0;
    // |M d| = sqrt(lambda) for the eigenvector; a damped d reads the compression along it
    float r = any_wave ? clamp(length(M * d), MIN_RATIO, 1.0) : 1.0;
    float r_geo = any_wave ? clamp(length(M_geo * d), MIN_RATIO, 1.0) : 1.0;
    // held edges (docs/method.md): a wave whose crests run into the held edge (d across u)
    // fades towards it by the strength x; one whose crests run along it keeps its amplitude
    vec4 holder = fetch(hold, i);
    float along = dot(normalize(d3), holder.yzw);
    float held = 1.0 - holder.x * (1.0 - along * along);
    float cap = fetch(coarsening, i).x;
    // room for a fold: FOLD_ROOM of the posed surface's radius of curvature
    float room = bend > 0.0 ? FOLD_ROOM / bend : 1e30;
    // the mesh's compression across d, which one wave restores with its own where the
    // second system is off (with it on, that system restores it) ...
    float across = u_biaxial > 0.0 || !usable ? 1.0
                   : clamp(length(M_geo * e), ACROSS_MIN, 1.0);
    // and its stretch across d beyond STRETCH_ONSET (a wrinkling cloth's own stretch
    // lies below it), up to ACROSS_MAX, which lowers only the drawn fold
    float stretched = usable ? clamp(length(M_geo * e) / STRETCH_ONSET, 1.0, ACROSS_MAX)
                             : 1.0;
    float drawn_slack = DRAWN_SLACK * u_slack;
    Fold f1 = fold(M_geo, d, r, r_geo, across, stretched, W, cap, room, u_amplitude_scale,
                   t1, t2, u_slack, drawn_slack);
    float drawn = f1.drawn;
    float amplitude = held * u_amplitude_scale * f1.amplitude;
    float weight = held * u_amplitude_scale * f1.weight;
    vec3 k = f1.k;
    float wavelength = f1.wavelength;  // the material-anchored phase's (rest space)
    bool compression_wave = true;      // false where the tension wave takes its place

    // Tension (docs/method.md): across the largest stretch s1 = sqrt(lambda2) beyond the
    // onset, crests along the pull. It shares the direction d (the other principal
    // direction) with the compression wave; the larger amplitude wins.
    float stretch = sqrt(max(lambda2, 0.0));
    float strain = stretch - 1.0 - u_tension_threshold;
    if (u_tension > 0.0 && usable && strain > 0.0) {
        float tension_wavelength = W * pow(strain / TENSION_REFERENCE_STRAIN, -0.25);
        float tension_amplitude = held * u_amplitude_scale * u_tension * TENSION_SLOPE
            * sqrt(strain) * tension_wavelength;
        if (tension_amplitude > amplitude) {
            amplitude = tension_amplitude;
            weight = tension_amplitude;
            drawn = 1.0;
            wavelength = tension_wavelength;
            k = wave_vector(M_geo, d, wavelength, t1, t2);
            compression_wave = false;
        }
    }

    // Deepened pleats (method/deepen.py): where the room lowered the fold, the length it
    // does not draw goes into an offset along n, away from the centre of curvature along
    // the wave, at most DEEPEN_CAP of the full fold and fading where the surface is flat
    float offset = 0.0;
    float drawn_amplitude = amplitude * drawn;
    float full = room < 1e30 ? drawn_amplitude * max(f1.full * u_amplitude_scale / room, 1.0)
                             : drawn_amplitude;
    float form_scale = form_aa[0][0] + form_aa[1][1] + form_aa[2][2];
    if (compression_wave && usable && full > drawn_amplitude && drawn_amplitude > 0.0
            && form_count >= 3
            && abs(determinant(form_aa)) > 1e-6 * form_scale * form_scale * form_scale) {
        vec3 form = inverse(form_aa) * form_ab;
        vec2 along = vec2(dot(k, t1), dot(k, t2));
        float along_length = length(along);
        float kappa = 0.0;
        if (along_length > 0.0) {
            along /= along_length;
            kappa = form.x * along.x * along.x + 2.0 * form.y * along.x * along.y
                  + form.z * along.y * along.y;
        }
        float curve = abs(kappa);
        if (curve > 0.0) {
            float kl = length(k);
            float gain = profile_length(full * kl) / profile_length(drawn_amplitude * kl);
            float c = min(min((gain - 1.0) / curve, DEEPEN_CAP * full),
                          full * curve * full / FOLD_ROOM);
            offset = -sign(kappa) * max(c, 0.0);
        }
    }

    // The second system: the other principal direction, where it is compressed too
    float r2 = any_wave ? clamp(length(M * e), MIN_RATIO, 1.0) : 1.0;
    float r2_geo = any_wave ? clamp(length(M_geo * e), MIN_RATIO, 1.0) : 1.0;
    Fold f2 = fold(M_geo, e, r2, r2_geo, 1.0, 1.0, W, cap, room,
                   u_amplitude_scale * u_biaxial, t1, t2, u_slack, drawn_slack);
    float amplitude2 = u_biaxial > 0.0 ? held * u_biaxial * u_amplitude_scale * f2.amplitude
                                        : 0.0;
    float weight2 = u_biaxial > 0.0 ? held * u_biaxial * u_amplitude_scale * f2.weight : 0.0;
    vec3 k2 = f2.k;

    STORE(fields, FIELD_NORMAL(i), vec4(n, usable ? 1.0 + drawn : 0.0));
    STORE(fields, FIELD_WAVE(i), vec4(k, amplitude));
    STORE(fields, FIELD_DIRECTION(i), vec4(d3, r));
    STORE(fields, FIELD_TEXELS * i + FIELD_WAVE2_TEXEL, vec4(k2, amplitude2));
    STORE(fields, FIELD_TEXELS * i + FIELD_DIRECTION2_TEXEL, vec4(e3, r2));
    // its gradient: DEEPEN_GRADIENT, once every point's offset is written
    STORE(fields, FIELD_DEEPEN(i), vec4(offset, 0.0, 0.0, 0.0));
    // the length pass's scale (length.glsl): none until it runs; the relaxation's weights
    STORE(fields, FIELD_LENGTH(i), vec4(1.0, weight, weight2, 0.0));
    // material-anchored start: crests ride with the cloth, frames stay independent.
    // Where the wave runs along the anchor table's direction (within 45 degrees: the
    // paint's, or a gathered tube's curvature), that stripe pattern in rest space
    // (method/anchor.py), its sign d's
    // the state's damped direction, and the material wave number its mobility reads
    imageStore(damped, TABLE_TEXEL(i), vec4(d, 1.0, TWO_PI / wavelength));
    float start = (TWO_PI / wavelength) * dot(d3, X_i);
    vec4 painted = fetch(anchor, i);
    float along_paint = dot(normalize(d3), painted.xyz);
    if (abs(along_paint) >= ANCHOR_ALIGNED) start = along_paint < 0.0 ? -painted.w : painted.w;
    STORE(phase, i, vec4(start, (TWO_PI / f2.wavelength) * dot(e3, X_i), 0.0, 0.0));
}

#endif

#endif
