// The wave blend (Loviscach 2006, sec. 5): at a point of a triangle, the three corner
// waves, each evaluated at the point and weighted by its barycentric coordinate. One
// function for every consumer: the draw pass (per pixel), the wrinkle maps (per texel
// of UV space) and the displaced geometry (per fine vertex).
//
// The including shader defines the units WAVE_POSED_POINTS, WAVE_FIELDS, WAVE_PHASE,
// WAVE_TRIANGLES, WAVE_HEIGHT_PROFILE, WAVE_GRADIENT_PROFILE and WAVE_REST_POINTS
// (render/bindings.py: WAVE) and sets u_profile_samples; the variant with IRREGULAR
// defined (wrinkle:irregularity > 0) also sets u_irregularity and u_irregularity_scale.
#ifndef USDWRINKLE_WAVE_GLSL
#define USDWRINKLE_WAVE_GLSL

layout(binding = WAVE_POSED_POINTS) uniform sampler2D posed_points;  // local space
layout(binding = WAVE_FIELDS) uniform sampler2D fields;
layout(binding = WAVE_PHASE) uniform sampler2D phase;
layout(binding = WAVE_TRIANGLES) uniform highp isampler2D triangles;  // corners of each
// 1D tables stored as N x 1 2D textures (moderngl has no 1D textures); repeat, linear
layout(binding = WAVE_HEIGHT_PROFILE) uniform sampler2D u_height_profile;  // H, one period
layout(binding = WAVE_GRADIENT_PROFILE) uniform sampler2D u_gradient_profile;  // dH/dtheta
uniform float u_profile_samples;
#if defined IRREGULAR
layout(binding = WAVE_REST_POINTS) uniform sampler2D wave_rest_points;  // local space
// Irregular folds (wrinkle:irregularity; method/contract.py, docs/method.md): beta, the
// radians of the field N added to every corner's phase, and 1 / Lambda, its length scale
uniform float u_irregularity;
uniform float u_irregularity_scale;
#endif
// Wave systems per vertex: the program variant with TWO_SYSTEMS defined (wrinkle:biaxial,
// or a bake of it) loops over u_systems; the default variant is the paper's one system,
// compiled without the second system's code (the general loop costs draw time even with
// one system: render/shaders.py, Variants, has the measurement).
#if defined TWO_SYSTEMS
uniform int u_systems;
#define SYSTEMS u_systems
#define SYSTEMS_MAX 2
#else
#define SYSTEMS 1
#define SYSTEMS_MAX 1
#endif

float profile(sampler2D table, float theta) {
    // sample s sits at theta = 2 pi s / N; texel centres are at (s + 0.5) / N
    return texture(table, vec2(theta / TWO_PI + 0.5 / u_profile_samples, 0.5)).r;
}

vec3 normalize_or_zero(vec3 v) {
    float len = length(v);
    return len > 1e-30 ? v / len : vec3(0.0);
}

struct Wave {
    float height;     // h, along the coarse normal (scene units)
    vec3 gradient;    // dh/dx in the tangent plane of n (local space)
    float amplitude;  // the blended amplitude sum(b_c a_c), before the band limit, plus
                      // the size of the deepening's carried offset: a bound of |h|
};

// The gradient of barycentric weight c over triangle (p0, p1, p2): constant, pointing from
// the opposite edge towards corner c, 1 / (its distance) long.
vec3 weight_gradient(int c, vec3 p0, vec3 p1, vec3 p2) {
    vec3 normal = cross(p1 - p0, p2 - p0);
    float area2 = dot(normal, normal);
    if (area2 < 1e-30) return vec3(0.0);
    vec3 opposite = c == 0 ? p2 - p1 : (c == 1 ? p0 - p2 : p1 - p0);
    return cross(normal, opposite) / area2;
}

