#version 430
// Render pass: per pixel, blend the three vertex waves of the triangle, bend the
// shading normal and deform the texture coordinates (Loviscach 2006, sec. 5).
// One file, two stages: the loader defines VERTEX_SHADER or FRAGMENT_SHADER.
#include "include/common.glsl"
#include "include/wave.glsl"

// the shading normals of this frame (normals pass) and each triangle corner's entry
layout(binding = DRAW_SHADING_NORMALS) uniform sampler2D shading_normals;
layout(binding = DRAW_NORMAL_CORNERS) uniform isampler2D normal_corners;

// Texture coordinates per triangle corner: [3t + c].xy, of the diffuse texture and, in
// the NORMAL_MAP variant (a mesh with a UsdPreviewSurface normal map), of the normal map
// (the same primvar, or each its own)
layout(binding = DRAW_CORNER_ST) uniform sampler2D corner_st;
#if defined NORMAL_MAP
layout(binding = DRAW_NORMAL_ST) uniform sampler2D normal_st;
#endif
#if defined VERTEX_COLOR
// colours per triangle corner ([3t + c].rgb, linear) that multiply the diffuse colour: a
// per-vertex displayColor, or the primvar a UsdPrimvarReader_float3 feeds diffuseColor
layout(binding = DRAW_CORNER_COLORS) uniform sampler2D corner_colors;
#endif

uniform mat4 u_local_to_world;   // USD row-vector matrix: GLSL sees its transpose
uniform mat4 u_world_to_clip;    // view * projection, same convention
uniform mat4 u_world_to_eye;     // view
uniform mat3 u_normal_to_world;  // inverse transpose of local_to_world's 3x3 (column-vector)
uniform vec3 u_eye_local;        // camera position in the mesh's local space
uniform vec3 u_eye_world;        // camera position in world space
uniform int u_wrinkles;          // 0: same shading, no wrinkles

// The fragment runs once per pixel, its varyings at the centroid: under multisampling,
// inside the covered part of the pixel, so that barycentrics never extrapolate past an
// edge. SHADE_SAMPLES (the default; off with render --no-shade-samples or --samples 1):
// where the folds turn the shading normal within the pixel (turn_across_pixel above
// u_sample_turn), each covered multisample is shaded again at its own position
// (interpolateAtSample) and the fragment writes their average, so the pixel averages what
// its samples see, as a texture's filtering averages a map over the pixel, never past a
// triangle's edge. The resolve then gives what shading every sample would (it averages
// the samples linearly), for the shading of wrinkled pixels alone: the texture is read
// once per pixel, filtered over its footprint as Storm reads it. gl_SampleMaskIn is the
// triangle's coverage before the depth test, so where a nearer surface hides part of the
// pixel the average also holds the hidden samples' shading (written only to the visible
// ones); shading every sample would leave them out. Until 2026-11-27 the
// varyings were interpolated per sample and every sample of every pixel was shaded:
// CesiumMan's 24 frames at 960x540 to PNG took 1.29x as long (3.91 s against 3.03 s,
// whole process, medians of seven alternating pairs on 2 cores).
#define INTERPOLATED centroid

#if defined VERTEX_SHADER

INTERPOLATED out vec3 v_local;
out vec3 v_local_footprint;  // the same, not centroid: derivatives of centroid are skewed
INTERPOLATED out vec3 v_world;
INTERPOLATED out vec3 v_normal_local;
INTERPOLATED out vec3 v_bary;
INTERPOLATED out vec2 v_st;
#if defined NORMAL_MAP
INTERPOLATED out vec2 v_normal_st;
#endif
#if defined VERTEX_COLOR
INTERPOLATED out vec3 v_color;
#endif
// per triangle, the same at its three corners (the draw is not indexed): the corner
// waves (wave.glsl: CornerWaves), gathered here once instead of in every fragment
flat out vec4 v_wave[WAVE_SLOTS];
flat out vec3 v_phase[SYSTEMS_MAX];
flat out vec3 v_corner[3];
flat out vec4 v_deepen[3];
#if defined IRREGULAR
flat out vec3 v_rest[3];
flat out vec3 v_u[WAVE_SLOTS];
#endif
#if defined TEXTURED
// the texture deformation's map from a local-space offset to an st offset: the rows of
// inverse(gram) [dP/ds; dP/dt] (zero where the triangle's st are degenerate)
flat out vec3 v_st_from_local[2];
#endif

