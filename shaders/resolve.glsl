#version 430
// Resolve pass: the drawn attachments -> the pixels a reader asked for, in one dispatch.
//
// Per pixel it averages the multisamples (coverage: colour stays premultiplied by alpha,
// the other AOVs are divided by the coverage so that an edge pixel holds the average
// over the samples that hit a surface; normals are renormalised), and writes them to one
// storage buffer of 32-bit words, laid out as render/resolve.py's ImageLayout says:
//   OUTPUT_AOVS  every AOV as float, (height, width, channels) blocks (Framebuffer.read);
//   OUTPUT_EXR   one plane per EXR channel (R G B A wrinkle.height wrinkle.amplitude N.X N.Y
//                N.Z Z; those of the layout's AOVs), colour and normals as half float with
//                HALF_COLOR_NORMAL;
//   OUTPUT_8BIT  RGBA8 sRGB codes per pixel: straight alpha, or with OVER_BLACK the
//                premultiplied colour over black and alpha 255 (JPEG).
// An EXR invocation resolves two neighbouring pixels, so that a half plane's words hold
// whole pairs; the others one. Rows come out top-down already (the draw pass flips y in clip space).
// Every value written that is NaN or infinite (depth: NaN only) counts in u_bad.
#include "include/common.glsl"

#if SAMPLES > 1
#define ATTACHMENT sampler2DMS
#else
#define ATTACHMENT sampler2D
#endif

layout(local_size_x = LOCAL_SIZE) in;
layout(binding = RESOLVE_COLOR) uniform ATTACHMENT u_color;
#if defined NEED_FIELDS
layout(binding = RESOLVE_WRINKLE) uniform ATTACHMENT u_wrinkle;
#endif
#if defined NEED_NORMAL
layout(binding = RESOLVE_NORMAL) uniform ATTACHMENT u_normal;
#endif
layout(std430, binding = RESOLVE_OUT) writeonly buffer Words { uint words[]; };
layout(std430, binding = RESOLVE_BAD) buffer Bad { uint u_bad; };

uniform ivec2 u_size;
// The invocations cover the part of the frame drawn into (render/bounds.py), its pixels
// (EXR: pixel pairs) numbered row by row: u_rect = (x0, y0, x1, y1), x1 and y1 exclusive,
// in a grid u_grid_width wide (the frame's width; for the pairs of an odd-width frame, one
// row of all its pixels). What lies outside is filled in by render/resolve.py.
uniform ivec4 u_rect;
uniform int u_grid_width;
// OUTPUT_AOVS: first word of color, wrinkle.height, wrinkle.amplitude, normal, depth;
// OUTPUT_EXR: first word of each channel's plane, in the order above; -1: a channel the
// file leaves out (render --aovs)
uniform int u_offset[OFFSET_SLOTS];

const float INF = uintBitsToFloat(0x7f800000u);

struct Pixel {
    vec4 color;    // premultiplied by alpha
    vec3 wrinkle;  // height, amplitude, eye depth (inf where nothing was hit)
    vec3 normal;
};

vec4 average(ATTACHMENT target, ivec2 p) {
#if SAMPLES > 1
    vec4 sum = vec4(0.0);
    for (int s = 0; s < SAMPLES; ++s) sum += texelFetch(target, p, s);
    return sum / float(SAMPLES);
#else
    return texelFetch(target, p, 0);
#endif
}

// floor(a / b) for 0 <= a, 0 < b: a float division corrected by one either way (an
// integer division per invocation cost this pass a tenth of its time on llvmpipe, which
// divides vector lanes one at a time)
int divide(int a, int b) {
    int q = int(float(a) / float(b));
    int r = a - q * b;
    if (r < 0) q -= 1;
    if (r >= b) q += 1;
    return q;
}

// the pixel of index i = y * width + x
ivec2 pixel_of(int i) {
    int y = divide(i, u_size.x);
    return ivec2(i - y * u_size.x, y);
}

// the grid cell (x, y) of invocation j's first pixel (``step`` pixels per invocation),
// or (-1, -1) past the last
ivec2 item_cell(int j, int step) {
    int per_row = (u_rect.z - u_rect.x) / step;
    if (per_row <= 0 || j >= per_row * (u_rect.w - u_rect.y)) return ivec2(-1);
    int row = divide(j, per_row);
    return ivec2(u_rect.x + step * (j - row * per_row), u_rect.y + row);
}

Pixel resolve(ivec2 p) {
    Pixel px;
    px.color = average(u_color, p);
    bool covered = px.color.a > 0.0;
#if SAMPLES > 1
    float inverse = covered ? 1.0 / px.color.a : 0.0;
#else
    float inverse = 1.0;
#endif
    px.wrinkle = vec3(0.0, 0.0, INF);
    px.normal = vec3(0.0);
#if defined NEED_FIELDS
    px.wrinkle = average(u_wrinkle, p).xyz * inverse;
    if (!covered) px.wrinkle.z = INF;
#endif
#if defined NEED_NORMAL
    px.normal = average(u_normal, p).xyz * inverse;
#if SAMPLES > 1
    float len = length(px.normal);
    if (len > 0.0) px.normal /= len;
#endif
#endif
    return px;
}