// The three corner waves of a triangle as the blend reads them, gathered once per
// triangle: wave[3 s + c] = (k, a) of corner c in system s, its sign aligned to corner
// 0's (a corner whose eigenvectors are swapped against corner 0's contributes its other
// system), phase[s][c] its phase, corner[c] the posed corner (local space). The draw pass
// gathers them in the vertex stage and hands them to its fragments as flat varyings.
#if defined TWO_SYSTEMS
#define WAVE_SLOTS 6
#else
#define WAVE_SLOTS 3
#endif
struct CornerWaves {
    vec4 wave[WAVE_SLOTS];
    vec3 phase[SYSTEMS_MAX];
    vec3 corner[3];
    // each corner's deepening (crush's FIELD_DEEPEN): x the offset along the normal, yzw
    // its gradient (method/deepen.py)
    vec4 deepen[3];
    // each corner's compression r along its wave (crush's FIELD_DIRECTION w): the rest
    // (material) wavelength is 2 pi / (|k| r), what the displaced mesh's band limit reads
    vec3 ratio[SYSTEMS_MAX];
#if defined IRREGULAR
    vec3 rest[3];  // the rest corners (local space), where the irregularity field lives
    // each corner wave's unit rest direction (crush's FIELD_DIRECTION xyz, along which
    // its k is the material wave), its sign flipped with the wave's
    vec3 u[WAVE_SLOTS];
#endif
};
#if defined TWO_SYSTEMS
#define NO_RATIOS vec3[2](vec3(1.0), vec3(1.0))
#else
#define NO_RATIOS vec3[1](vec3(1.0))
#endif

// the share of vertex i's first wave that the surface draws (crush: FIELD_NORMAL's w is
// 1 + it where the ring is usable; 0 where not, and no wave there)
float drawn_share(int i) {
    return clamp(fetch(fields, FIELD_NORMAL(i)).w - 1.0, 0.0, 1.0);
}

// the length pass's scale of vertex i's folds, both systems (1 until it runs; a bake's is
// in its amplitudes)
float length_kept(int i) {
    return fetch(fields, FIELD_LENGTH(i)).x;
}

CornerWaves corner_waves(int t) {
    CornerWaves cw;
    ivec3 corners = fetch(triangles, t).xyz;
    for (int c = 0; c < 3; ++c) {
        cw.corner[c] = fetch(posed_points, corners[c]).xyz;
        cw.deepen[c] = fetch(fields, FIELD_DEEPEN(corners[c]));
    }
#if defined IRREGULAR
    for (int c = 0; c < 3; ++c) cw.rest[c] = fetch(wave_rest_points, corners[c]).xyz;
#endif
    vec3 reference0 = fetch(fields, FIELD_WAVE(corners.x)).xyz;
#if defined TWO_SYSTEMS
    vec3 reference1 = fetch(fields, FIELD_WAVE_OF(corners.x, 1)).xyz;
    bool swapped[3] = bool[3](false, false, false);
    for (int c = 1; c < 3; ++c) {
        vec3 k0 = normalize_or_zero(fetch(fields, FIELD_WAVE_OF(corners[c], 0)).xyz);
        vec3 k1 = normalize_or_zero(fetch(fields, FIELD_WAVE_OF(corners[c], 1)).xyz);
        vec3 r0 = normalize_or_zero(reference0);
        vec3 r1 = normalize_or_zero(reference1);
        swapped[c] = abs(dot(r0, k1)) + abs(dot(r1, k0)) > abs(dot(r0, k0)) + abs(dot(r1, k1));
    }
#endif
    for (int s = 0; s < SYSTEMS_MAX; ++s) {
        cw.phase[s] = vec3(0.0);
        cw.ratio[s] = vec3(1.0);
#if defined TWO_SYSTEMS
        vec3 k0 = s == 0 ? reference0 : reference1;
#else
        vec3 k0 = reference0;
#endif
        for (int c = 0; c < 3; ++c) {
            int i = corners[c];
#if defined TWO_SYSTEMS
            int system = swapped[c] ? 1 - s : s;
            vec4 wave = s < SYSTEMS ? fetch(fields, FIELD_WAVE_OF(i, system)) : vec4(0.0);
            if (system == 0) wave.w *= drawn_share(i);
            wave.w *= length_kept(i);
            float phi = fetch(phase, i)[system];
            vec4 direction = fetch(fields, FIELD_TEXELS * i + (system == 0
                ? FIELD_DIRECTION_TEXEL : FIELD_DIRECTION2_TEXEL));
            cw.ratio[s][c] = direction.w;
#else
            vec4 wave = fetch(fields, FIELD_WAVE(i));
            wave.w *= drawn_share(i) * length_kept(i);
            float phi = fetch(phase, i).x;
            vec4 direction = fetch(fields, FIELD_DIRECTION(i));
            cw.ratio[s][c] = direction.w;
#endif
#if defined IRREGULAR
            cw.u[3 * s + c] = normalize_or_zero(direction.xyz);
#endif
            if (c > 0 && dot(wave.xyz, k0) < 0.0) {
                wave.xyz = -wave.xyz;
                phi = -phi;
#if defined IRREGULAR
                cw.u[3 * s + c] = -cw.u[3 * s + c];
#endif
            }
            cw.wave[3 * s + c] = wave;
            cw.phase[s][c] = phi;
        }
    }
    return cw;
}