void main() {
    // Not indexed: 3 corners per triangle, each run on its own, because the barycentric
    // weights and face-varying st are per corner. (Indexed, with the weights computed per
    // fragment from the three corners, was no faster on llvmpipe: docs/benchmarks.md.)
    int corner = gl_VertexID;
    DrawCorner dc = draw_corner(triangles, corner);
    int t = dc.t, c = dc.c, i = dc.i;
    vec3 p = fetch(posed_points, i).xyz;  // posed, local space
    v_local = p;
    v_local_footprint = p;
    vec4 world = u_local_to_world * vec4(p, 1.0);  // local -> world
    v_world = world.xyz / world.w;
    // the shading normal; the wave physics' own where it degenerates
    vec4 shading = fetch(shading_normals, fetch(normal_corners, corner).x);
    v_normal_local = shading.w > 0.0 ? shading.xyz : fetch(fields, FIELD_NORMAL(i)).xyz;
    v_bary = vec3(c == 0, c == 1, c == 2);
    v_st = fetch(corner_st, corner).xy;
#if defined VERTEX_COLOR
    v_color = fetch(corner_colors, corner).rgb;
#endif
#if defined NORMAL_MAP
    v_normal_st = fetch(normal_st, corner).xy;
#endif
    CornerWaves cw;
    for (int k = 0; k < WAVE_SLOTS; ++k) cw.wave[k] = vec4(0.0);
    for (int k = 0; k < SYSTEMS_MAX; ++k) cw.phase[k] = vec3(0.0);
    for (int k = 0; k < 3; ++k) cw.corner[k] = vec3(0.0);
    for (int k = 0; k < 3; ++k) cw.deepen[k] = vec4(0.0);
    if (u_wrinkles != 0) cw = corner_waves(t);
    v_wave = cw.wave;
    v_phase = cw.phase;
    v_corner = cw.corner;
    v_deepen = cw.deepen;
#if defined IRREGULAR
    for (int k = 0; k < 3; ++k) v_rest[k] = u_wrinkles != 0 ? cw.rest[k] : vec3(0.0);
    for (int k = 0; k < WAVE_SLOTS; ++k) v_u[k] = u_wrinkles != 0 ? cw.u[k] : vec3(0.0);
#endif
#if defined TEXTURED
    v_st_from_local[0] = v_st_from_local[1] = vec3(0.0);
    vec3 dp_du, dp_dv;  // dP/dUV, local space
    if (u_wrinkles != 0 && uv_derivatives(t, corner_st, dp_du, dp_dv)) {
        mat2 gram = mat2(dot(dp_du, dp_du), dot(dp_du, dp_dv),
                         dot(dp_du, dp_dv), dot(dp_dv, dp_dv));
        if (abs(determinant(gram)) > 1e-30) {
            mat2 inv = inverse(gram);  // column-major: inv[col][row]
            v_st_from_local[0] = inv[0][0] * dp_du + inv[1][0] * dp_dv;
            v_st_from_local[1] = inv[0][1] * dp_du + inv[1][1] * dp_dv;
        }
    }
#endif
    gl_Position = u_world_to_clip * world;         // world -> clip
}

#elif defined FRAGMENT_SHADER

INTERPOLATED in vec3 v_local;
in vec3 v_local_footprint;
INTERPOLATED in vec3 v_world;
INTERPOLATED in vec3 v_normal_local;
INTERPOLATED in vec3 v_bary;
INTERPOLATED in vec2 v_st;
#if defined NORMAL_MAP
INTERPOLATED in vec2 v_normal_st;
#endif
#if defined VERTEX_COLOR
INTERPOLATED in vec3 v_color;
#endif
flat in vec4 v_wave[WAVE_SLOTS];
flat in vec3 v_phase[SYSTEMS_MAX];
flat in vec3 v_corner[3];
flat in vec4 v_deepen[3];
#if defined IRREGULAR
flat in vec3 v_rest[3];
flat in vec3 v_u[WAVE_SLOTS];
#define DRAWN_CORNER_WAVES CornerWaves(v_wave, v_phase, v_corner, v_deepen, NO_RATIOS, v_rest, v_u)
#else
#define DRAWN_CORNER_WAVES CornerWaves(v_wave, v_phase, v_corner, v_deepen, NO_RATIOS)
#endif
#if defined TEXTURED
flat in vec3 v_st_from_local[2];
#endif

