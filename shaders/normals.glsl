#version 430
// Normals pass: the shading normals of one frame (scene/normals.py), as Storm makes them.
//   SMOOTH   per point: sum over its polygon corners of cross(next - p, prev - p)
//            (hd/smoothNormals.cpp), for subdivision meshes
//   FACETED  per face: sum over its fan of cross(v[j-1] - v0, v[j] - v0)
//            (hd/flatNormals.cpp), for polygonal meshes without authored normals
//   SKINNED  per authored normal: skinned by its point's joints (LBS or DQS)
// The plan table holds entries + 1 offsets, then each entry's list: (prev, next) pairs,
// the face's points, or the point that skins it.
#include "include/common.glsl"
#if defined SKINNED
#include "include/skinning.glsl"
#endif

layout(local_size_x = LOCAL_SIZE) in;

layout(binding = NORMALS_PLAN) uniform isampler2D plan;
layout(rgba32f, binding = NORMALS_OUT) writeonly uniform image2D shading_normals;
#if defined SKINNED
layout(binding = NORMALS_AUTHORED) uniform sampler2D authored;
uniform int u_method;  // 1: LBS, 2: DQS
#else
layout(binding = NORMALS_POSED_POINTS) uniform sampler2D posed_points;
#endif

uniform int u_entries;

int plan_at(int k) { return fetch(plan, k).x; }

void main() {
    int e = int(gl_GlobalInvocationID.x);
    if (e >= u_entries) return;
    int first = plan_at(e);
    int last = plan_at(e + 1);
    vec3 n = vec3(0.0);
#if defined SKINNED
    int i = plan_at(first);
    vec3 rest = fetch(authored, e).xyz;
    n = u_method == 1 ? skin_lbs_normal(i, rest) : skin_dqs_normal(i, rest);
#elif defined SMOOTH
    vec3 p = fetch(posed_points, e).xyz;
    for (int k = first; k + 1 < last; k += 2) {
        vec3 prev = fetch(posed_points, plan_at(k)).xyz;
        vec3 next = fetch(posed_points, plan_at(k + 1)).xyz;
        n += cross(next - p, prev - p);
    }
#else  // FACETED
    if (last - first >= 3) {
        vec3 v0 = fetch(posed_points, plan_at(first)).xyz;
        for (int k = first + 2; k < last; ++k) {
            vec3 v1 = fetch(posed_points, plan_at(k - 1)).xyz;
            vec3 v2 = fetch(posed_points, plan_at(k)).xyz;
            n += cross(v1 - v0, v2 - v0);
        }
    }
#endif
    float len = length(n);
    // w: 1 where the normal is usable, 0 where it degenerates (the draw falls back)
    STORE(shading_normals, e, len > 0.0 ? vec4(n / len, 1.0) : vec4(0.0, 0.0, 1.0, 0.0));
}
