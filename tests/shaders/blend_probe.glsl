#version 430
// tests/test_blend.py: include/wave.glsl's blend_corner_waves on corner waves the test
// writes, one case per invocation, so that numpy can check it number by number.
#include "include/common.glsl"
#include "include/wave.glsl"

layout(local_size_x = 1) in;
const int CASE = 18;  // vec4 per case

// per case, 15 vec4: the 3 corner waves (k, a), the phases (xyz), the 3 corners (xyz),
// the barycentrics (xyz), the point p (xyz), the 3 rest corners (xyz) and the 3 corners'
// rest directions (xyz; the IRREGULAR variant's), the 3 corners' deepening (offset,
// gradient)
layout(std430, binding = 0) readonly buffer Cases { vec4 cases[]; };
// per case, 2 vec4: (h, exact gradient), (h, the tangent-plane gradient)
layout(std430, binding = 1) writeonly buffer Results { vec4 results[]; };

void main() {
    int i = int(gl_GlobalInvocationID.x);
    CornerWaves cw;
    for (int c = 0; c < 3; ++c) {
        cw.wave[c] = cases[CASE * i + c];
        cw.corner[c] = cases[CASE * i + 4 + c].xyz;
        cw.deepen[c] = cases[CASE * i + 15 + c];
#if defined IRREGULAR
        cw.rest[c] = cases[CASE * i + 9 + c].xyz;
        cw.u[c] = cases[CASE * i + 12 + c].xyz;
#endif
    }
    cw.phase[0] = cases[CASE * i + 3].xyz;
    cw.ratio[0] = vec3(1.0);
    vec3 bary = cases[CASE * i + 7].xyz;
    vec3 p = cases[CASE * i + 8].xyz;
    vec3 n = normalize(cross(cw.corner[1] - cw.corner[0], cw.corner[2] - cw.corner[0]));
    Footprint none = Footprint(vec3(0.0), vec3(0.0), 0.0);
    Wave exact = blend_corner_waves(cw, bary, p, n, true, none);
    Wave paper = blend_corner_waves(cw, bary, p, n, false, none);
    results[2 * i] = vec4(exact.height, exact.gradient);
    results[2 * i + 1] = vec4(paper.height, paper.gradient);
}