// The blend at local-space point p of a triangle with corner waves cw, barycentric
// weights bary, interpolated coarse unit normal n. The surface P + h n has the normal
// normalize(n - gradient). The gradient is the paper's sum(b_c a_c H'(theta_c) k_c) in
// the tangent plane of n, which shading uses. With exact_gradient it is the true 3D
// gradient of h over the flat coarse triangle instead: the blend weights' own slope
// sum(a_c H(theta_c) grad b_c) added, and not projected (displaced geometry
// differentiates its surface with it).
//
// Band limit: a corner wave shorter than what the consumer can carry fades towards the
// mean surface (amplitude to 0) instead of aliasing (docs/method.md: band limit).
// - min_wavelength (rest space; 0: none): displaced geometry passes 2 mean rest edges of
//   its fine mesh. The fine vertices ride with the cloth, so they sample a wave along the
//   material, and what they can carry is the rest wavelength 2 pi / (|k| r) (r: the
//   corner's compression along k): the factor is smoothstep(min_wavelength,
//   1.5 min_wavelength, 2 pi / (|k| r)).
// - footprint: the local-space steps of one pixel (or texel) across and down the image,
//   dFdx and dFdy of the position (zero vectors: none). The wave advances |k . step|
//   radians a pixel; fewer than 2 pixels a wavelength alias, so the factor is
//   smoothstep(2, 3, 2 pi / max |k . step|): only the wave's own direction counts, and a
//   grazing view does not fade waves that run across it.
struct Footprint {
    vec3 dx;
    vec3 dy;
    float min_wavelength;
};

// the radians of phase wave vector k advances over one step of the footprint, the
// larger of its two steps
float phase_step(vec3 k, Footprint footprint) {
    return max(abs(dot(k, footprint.dx)), abs(dot(k, footprint.dy)));
}

float band_limit(vec3 k, float ratio, Footprint footprint) {
    float factor = 1.0;
    if (footprint.min_wavelength > 0.0) {
        float lambda = TWO_PI / max(length(k) * ratio, 1e-30);
        factor = smoothstep(footprint.min_wavelength, 1.5 * footprint.min_wavelength, lambda);
    }
    float step = phase_step(k, footprint);
    if (step > 0.0) factor *= smoothstep(2.0, 3.0, TWO_PI / step);
    return factor;
}

// barycentric weights as the blend uses them: interpolation on slivers can leave [0, 1];
// renormalised weights keep |h| <= max a
vec3 blend_weights(vec3 bary) {
    bary = clamp(bary, 0.0, 1.0);
    return bary / max(bary.x + bary.y + bary.z, 1e-20);
}