layout(location = 0) out vec4 out_color;    // linear RGB, alpha
layout(location = 1) out vec4 out_wrinkle;  // x: height h, y: amplitude, z: eye depth Z
layout(location = 2) out vec4 out_normal;   // world-space shading normal

#include "include/surface.glsl"

uniform int u_double_sided;            // back faces shaded with the flipped normal
// switches (render/passes/draw.py): FALLBACK_SURFACE (no UsdPreviewSurface: Storm's
// fallback surface), TEXTURED (a diffuse texture), DOME (a dome light), MASKED (an
// opacityThreshold above 0); each off compiles
// out, which llvmpipe's masked execution of uniform branches would otherwise pay for
uniform vec3 u_diffuse_color;          // UsdPreviewSurface diffuseColor, or displayColor
uniform vec3 u_emissive_color;
uniform int u_use_specular_workflow;
uniform vec3 u_specular_color;
uniform float u_metallic;
uniform float u_roughness;
uniform float u_clearcoat;
uniform float u_clearcoat_roughness;
uniform float u_opacity;               // or displayOpacity
uniform float u_opacity_threshold;     // > 0: masked (cut out below it, else opaque)
uniform float u_ior;
uniform float u_occlusion;
layout(binding = DRAW_DIFFUSE_TEXTURE) uniform sampler2D u_diffuse_texture;
uniform vec4 u_texture_scale;
uniform vec4 u_texture_bias;
#if defined NORMAL_MAP
// UsdPreviewSurface inputs:normal from a UsdUVTexture: a tangent-space normal map, tiles
// of a UDIM set in the layers of an array (u_udim_layer[10 v + u]: the layer, or -1)
layout(binding = DRAW_NORMAL_TEXTURE) uniform sampler2DArray u_normal_map;
uniform int u_udim_layer[UDIM_TILES];
uniform vec4 u_normal_scale;
uniform vec4 u_normal_bias;
#endif


// Anisotropic filtering as GPUs do it, written out: the footprint of the pixel in the
// texture (st's screen derivatives, in texels of level 0) is sampled by n trilinear probes
// spaced along its longer axis, n = ceil(longer / shorter) but at most TEXTURE_ANISOTROPY,
// each at the level where the longer axis over n, or the shorter axis if that is longer,
// is one texel. Hydra's GL samplers ask the
// driver for this with 16 probes (hgiGL/sampler.cpp); drivers differ in the details, and
// Mesa's llvmpipe walks the whole elliptical footprint at the shorter axis's level, which
// at a grazing triangle is millions of texels (CesiumMan at 960x540, frame 7: one draw
// took 14 s). Written out, every machine filters alike and in bounded time.
// ``size``: level 0 in texels; ``dx``, ``dy``: st's derivatives; ``lod``, ``step`` and
// the returned n: the probes at st + step * ((i + 0.5) / n - 0.5), i < n, at level lod.
int anisotropic_probes(vec2 size, vec2 dx, vec2 dy, out float lod, out vec2 step) {
    vec2 tx = dx * size, ty = dy * size;
    float lx = length(tx), ly = length(ty);
    float longer = max(lx, ly), shorter = min(lx, ly);
    float n = clamp(ceil(longer / max(shorter, 1e-20)), 1.0, TEXTURE_ANISOTROPY);
    if (!(longer > 0.0) || isinf(longer)) {  // constant, or not finite: one probe
        n = 1.0;
    }
    lod = log2(max(max(longer / n, shorter), 1e-20));  // the shorter axis never aliases
    step = lx >= ly ? dx : dy;
    return int(n);
}

// the texture at st, filtered over the footprint dx, dy (st's screen derivatives)
vec4 texture_anisotropic(sampler2D tex, vec2 st, vec2 dx, vec2 dy) {
    float lod;
    vec2 step;
    int n = anisotropic_probes(vec2(textureSize(tex, 0)), dx, dy, lod, step);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < n; ++i) {
        sum += textureLod(tex, st + step * ((float(i) + 0.5) / float(n) - 0.5), lod);
    }
    return sum / float(n);
}

