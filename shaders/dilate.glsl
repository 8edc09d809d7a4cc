#version 430
// Padding of wrinkle maps (maps/raster.py): one step of island dilation. A texel no
// triangle covers (coverage w == 0) takes the mean of its covered 8-neighbours and
// becomes covered; run --map-padding times, islands grow by that many texels, so
// that filtering and mip-mapping at their borders do not pull in the background.
#include "include/common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = DILATE_NORMAL_IN, rgba32f) readonly uniform image2D normal_in;
layout(binding = DILATE_WRINKLE_IN, rgba32f) readonly uniform image2D wrinkle_in;
layout(binding = DILATE_NORMAL_OUT, rgba32f) writeonly uniform image2D normal_out;
layout(binding = DILATE_WRINKLE_OUT, rgba32f) writeonly uniform image2D wrinkle_out;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(normal_in);
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 normal = imageLoad(normal_in, p);
    vec4 wrinkle = imageLoad(wrinkle_in, p);
    if (normal.w == 0.0) {
        vec4 normal_sum = vec4(0.0);
        vec4 wrinkle_sum = vec4(0.0);
        float count = 0.0;
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                ivec2 q = p + ivec2(dx, dy);
                if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
                vec4 neighbour = imageLoad(normal_in, q);
                if (neighbour.w == 0.0) continue;
                normal_sum += neighbour;
                wrinkle_sum += imageLoad(wrinkle_in, q);
                count += 1.0;
            }
        }
        if (count > 0.0) {
            normal = vec4(safe_normalize(normal_sum.xyz, vec3(0.0, 0.0, 1.0)), 1.0);
            wrinkle = vec4(wrinkle_sum.xy / count, 0.0, 1.0);  // z: not a triangle's
        }
    }
    imageStore(normal_out, p, normal);
    imageStore(wrinkle_out, p, wrinkle);
}