#if defined IRREGULAR
// The irregularity fields at the point of weights bary (docs/method.md, "Irregular
// folds"): three fields N_i over the rest surface at X = sum b_c R_c (terms j of field
// j / IRREGULARITY_TERMS_PER_FIELD), each with its gradient over the posed triangle (X is
// affine in the posed point: grad_p N = sum_c (R_c . grad_X N) grad b_c); and per term its
// posed wave vector q_j and sin(phi_j), from which the exact gradient takes the fields'
// second derivatives (grad_p grad_p N_i = -c sum_j sin(phi_j) q_j q_j^T). A system's
// phases shift by beta u . N (system_shift).
struct Irregular {
    float field[IRREGULARITY_FIELDS];
    vec3 gradient[IRREGULARITY_FIELDS];
    vec3 q[IRREGULARITY_COUNT];
    float s[IRREGULARITY_COUNT];
    vec3 db[3];  // the gradients of the weights over the posed triangle
};
const float IRREGULARITY_NORM = sqrt(2.0 / float(IRREGULARITY_TERMS_PER_FIELD));

Irregular irregular_field(CornerWaves cw, vec3 bary) {
    Irregular field;
    for (int i = 0; i < IRREGULARITY_FIELDS; ++i) {
        field.field[i] = 0.0;
        field.gradient[i] = vec3(0.0);
    }
    vec3 X = bary.x * cw.rest[0] + bary.y * cw.rest[1] + bary.z * cw.rest[2];
    for (int c = 0; c < 3; ++c) {
        field.db[c] = weight_gradient(c, cw.corner[0], cw.corner[1], cw.corner[2]);
    }
    vec4 terms[IRREGULARITY_COUNT] = IRREGULARITY_TERMS;
    for (int j = 0; j < IRREGULARITY_COUNT; ++j) {
        int i = j / IRREGULARITY_TERMS_PER_FIELD;
        vec3 omega = terms[j].xyz * u_irregularity_scale;  // rest space, radians a unit
        float phi = dot(omega, X) + terms[j].w;
        // posed: the rest corners' phases differ by omega . (R_c - R_0)
        vec3 q = dot(omega, cw.rest[1] - cw.rest[0]) * field.db[1]
               + dot(omega, cw.rest[2] - cw.rest[0]) * field.db[2];
        field.q[j] = q;
        field.s[j] = sin(phi);
        field.field[i] += IRREGULARITY_NORM * field.s[j];
        field.gradient[i] += IRREGULARITY_NORM * cos(phi) * q;
    }
    return field;
}

// One wave system's shift of the phase at the point, the same for its three corners:
// m = beta u . N, u = v / |v| the direction of v = sum_c b_c a_c u_c (u_c: corner c's
// rest direction, the crush pass's per vertex, sign-aligned as the corners are:
// CornerWaves.u). A wave's sign flips u with its phase, so (k, phi) and (-k, -phi) draw
// the same folds. Per vertex, u_c is the same in every triangle around the vertex, so
// the shift is continuous across the coarse edges; taken through each triangle's own
// map (until 2026-12-05) it jumped across those between triangles crushed unlike, and
// the bent 10 cm sleeve drew 1.105 of its rest area at irregularity 0.3 (docs/physics.md,
// "Irregular folds against the referee"). Its posed gradient:
// grad m = beta (sum_i u_i grad N_i + (grad u)^T N), grad u = (I - u u^T) V / |v|,
// V = sum_c a_c u_c grad b_c^T.
struct Shift {
    float m;
    vec3 gradient;
    vec3 u;
    mat3 V;
    float rho;  // |v|; 0: no shift (no wave, or directions that cancel)
};