#if defined NORMAL_MAP
// The tangent-space normal of the normal map at st, or nothing (false) outside its tiles
bool normal_map(vec2 st, out vec3 n_tangent) {
    vec2 tile = floor(st);
    int layer = 0;
    if (u_udim_layer[0] != UDIM_REPEAT) {  // one texture that repeats, not a UDIM set
        bool inside = tile.x >= 0.0 && tile.x < 10.0 && tile.y >= 0.0 && tile.y < 10.0;
        layer = inside ? u_udim_layer[int(tile.y) * 10 + int(tile.x)] : -1;
        if (layer < 0) return false;
    }
    float lod;
    vec2 step;  // from the continuous st: a tile's border is no edge of the footprint
    int n = anisotropic_probes(vec2(textureSize(u_normal_map, 0).xy), dFdx(st), dFdy(st),
                               lod, step);
    vec4 texel = vec4(0.0);
    for (int i = 0; i < n; ++i) {
        vec2 probe = st - tile + step * ((float(i) + 0.5) / float(n) - 0.5);
        texel += textureLod(u_normal_map, vec3(probe, float(layer)), lod);
    }
    texel /= float(n);
    n_tangent = (texel * u_normal_scale + u_normal_bias).xyz;
    return true;
}
#endif

// the coarse unit normal of a fragment, flipped on a double-sided mesh's back faces
vec3 coarse_normal(vec3 interpolated) {
    vec3 n = safe_normalize(interpolated, vec3(0.0, 0.0, 1.0));
    // a double-sided mesh's back faces are shaded about the flipped normal, which the
    // wrinkles then bend and a normal map's frame is built about, as Storm does: the
    // tangent frame keeps T and B and turns N (previewSurface's ComputeTBNMatrix), so a
    // normal map's tilt reads the same from both sides. A single-sided mesh's back faces
    // keep it (unlit, as Storm draws them).
    if (!gl_FrontFacing && u_double_sided != 0) n = -n;
    return n;
}

// What the wrinkles do at one point of the pixel: the wave's height and amplitude, the
// normal they bend (local space; composed with the normal map's tangent normal n_tangent
// where ``mapped``), which moves the texture, and the shading normal: that one turned to
// the horizon.
struct Bent {
    float height;
    float amplitude;
    vec3 shading_local;
    vec3 bent_local;
};

Bent bend(int t, CornerWaves cw, vec3 n, vec3 bary, vec3 local, Footprint pixel,
          bool mapped, vec3 n_tangent) {
    Wave wave = Wave(0.0, vec3(0.0), 0.0);
    if (u_wrinkles != 0) {
        wave = blend_corner_waves(cw, bary, local, n, false, pixel);
    }
    vec3 bent_local = safe_normalize(n - wave.gradient, n);
#if defined NORMAL_MAP
    if (mapped) {
        // the map's frame about the (wrinkled) shading normal: maps and wrinkles compose
        mat3 frame = tangent_frame(t, normal_st, bent_local);
        bent_local = safe_normalize(frame * n_tangent, bent_local);
    }
#endif
    // the horizon: a seen point faces the eye, so a normal the folds bent away from it is
    // shaded turned back until its cosine with v is HORIZON_COSINE (contract.py), or the
    // coarse normal's where that is less; a normal the folds did not bend is left as it
    // is, and the texture moves with the bent normal as it was
    vec3 shading_local = bent_local;
    if (u_wrinkles != 0 && wave.amplitude > 0.0) {
        vec3 v = safe_normalize(u_eye_local - local, n);
        float least = min(HORIZON_COSINE, dot(v, n));
        float vn = dot(v, bent_local);
        if (vn < least) shading_local = safe_normalize(bent_local + (least - vn) * v, n);
    }
    return Bent(wave.height, wave.amplitude, shading_local, bent_local);
}

#if defined RELIEF
// Relief (render --relief; docs/method.md, "Relief"): the folds seen where the view ray
// meets them, not where it meets the coarse surface. The wrinkled surface is the coarse
// surface lifted by the blend's height h along the fragment's coarse normal n; the ray
// from the eye through the fragment's point p crosses height z at p + z s, s = v_t / v.n
// (v towards the eye; v.n taken at least RELIEF_MIN_COSINE, and the relief faded out from
// there to RELIEF_FADE, towards the silhouette, where the ray would run far). It is
// marched from the height bound down in steps that cannot pass a crossing (relief_step),
// and the first crossing refined by RELIEF_SECANT secant steps.
// Where the ray leaves the triangle, it walks on into the neighbour across the edge it
// crossed (triangle_neighbors), whose own corner waves give h there, as that triangle's
// fragments blend them: no seam along the coarse edges. A double-sided mesh's back face
// is lifted along its flipped normal, as bend() bends its normal (the folds stand towards
// the eye from either side, as a normal map's tilt does in Storm); a single-sided one's
// is not lifted.
layout(binding = DRAW_TRIANGLE_NEIGHBORS) uniform isampler2D triangle_neighbors;

