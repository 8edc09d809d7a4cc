#version 430
// Wrinkle maps: the wave blend rasterised in texture space (maps/raster.py). Each
// triangle is drawn at its texture coordinates (one UDIM tile at a time); every texel
// gets the wrinkle of the surface point it maps to, from the same wave_blend as the
// draw pass. One file, two stages: the loader defines VERTEX_SHADER or FRAGMENT_SHADER.
#include "include/common.glsl"
#include "include/wave.glsl"

layout(binding = MAPS_UV) uniform sampler2D corner_uv;   // [3t + c].xy, the baked UV set
layout(binding = MAPS_Q_WIDTH) uniform sampler2D q_width;  // .w: rest wavelength W
// the draw pass's shading normals (normals pass) and each corner's entry: the maps are
// relative to the normal every renderer shades with, which the bake layer authors
layout(binding = MAPS_SHADING_NORMALS) uniform sampler2D shading_normals;
layout(binding = MAPS_NORMAL_CORNERS) uniform isampler2D normal_corners;
uniform vec2 u_tile;  // the tile drawn: its lower-left corner in UV space
#if defined MIKKTSPACE
// MikkTSpace per triangle corner ([3t + c]): unit tangent, bitangent sign (maps/tangents.py)
layout(binding = MAPS_TANGENTS) uniform sampler2D corner_tangents;
// the normal a MikkTSpace renderer builds that frame about, per corner: the shading normal,
// or Blender's own smooth normal where the mesh authors none (maps/tangents.py)
layout(binding = MAPS_FRAME_NORMALS) uniform sampler2D corner_frame_normals;
#endif

#if defined VERTEX_SHADER

out vec3 v_local;
out vec3 v_normal_local;
out vec3 v_bary;
// L_max g W / 4: about the fold law's height where the cloth is crushed flat (the material
// wavelength coarsened to L_max W, the triangle's slope), over s
out float v_full;
#if defined MIKKTSPACE
out vec4 v_tangent;
out vec3 v_frame_normal;
#endif

void main() {
    int corner = gl_VertexID;
    DrawCorner dc = draw_corner(triangles, corner);
    int t = dc.t, c = dc.c, i = dc.i;
    v_local = fetch(posed_points, i).xyz;             // posed, local space
    vec4 shading = fetch(shading_normals, fetch(normal_corners, corner).x);
    v_normal_local = shading.w > 0.0 ? shading.xyz : fetch(fields, FIELD_NORMAL(i)).xyz;
    v_bary = vec3(c == 0, c == 1, c == 2);
    v_full = COARSENING_MAX * fetch(q_width, i).w / 4.0;
#if defined MIKKTSPACE
    v_tangent = fetch(corner_tangents, corner);
    v_frame_normal = fetch(corner_frame_normals, corner).xyz;
#endif
    vec2 uv = fetch(corner_uv, corner).xy - u_tile;   // [0, 1] inside the tile
    gl_Position = vec4(uv * 2.0 - 1.0, 0.0, 1.0);     // row 0 of the target is t = 0
}

#elif defined FRAGMENT_SHADER

in vec3 v_local;
in vec3 v_normal_local;
in vec3 v_bary;
in float v_full;
#if defined MIKKTSPACE
in vec4 v_tangent;
in vec3 v_frame_normal;
#endif

uniform float u_amplitude_scale;  // s
uniform int u_count;              // 1: count the triangles over each texel (overlaps)

layout(location = 0) out vec4 out_normal;   // xyz: tangent-space unit normal; w: coverage
layout(location = 1) out vec4 out_wrinkle;  // x: height h; y: a / (s g W / 4); w: coverage
#if defined PARALLAX
// the texture deformation's inputs, local (object) space: the bent unit normal n', and h
// times the rows of inverse(gram) [dP/ds; dP/dt] of the texture's st (draw.glsl's
// v_st_from_local): a renderer's st offset is (hS.x', hT.x') with x' = v/(v.n') - n'
layout(location = 2) out vec4 out_bent;     // xyz: n'; w: coverage
layout(location = 3) out vec4 out_hs;       // xyz: h S; w: coverage
layout(location = 4) out vec4 out_ht;       // xyz: h T; w: coverage
#endif

void main() {
    if (u_count != 0) {  // additive blending sums these
        out_normal = vec4(1.0);
        out_wrinkle = vec4(1.0);
#if defined PARALLAX
        out_bent = out_hs = out_ht = vec4(1.0);
#endif
        return;
    }
    int t = gl_PrimitiveID;
    vec3 n = safe_normalize(v_normal_local, vec3(0.0, 0.0, 1.0));
    // band limit: no wave shorter than 2 texels along it
    Wave wave = wave_blend(t, v_bary, v_local, n, false,
                           Footprint(dFdx(v_local), dFdy(v_local), 0.0));
    vec3 shading = safe_normalize(n - wave.gradient, n);
    mat3 frame = tangent_frame(t, corner_uv, n);   // orthonormal: its transpose inverts it
    vec3 encoded = transpose(frame) * shading;
#if defined MIKKTSPACE
    // the frame a MikkTSpace renderer decodes in (Cycles' normal-map node): T and N
    // interpolated and not renormalised, B = sign * cross(N, T); the decoded normal is
    // normalize(x T + y B + z N), so the map holds the direction of that frame's inverse
    // applied to the shading normal. N is the renderer's own normal (v_frame_normal).
    vec3 T = v_tangent.xyz;
    vec3 B = (v_tangent.w < 0.0 ? -1.0 : 1.0) * cross(v_frame_normal, T);
    mat3 mikk = mat3(T, B, v_frame_normal);
    if (dot(T, T) > 1e-6 && abs(determinant(mikk)) > 1e-6) {
        encoded = safe_normalize(inverse(mikk) * shading, encoded);
    }
#endif
    float full = u_amplitude_scale * v_full;
    out_normal = vec4(encoded, 1.0);
    out_wrinkle = vec4(wave.height, full > 0.0 ? min(wave.amplitude / full, 1.0) : 0.0, 0.0,
                       1.0);
#if defined PARALLAX
    vec3 row_s = vec3(0.0), row_t = vec3(0.0);
    vec3 dp_ds, dp_dt;
    // the parallax maps are laid out in the texture's own st: their gradients are these
    if (uv_derivatives(t, corner_uv, dp_ds, dp_dt)) {
        mat2 gram = mat2(dot(dp_ds, dp_ds), dot(dp_ds, dp_dt),
                         dot(dp_ds, dp_dt), dot(dp_dt, dp_dt));
        if (abs(determinant(gram)) > 1e-30) {
            mat2 inv = inverse(gram);  // column-major: inv[col][row]
            row_s = inv[0][0] * dp_ds + inv[1][0] * dp_dt;
            row_t = inv[0][1] * dp_ds + inv[1][1] * dp_dt;
        }
    }
    out_bent = vec4(shading, 1.0);
    out_hs = vec4(wave.height * row_s, 1.0);
    out_ht = vec4(wave.height * row_t, 1.0);
#endif
}

#endif
