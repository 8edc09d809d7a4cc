#version 430
// Mipmap pass: one level of a texture's mip chain from the level above it
// (render/mipmaps.py), all levels in one storage buffer: of RGBA8 words, or with FLOAT
// of RGBA32F texels.
//
// Each texel of level k is the bilinear sample of level k - 1 at its centre, as GL's
// glGenerateMipmap blit takes it: the average of a 2x2 block where the size halves
// exactly, the same weights as the blit where a size is odd. With u_srgb the colour is
// decoded to linear first and encoded after (IEC 61966-2-1, the sampler's conversion);
// alpha is linear.
#include "include/common.glsl"

layout(local_size_x = LOCAL_SIZE) in;
#if defined FLOAT
layout(std430, binding = MIPMAP_LEVELS) buffer Levels { vec4 texels[]; };
vec4 load(int i) { return texels[i]; }
void store(int i, vec4 value) { texels[i] = value; }
#else
layout(std430, binding = MIPMAP_LEVELS) buffer Levels { uint words[]; };
vec4 load(int i) { return unpackUnorm4x8(words[i]); }
void store(int i, vec4 value) { words[i] = packUnorm4x8(value); }
#endif

uniform ivec2 u_source_size;  // level k - 1 (width, height)
uniform ivec2 u_size;         // level k
uniform int u_layers;         // layers of a texture array (1: a 2D texture)
uniform int u_source_first;   // first texel of level k - 1, layer 0 (layers follow)
uniform int u_first;          // first texel of level k
uniform int u_srgb;           // 8-bit only

vec3 decode(vec3 c) {
    return mix(pow((c + 0.055) / 1.055, vec3(2.4)), c / 12.92, lessThanEqual(c, vec3(0.04045)));
}

vec3 encode(vec3 linear) {
    vec3 c = clamp(linear, 0.0, 1.0);
    return mix(1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, 12.92 * c,
               lessThanEqual(c, vec3(0.0031308)));
}

vec4 source(int layer, int x, int y) {
    vec4 c = load(u_source_first + (layer * u_source_size.y + y) * u_source_size.x + x);
    return u_srgb != 0 ? vec4(decode(c.rgb), c.a) : c;
}

// the two source texels a destination texel's centre falls between along one axis, and
// the second one's weight
void taps(int i, int size, int source_size, out int i0, out int i1, out float w) {
    float u = (float(i) + 0.5) * float(source_size) / float(size) - 0.5;
    float f = floor(u);
    w = u - f;
    i0 = clamp(int(f), 0, source_size - 1);
    i1 = min(i0 + 1, source_size - 1);
}

void main() {
    int n = int(gl_GlobalInvocationID.x);
    int per_layer = u_size.x * u_size.y;
    if (n >= per_layer * u_layers) return;
    int layer = n / per_layer;
    int rest = n - layer * per_layer;
    int y = rest / u_size.x;
    int x = rest - y * u_size.x;
    int x0, x1, y0, y1;
    float wx, wy;
    taps(x, u_size.x, u_source_size.x, x0, x1, wx);
    taps(y, u_size.y, u_source_size.y, y0, y1, wy);
    vec4 top = mix(source(layer, x0, y0), source(layer, x1, y0), wx);
    vec4 bottom = mix(source(layer, x0, y1), source(layer, x1, y1), wx);
    vec4 value = mix(top, bottom, wy);
    if (u_srgb != 0) value.rgb = encode(value.rgb);
    store(u_first + n, value);
}