// where the relief's walk stands: a triangle, its corner waves and the gradients of its
// barycentric weights (weight_gradient, one column per corner)
struct ReliefCursor {
    int t;
    CornerWaves cw;
    mat3 grads;
};

ReliefCursor relief_cursor(int t, CornerWaves cw) {
    return ReliefCursor(t, cw, mat3(weight_gradient(0, cw.corner[0], cw.corner[1], cw.corner[2]),
                                    weight_gradient(1, cw.corner[0], cw.corner[1], cw.corner[2]),
                                    weight_gradient(2, cw.corner[0], cw.corner[1], cw.corner[2])));
}

// the largest |h| the blend can reach over the fragment's triangle: each system's largest
// corner amplitude (times the irregular folds' largest factor), and the largest offset
// carried across the triangle; with RELIEF_BOUND_MARGIN for its neighbours' folds
float relief_bound() {
    float bound = 0.0;
    for (int s = 0; s < SYSTEMS; ++s) {
        bound += max(max(v_wave[3 * s].w, v_wave[3 * s + 1].w), v_wave[3 * s + 2].w);
    }
#if defined IRREGULAR
    bound *= IRREGULARITY_FACTOR_MAX;
#endif
    float reach = max(max(length(v_corner[1] - v_corner[0]), length(v_corner[2] - v_corner[1])),
                      length(v_corner[0] - v_corner[2]));
    float offset = 0.0;
    for (int c = 0; c < 3; ++c) {
        offset = max(offset, abs(v_deepen[c].x) + length(v_deepen[c].yzw) * reach);
    }
    return RELIEF_BOUND_MARGIN * (bound + offset);
}

// max |H'| of the height profile (render/resources.py)
uniform float u_profile_steepest;

// a bound of |grad h| over the fragment's triangle: each system's largest corner slope
// a |k| max |H'| (times the irregular folds' largest factors), and the largest offset
// gradient; with RELIEF_BOUND_MARGIN for its neighbours' folds
float relief_slope() {
    float slope = 0.0;
    for (int s = 0; s < SYSTEMS; ++s) {
        float most = 0.0;
        for (int c = 0; c < 3; ++c) {
            most = max(most, v_wave[3 * s + c].w * length(v_wave[3 * s + c].xyz));
        }
        slope += most * u_profile_steepest;
    }
#if defined IRREGULAR
    slope *= IRREGULARITY_FACTOR_MAX * IRREGULARITY_FACTOR_MAX;
#endif
    float offset = 0.0;
    for (int c = 0; c < 3; ++c) offset = max(offset, length(v_deepen[c].yzw));
    return RELIEF_BOUND_MARGIN * (slope + offset);
}

// the barycentric weights of point q (projected onto the triangle's plane): b_c is 0 on
// the edge opposite c and grows along weight_gradient(c)
vec3 relief_weights(ReliefCursor at, vec3 q) {
    return vec3(dot(q - at.cw.corner[1], at.grads[0]), dot(q - at.cw.corner[2], at.grads[1]),
                dot(q - at.cw.corner[0], at.grads[2]));
}

// the blend's height along n at q, walking the cursor
// into the triangle q lies over (at most RELIEF_HOPS edges; a border keeps the triangle,
// whose weights blend_weights then holds at the edge); ``bary``: q's weights there
float relief_height(inout ReliefCursor at, vec3 q, vec3 n, Footprint pixel, out vec3 bary) {
    bary = relief_weights(at, q);
    for (int hop = 0; hop < RELIEF_HOPS; ++hop) {
        float least = min(bary.x, min(bary.y, bary.z));
        if (least >= 0.0) break;
        int c = bary.x == least ? 0 : (bary.y == least ? 1 : 2);
        int next = fetch(triangle_neighbors, at.t)[c];
        if (next < 0) break;
        at = relief_cursor(next, corner_waves(next));
        bary = relief_weights(at, q);
    }
    return blend_corner_waves(at.cw, bary, q, n, false, pixel).height;
}