Shift system_shift(CornerWaves cw, Irregular field, vec3 bary, int s, float beta) {
    Shift shift = Shift(0.0, vec3(0.0), vec3(0.0), mat3(0.0), 0.0);
    vec3 v = vec3(0.0);
    float total = 0.0;
    for (int c = 0; c < 3; ++c) {
        vec4 wave = cw.wave[3 * s + c];
        vec3 u_c = wave.w * cw.u[3 * s + c];
        v += bary[c] * u_c;
        shift.V += outerProduct(u_c, field.db[c]);
        total += bary[c] * wave.w;
    }
    float rho = length(v);
    if (!(rho > 1e-6 * total) || total <= 0.0) return shift;
    shift.rho = rho;
    shift.u = v / rho;
    vec3 N = vec3(field.field[0], field.field[1], field.field[2]);
    shift.m = beta * dot(shift.u, N);
    shift.gradient = beta * (shift.u.x * field.gradient[0] + shift.u.y * field.gradient[1]
                             + shift.u.z * field.gradient[2]
                             + transpose(shift.V) * (N - shift.u * dot(shift.u, N)) / rho);
    return shift;
}

// the shift's second derivatives applied to a vector: (grad grad m) w, for the exact
// gradient of the amplitude factor |k| / |k + grad m|
vec3 shift_hessian(Shift shift, Irregular field, float beta, vec3 w) {
    if (shift.rho <= 0.0) return vec3(0.0);
    vec3 u = shift.u;
    vec3 N = vec3(field.field[0], field.field[1], field.field[2]);
    vec3 out_ = vec3(0.0);
    // sum_i u_i H_i w, H_i = -c sum_j sin(phi_j) q_j q_j^T over field i's terms
    for (int j = 0; j < IRREGULARITY_COUNT; ++j) {
        out_ -= IRREGULARITY_NORM * u[j / IRREGULARITY_TERMS_PER_FIELD] * field.s[j]
              * dot(field.q[j], w) * field.q[j];
    }
    vec3 du = (shift.V * w - u * dot(u, shift.V * w)) / shift.rho;  // (grad u) w
    vec3 jn = vec3(dot(field.gradient[0], w), dot(field.gradient[1], w),
                   dot(field.gradient[2], w));                         // (grad N) w
    out_ += du.x * field.gradient[0] + du.y * field.gradient[1] + du.z * field.gradient[2];
    out_ += transpose(shift.V) * (jn - u * dot(u, jn)) / shift.rho;
    // N . u(p), N held: d/dw of V^T (N - u (u . N)) / rho
    float uN = dot(u, N);
    out_ += transpose(shift.V) * (-du * uN - u * dot(du, N)) / shift.rho
          - transpose(shift.V) * (N - u * uN) * dot(u, shift.V * w) / (shift.rho * shift.rho);
    return beta * out_;
}
#endif