uint bad_values(vec4 v) { return uint(any(isnan(v)) || any(isinf(v))); }

#if defined OUTPUT_8BIT
vec3 srgb_encode(vec3 linear) {  // IEC 61966-2-1, as colour.py's srgb_encode
    vec3 c = clamp(linear, 0.0, 1.0);
    return mix(1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, 12.92 * c,
               lessThanEqual(c, vec3(0.0031308)));
}

uint codes(Pixel px) {
#if defined OVER_BLACK
    if (px.color.rgb == vec3(0.0)) return 0xff000000u;  // black: no sRGB encode to run
    return packUnorm4x8(vec4(srgb_encode(px.color.rgb), 1.0));
#else
    if (!(px.color.a > 0.0)) return 0u;  // empty (or NaN): transparent black
    float alpha = clamp(px.color.a, 0.0, 1.0);
    vec3 straight = alpha > 0.0 ? px.color.rgb / alpha : vec3(0.0);
    return packUnorm4x8(vec4(srgb_encode(straight), alpha));
#endif
}
#endif

#if defined OUTPUT_EXR
// one channel's value of a resolved pixel, in the plane order
float channel(Pixel px, int c) {
    if (c < 4) return px.color[c];
    if (c < 6) return px.wrinkle[c - 4];
    if (c < 9) return px.normal[c - 6];
    return px.wrinkle.z;
}

#if defined HALF_COLOR_NORMAL
bool is_half(int c) { return c < 4 || (c >= 6 && c < 9); }
#else
bool is_half(int c) { return false; }
#endif
#endif

#if defined OUTPUT_EXR
// Two neighbouring pixels per invocation, so that a half plane's words hold whole pairs.
void main() {
    int n = u_size.x * u_size.y;
    ivec2 cell = item_cell(int(gl_GlobalInvocationID.x), 2);
    int first = cell.y * u_grid_width + cell.x;
    if (cell.x < 0 || first >= n) return;
    int pair = first / 2;  // first is even: a pair never straddles the rectangle's edge
    bool second = first + 1 < n;
    Pixel a = resolve(pixel_of(first));
    Pixel b = resolve(pixel_of(second ? first + 1 : first));
    uint bad = 0u;
    for (int c = 0; c < OFFSET_SLOTS; ++c) {
        if (u_offset[c] < 0) continue;
        vec2 v = vec2(channel(a, c), channel(b, c));
        if (is_half(c)) {
            // what the file will hold: NaN, or infinite where the value rounds beyond
            // half float's largest (65504; from 65520 up). Checked on the float, not on
            // the packed word: packHalf2x16 of an out-of-range value is undefined, and an
            // NVIDIA driver clamps it to 65504 where llvmpipe gives Inf
            bad += uint(any(isnan(v)) || any(greaterThanEqual(abs(v), vec2(65520.0))));
            words[u_offset[c] + pair] = packHalf2x16(v);
            continue;
        } else {
            words[u_offset[c] + first] = floatBitsToUint(v.x);
            if (second) words[u_offset[c] + first + 1] = floatBitsToUint(v.y);
        }
        bad += c == 9 ? uint(any(isnan(v))) : bad_values(vec4(v, 0.0, 0.0));
    }
    if (bad > 0u) atomicAdd(u_bad, bad);
}
#else
// One pixel per invocation.
void main() {
    ivec2 p = item_cell(int(gl_GlobalInvocationID.x), 1);  // the grid is the frame
    if (p.x < 0) return;
    int i = p.y * u_size.x + p.x;
    Pixel px = resolve(p);
    uint bad = bad_values(px.color);
#if defined OUTPUT_AOVS
    for (int c = 0; c < 4; ++c) words[u_offset[0] + 4 * i + c] = floatBitsToUint(px.color[c]);
#if defined NEED_FIELDS
    words[u_offset[1] + i] = floatBitsToUint(px.wrinkle.x);
    words[u_offset[2] + i] = floatBitsToUint(px.wrinkle.y);
    words[u_offset[4] + i] = floatBitsToUint(px.wrinkle.z);
    bad += bad_values(vec4(px.wrinkle.xy, 0.0, 0.0)) + uint(isnan(px.wrinkle.z));
#endif
#if defined NEED_NORMAL
    for (int c = 0; c < 3; ++c) words[u_offset[3] + 3 * i + c] = floatBitsToUint(px.normal[c]);
    bad += bad_values(vec4(px.normal, 0.0));
#endif
#elif defined OUTPUT_8BIT
    words[i] = codes(px);
#endif
    if (bad > 0u) atomicAdd(u_bad, bad);
}
#endif