// The step dp in the tangent plane from p to where the ray meets the folds; ``at``: the
// fragment's triangle, then the one the seen point lies over; ``bary``: the fragment's
// weights, then the seen point's. ``n``: the fragment's coarse normal (flipped on a
// double-sided mesh's back face: the folds stand along it, as its shading bends them)
//
// ``start``: the height the march starts from (at most the bound). With ``tolerance`` >=
// 0, ``safe`` is the lowest height the march passed with every ray within ``tolerance``
// of this one's f (f moves by at most the slope bound times the rays' distance) still
// above the folds down to it, and ``safe_at`` its cursor: a multisample's ray, within a
// pixel of this one, starts its own march there instead of at the bound.
vec3 relief_step(vec3 p, vec3 n, Footprint pixel, float start, float tolerance,
                 inout ReliefCursor at, inout vec3 bary, out float safe,
                 out ReliefCursor safe_at) {
    vec3 v = safe_normalize(u_eye_local - p, n);
    float bound = relief_bound();
    float vn = dot(v, n);
    safe = bound;
    safe_at = at;
    if (vn <= RELIEF_FADE || bound <= 0.0) return vec3(0.0);
    vec3 s = (v - vn * n) / max(vn, RELIEF_MIN_COSINE) * smoothstep(RELIEF_FADE,
                                                                    RELIEF_MIN_COSINE, vn);
    // f(z) = z - h(p + z s): >= 0 at the bound, <= 0 at -bound, and it falls at most
    // lipschitz per unit of z, so a step of f / lipschitz cannot pass a crossing (none is
    // shorter than 2 bound / RELIEF_MAX_STEPS: a crossing within that of the ray is
    // bracketed, not missed). The upper end keeps its cursor, so each refinement step
    // walks from the triangle it lies over
    float lipschitz = 1.0 + relief_slope() * length(s);
    float least = 2.0 * bound / RELIEF_MAX_STEPS;
    ReliefCursor above = at;
    vec3 b;
    float z0 = min(start, bound);
    float f0 = z0 - relief_height(above, p + z0 * s, n, pixel, b);
    safe = z0;
    safe_at = above;
    bool tracking = tolerance >= 0.0 && f0 > tolerance;
    float z1 = -bound, f1 = -1.0;
    if (f0 > 0.0) {
        for (int i = 0; i < int(RELIEF_MAX_STEPS); ++i) {
            float z = max(z0 - max(f0 / lipschitz, least), -bound);
            ReliefCursor next = above;
            float f = z - relief_height(next, p + z * s, n, pixel, b);
            if (f <= 0.0) {
                z1 = z;
                f1 = f;
                break;
            }
            // between the two samples f is at least (f0 + f - lipschitz dz) / 2
            if (tracking && 0.5 * (f0 + f - lipschitz * (z0 - z)) > tolerance
                    && f > tolerance) {
                safe = z;
                safe_at = next;
            } else {
                tracking = false;
            }
            above = next;
            z0 = z;
            f0 = f;
        }
        // secant steps inside the bracket [z1, z0]
        for (int i = 0; i < RELIEF_SECANT; ++i) {
            float z = f0 - f1 > 1e-30 ? z0 - f0 * (z0 - z1) / (f0 - f1) : z1;
            ReliefCursor next = above;
            float f = z - relief_height(next, p + z * s, n, pixel, b);
            if (f > 0.0) {
                above = next;
                z0 = z;
                f0 = f;
            } else {
                z1 = z;
                f1 = f;
            }
        }
    } else {
        z1 = z0;  // the folds stand above the bound here: seen where the march starts
        f0 = f1;
    }
    float z = f0 - f1 > 1e-30 ? z0 - f0 * (z0 - z1) / (f0 - f1) : z1;
    at = above;
    relief_height(at, p + z * s, n, pixel, bary);
    return z * s;
}
#endif

// the depth along the view of world point ``world`` (the Z AOV: eye space's -z)
float eye_depth(vec3 world) {
    return -(u_world_to_eye * vec4(world, 1.0)).z;
}