Wave blend_corner_waves(CornerWaves cw, vec3 bary, vec3 p, vec3 n, bool exact_gradient,
                        Footprint footprint) {
    Wave w = Wave(0.0, vec3(0.0), 0.0);
    bary = blend_weights(bary);
    // the deepened pleats (method/deepen.py): each corner's offset carried to p along its
    // gradient, o_c + g_c.(p - P_c), blended by the weights, as the corner waves' phases
    // are (so the offset surface meets each corner's slope, with no kinks along the coarse
    // edges); its gradient the blended g_c, and with exact_gradient the weights' part too.
    // The amplitude, the bound of |h|, holds the offset's size
    if (cw.deepen[0] != vec4(0.0) || cw.deepen[1] != vec4(0.0) || cw.deepen[2] != vec4(0.0)) {
        for (int c = 0; c < 3; ++c) {
            float carried = cw.deepen[c].x + dot(cw.deepen[c].yzw, p - cw.corner[c]);
            w.height += bary[c] * carried;
            w.gradient += bary[c] * cw.deepen[c].yzw;
            if (exact_gradient) {
                w.gradient += carried * weight_gradient(c, cw.corner[0], cw.corner[1],
                                                        cw.corner[2]);
            }
        }
        w.amplitude = abs(w.height);
    }
#if defined IRREGULAR
    Irregular field = irregular_field(cw, bary);
    float beta = u_irregularity;
#endif
    for (int s = 0; s < SYSTEMS; ++s) {
        float height = 0.0;      // this system's blend, before its coherence
        vec3 gradient = vec3(0.0);
        float total = 0.0;       // sum b_c a_c
        vec2 phasor = vec2(0.0); // sum b_c a_c e^(i theta_c)
        vec3 d_total = vec3(0.0);  // their gradients (exact_gradient)
        vec3 d_cos = vec3(0.0);
        vec3 d_sin = vec3(0.0);
#if defined IRREGULAR
        Shift shift = system_shift(cw, field, bary, s, beta);
#endif
        for (int c = 0; c < 3; ++c) {
            vec4 wave = cw.wave[3 * s + c];
            vec3 k = wave.xyz;
            float b = bary[c];
            // the amplitude field (the AOV, the maps' mask) is the cloth's, before the
            // band limit: it says how wrinkled the cloth is, not what this pixel resolves
            // (irregular folds: with their factor |k| / |k'|, below)
#if !defined IRREGULAR
            w.amplitude += b * wave.w;
#endif
            float theta = cw.phase[s][c] + dot(k, p - cw.corner[c]);  // local space
#if defined IRREGULAR
            // irregular folds: every corner's phase moves by the system's shift m, so
            // the local wave is k + grad m; the amplitude by |k| / |k'| keeps the law's
            // slope
            float k_length = length(k);
            theta += shift.m;
            k += shift.gradient;
            float k_local = length(k);
            float f = k_length > 0.0
                ? clamp(k_length / max(k_local, 1e-30), IRREGULARITY_FACTOR_MIN,
                        IRREGULARITY_FACTOR_MAX)
                : 1.0;
            float a = wave.w * band_limit(k, cw.ratio[s][c], footprint);
            // the factor's gradient (exact_gradient): -|k| / |k'|^3 (grad_p k')^T k',
            // grad_p k' = grad_p grad_p m; none where the factor is clamped
            vec3 d_factor = vec3(0.0);
            if (exact_gradient && k_length > 0.0 && f > IRREGULARITY_FACTOR_MIN
                    && f < IRREGULARITY_FACTOR_MAX) {
                d_factor = -k_length / (k_local * k_local * k_local)
                         * shift_hessian(shift, field, beta, k);
            }
            vec3 d_a = a * d_factor;  // the gradient of a f
            a *= f;
            w.amplitude += b * wave.w * f;
#else
            float a = wave.w * band_limit(k, cw.ratio[s][c], footprint);
#endif
            if (a == 0.0) continue;  // no wave here: skip the profile lookups
            float h = profile(u_height_profile, theta);
            height += b * a * h;
            gradient += b * a * profile(u_gradient_profile, theta) * k;
            total += b * a;
            phasor += b * a * vec2(cos(theta), sin(theta));
            if (exact_gradient) {
                vec3 db = weight_gradient(c, cw.corner[0], cw.corner[1], cw.corner[2]);
                gradient += a * h * db;
                d_total += a * db;
                d_cos += a * (cos(theta) * db - b * sin(theta) * k);
                d_sin += a * (sin(theta) * db + b * cos(theta) * k);
#if defined IRREGULAR
                // and the amplitude's own gradient
                gradient += b * h * d_a;
                d_total += b * d_a;
                d_cos += b * cos(theta) * d_a;
                d_sin += b * sin(theta) * d_a;
#endif
            }
        }
        // coherence: corner waves that drift out of phase inside the triangle cancel in
        // the blend, which then draws less than the interpolated amplitude (and less
        // length than the law's). The blend is divided by its coherence |phasor| / total
        // (1 where the corners agree), at most 1 / BLEND_COHERENCE_FLOOR times, and held
        // within the interpolated amplitude total (as the blend alone is: a profile that
        // is not a cosine can pass it by a few percent), so |h| never exceeds the
        // largest corner amplitude. It depends only on the corners whose weight is not
        // zero, so it is continuous across the coarse edges.
        float magnitude = length(phasor);
        if (total > 0.0 && magnitude < total) {
            float keep = total / max(magnitude, BLEND_COHERENCE_FLOOR * total);
            if (abs(height) * keep >= total) {
                // the crest held at the interpolated amplitude
                gradient = exact_gradient ? sign(height) * d_total : vec3(0.0);
                height = sign(height) * total;
            } else {
                if (exact_gradient && magnitude > BLEND_COHERENCE_FLOOR * total) {
                    // keep = total / |phasor|: its gradient, so that h keep differentiates
                    vec3 d_magnitude = (phasor.x * d_cos + phasor.y * d_sin) / magnitude;
                    gradient = keep * gradient
                             + height * (d_total - keep * d_magnitude) / magnitude;
                } else {
                    gradient *= keep;
                }
                height *= keep;
            }
        }
        w.height += height;
        w.gradient += gradient;
    }
    if (!exact_gradient) {
        w.gradient -= dot(w.gradient, n) * n;  // keep the gradient in the tangent plane
    }
    return w;
}