// The radiance leaving world point ``world`` whose shading normal is ``shading_local``,
// and that normal in world space (N)
vec3 shade(vec3 base, float opacity, vec3 world, vec3 shading_local, out vec3 N) {
    // local -> world shading normal (a double-sided mesh's back faces: flipped above)
    N = safe_normalize(u_normal_to_world * shading_local, vec3(0.0, 0.0, 1.0));
#if defined FALLBACK_SURFACE
    return fallback_surface(base, world, N);
#else
    vec3 V = safe_normalize(u_eye_world - world, N);
    PreviewSurface surface = PreviewSurface(
        base * opacity, u_emissive_color, u_use_specular_workflow != 0, u_specular_color,
        u_metallic, u_roughness, u_clearcoat, u_clearcoat_roughness, opacity, u_ior,
        u_occlusion);
    return preview_surface(surface, world, N, V);
#endif
}

#if defined SHADE_SAMPLES
// max |H''| of the height profile (radians^-2 of phase; render/resources.py), and the
// turn of the bent normal across a pixel above which the pixel shades its samples
uniform float u_profile_curvature;
uniform float u_sample_turn;

// How far the bent normal turns across one pixel, in radians, at most: per corner wave,
// its slope's change per radian of phase (a |k| max|H''|) times the phase it advances
// across the pixel (max |k . step|), blended by the barycentric weights
float turn_across_pixel(vec3 bary, Footprint pixel) {
    float turn = 0.0;
    bary = blend_weights(bary);
    for (int s = 0; s < SYSTEMS; ++s) {
        for (int c = 0; c < 3; ++c) {
            vec4 wave = v_wave[3 * s + c];
            float a = wave.w * band_limit(wave.xyz, 1.0, pixel);
            turn += bary[c] * a * length(wave.xyz) * phase_step(wave.xyz, pixel);
        }
    }
    return turn * u_profile_curvature;
}
#endif