// The blend at local-space point p of triangle t (corner_waves and blend_corner_waves).
Wave wave_blend(int t, vec3 bary, vec3 p, vec3 n, bool exact_gradient,
                Footprint footprint) {
    return blend_corner_waves(corner_waves(t), bary, p, n, exact_gradient, footprint);
}

// dP/ds and dP/dt of triangle t (posed, local space) for a table of texture coordinates
// per triangle corner ([3t + c]); false where the triangle's UVs are degenerate.
bool uv_derivatives(int t, sampler2D corner_uv, out vec3 dp_ds, out vec3 dp_dt) {
    ivec3 corners = fetch(triangles, t).xyz;
    vec3 p0 = fetch(posed_points, corners.x).xyz;
    vec3 e1 = fetch(posed_points, corners.y).xyz - p0;
    vec3 e2 = fetch(posed_points, corners.z).xyz - p0;
    vec2 s0 = fetch(corner_uv, 3 * t).xy;
    vec2 d1 = fetch(corner_uv, 3 * t + 1).xy - s0;
    vec2 d2 = fetch(corner_uv, 3 * t + 2).xy - s0;
    float det = d1.x * d2.y - d2.x * d1.y;
    if (abs(det) <= 1e-20) {
        dp_ds = dp_dt = vec3(0.0);
        return false;
    }
    dp_ds = (e1 * d2.y - e2 * d1.y) / det;
    dp_dt = (e2 * d1.x - e1 * d2.x) / det;
    return true;
}

// The tangent frame of triangle t for a texture-coordinate table: T along dP/ds and B
// along dP/dt (local space, from the posed corners), made orthonormal about the unit
// normal n (Gram-Schmidt), B's sign from the triangle's UV winding (a mirrored island
// flips it), as MikkTSpace does per vertex. A triangle with degenerate UVs gets an
// arbitrary frame about n. Columns: T, B, n.
mat3 tangent_frame(int t, sampler2D corner_uv, vec3 n) {
    vec3 dp_ds, dp_dt;
    bool usable = uv_derivatives(t, corner_uv, dp_ds, dp_dt);
    vec3 fallback = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    vec3 T = safe_normalize(dp_ds - dot(dp_ds, n) * n,
                            safe_normalize(fallback - dot(fallback, n) * n, fallback));
    vec3 B = cross(n, T);
    if (usable && dot(B, dp_dt) < 0.0) B = -B;
    return mat3(T, B, n);
}

#endif