void main() {
    int t = gl_PrimitiveID;
    // band limit: no wave shorter than 2 pixels along it
    Footprint pixel = Footprint(dFdx(v_local_footprint), dFdy(v_local_footprint), 0.0);
    vec3 n = coarse_normal(v_normal_local);
    bool mapped = false;
    vec3 n_tangent = vec3(0.0, 0.0, 1.0);
#if defined NORMAL_MAP
    mapped = normal_map(v_normal_st, n_tangent);  // filtered over the pixel's footprint
#endif
#if defined RELIEF
    // the folds where the view ray meets them (relief_step); the texture moves with the
    // seen point, and the material's own shift -n' h as in the texture deformation below
    ReliefCursor seen_at = relief_cursor(t, DRAWN_CORNER_WAVES);
    vec3 seen_bary = v_bary;
    // the multisamples' rays lie within half the pixel's diagonal of the centre's
    float within = 0.5 * (length(pixel.dx) + length(pixel.dy));
    float safe_height = 0.0;
    ReliefCursor safe_at = seen_at;
    vec3 seen = u_wrinkles != 0
        ? relief_step(v_local, n, pixel, 1e30, RELIEF_SAMPLE_REACH * relief_slope() * within,
                      seen_at, seen_bary, safe_height, safe_at)
        : vec3(0.0);
    Bent centre = bend(t, seen_at.cw, n, seen_bary, v_local + seen, pixel, mapped, n_tangent);
#else
    Bent centre = bend(t, DRAWN_CORNER_WAVES, n, v_bary, v_local, pixel, mapped, n_tangent);
#endif
    float h = centre.height;
    // texture deformation: the point seen through the wrinkle, dx = (v/(v.n') - n') h
    vec2 st = v_st;
#if defined TEXTURED
    if (u_wrinkles != 0 && h != 0.0) {
#if defined RELIEF
        vec3 dx = seen - centre.bent_local * h;
#else
        vec3 v = safe_normalize(u_eye_local - v_local, n);
        float vn = max(abs(dot(v, centre.bent_local)), 0.25);
        vec3 dx = (v / vn - centre.bent_local) * h;
#endif
        st += vec2(dot(v_st_from_local[0], dx), dot(v_st_from_local[1], dx));
    }
#endif

    vec3 base = u_diffuse_color;
#if defined VERTEX_COLOR
    base *= v_color;
#endif
#if defined TEXTURED
    vec2 st_dx = dFdx(st), st_dy = dFdy(st);
#if defined RELIEF
    // where the seen point jumps from one fold to the one behind it, st's derivatives
    // jump with it (in the 2 x 2 pixels a derivative spans): held within
    // RELIEF_FOOTPRINT times the coarse surface's, the pixel is not blurred to a block
    float coarse = max(length(dFdx(v_st)), length(dFdy(v_st)));
    float longest = max(length(st_dx), length(st_dy));
    if (longest > RELIEF_FOOTPRINT * coarse) {
        float keep = RELIEF_FOOTPRINT * coarse / longest;
        st_dx *= keep;
        st_dy *= keep;
    }
#endif
    vec4 texel = texture_anisotropic(u_diffuse_texture, st, st_dx, st_dy) * u_texture_scale
               + u_texture_bias;
    base *= texel.rgb;
#endif

    float opacity = u_opacity;
#if defined MASKED
    // opacityThreshold > 0: cut out, else opaque. Only this variant may discard: a
    // shader that can discard is depth-tested after it runs (llvmpipe shades every
    // hidden fragment then)
    if (opacity < u_opacity_threshold) discard;
    opacity = 1.0;
#endif
    vec3 N;
    vec3 radiance = shade(base, opacity, v_world, centre.shading_local, N);
    float amplitude = centre.amplitude;
    float depth = eye_depth(v_world);

#if defined SHADE_SAMPLES
    // Where the folds turn the normal within the pixel, every covered multisample is
    // shaded where it lies and the fragment writes their average: the resolve then
    // averages the pixel's area, as a texture's filtering averages a map. Elsewhere the
    // pixel is shaded once, at its centroid (the texture, filtered over the pixel, is
    // read once either way).
    if (u_wrinkles != 0 && turn_across_pixel(v_bary, pixel) > u_sample_turn) {
        vec3 sum_radiance = vec3(0.0), sum_normal = vec3(0.0);
        float sum_h = 0.0, sum_amplitude = 0.0, sum_depth = 0.0, count = 0.0;
        // s runs over every sample index below gl_NumSamples, not over the mask's set
        // bits: walked with findLSB (-1 once a lane's mask is empty), llvmpipe crashed
        // (a segmentation fault in 3 of 3 runs of tests/test_trust.py on two workers,
        // none since), as if its masked-off lanes read a sample position outside the
        // pattern
        int mask = gl_SampleMaskIn[0];
        for (int s = 0; s < gl_NumSamples; ++s) {
            if ((mask & (1 << s)) == 0) continue;
            vec3 world = interpolateAtSample(v_world, s);
            vec3 ns = coarse_normal(interpolateAtSample(v_normal_local, s));
            vec3 bs = interpolateAtSample(v_bary, s);
            vec3 ps = interpolateAtSample(v_local, s);
#if defined RELIEF
            // each sample marches its own ray: where a crest's outline crosses the pixel,
            // its samples see different folds (the centre's step for every sample, tried,
            // saw through the crests' outlines: on the analytic sheet at 55 degrees the
            // normals' 90th percentile against the displaced mesh's went 5.3 -> 7.8
            // degrees). It starts where the centre's march knew no ray within the pixel
            // meets the folds above (relief_step's ``safe``)
            ReliefCursor at = safe_at;
            float unused_height;
            ReliefCursor unused_at;
            ps += relief_step(ps, ns, pixel, safe_height, -1.0, at, bs, unused_height,
                              unused_at);
            Bent b = bend(t, at.cw, ns, bs, ps, pixel, mapped, n_tangent);
#else
            Bent b = bend(t, DRAWN_CORNER_WAVES, ns, bs, ps, pixel, mapped, n_tangent);
#endif
            vec3 Ns;
            sum_radiance += shade(base, opacity, world, b.shading_local, Ns);
            sum_normal += Ns;
            sum_h += b.height;
            sum_amplitude += b.amplitude;
            sum_depth += eye_depth(world);
            count += 1.0;
        }
        if (count > 0.0) {
            radiance = sum_radiance / count;
            N = sum_normal / count;  // unit normals averaged: the resolve renormalises
            h = sum_h / count;
            amplitude = sum_amplitude / count;
            depth = sum_depth / count;
        }
    }
#endif

    out_color = vec4(radiance, opacity);
    out_wrinkle = vec4(h, amplitude, depth, 1.0);
    out_normal = vec4(N, 1.0);
}

#endif
