// UsdSkel's LBS and DQS blends of one point's joint influences, shared by the skin pass
// (points) and the normals pass (authored normals). Matrices are USD row-vector
// matrices uploaded as-is, so GLSL sees their transpose and 'M * vec4(p, 1)' equals
// USD's 'p * M'.
//
// Joints: JOINT_TEXELS (9) texels each.
//   0..2  LBS: the first three columns of the row-vector matrix geomBind * skinning
//         transform * skel-to-local, combined on the CPU in double precision (local rest ->
//         local posed): posed coordinate c = dot(column c, (p, 1))
//   3     unused
//   4..6  LBS: the rows of that matrix's 3x3 inverse (local rest -> local posed normals:
//         normal coordinate c = dot(row c, n), the inverse transpose's column c)
//   4     DQS rotation quaternion (xyz, w)
//   5     DQS dual part (xyz, w)
//   6..8  DQS scale/shear remainder, row-vector 3x3 rows, applied by LBS
#define JOINT(j, k) fetch(joints, JOINT_TEXELS * (j) + (k))

layout(binding = SKIN_INFLUENCES) uniform sampler2D influences;  // x: joint (-1: none), y: weight
layout(binding = SKIN_JOINTS) uniform sampler2D joints;

uniform int u_influences;      // influences per point
uniform int u_num_joints;
uniform int u_has_scale;       // DQS: any joint has scale or shear
uniform mat4 u_geom_bind;      // local (rest) -> skeleton bind space
uniform mat4 u_skel_to_local;  // skeleton space -> prim (local) space

vec3 quat_rotate(vec4 q, vec3 v) {
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// LBS is linear in the matrices: sum_j w_j (p G J_j S) with the three matrices of each
// joint premultiplied, local rest -> local posed in one product
vec3 skin_lbs(int i, vec3 p) {
    vec3 local_p = vec3(0.0);
    vec4 p1 = vec4(p, 1.0);
    for (int k = 0; k < u_influences; ++k) {
        vec2 influence = fetch(influences, i * u_influences + k).xy;
        int j = int(influence.x);
        float w = influence.y;
        if (w != 0.0 && j >= 0 && j < u_num_joints) {
            local_p += vec3(dot(JOINT(j, 0), p1), dot(JOINT(j, 1), p1),
                            dot(JOINT(j, 2), p1)) * w;
        }
    }
    return local_p;
}

// the same blend of the joints' normal matrices (inverse transposes), local rest ->
// local posed, unnormalised
vec3 skin_lbs_normal(int i, vec3 n) {
    vec3 local_n = vec3(0.0);
    for (int k = 0; k < u_influences; ++k) {
        vec2 influence = fetch(influences, i * u_influences + k).xy;
        int j = int(influence.x);
        float w = influence.y;
        if (w != 0.0 && j >= 0 && j < u_num_joints) {
            local_n += vec3(dot(JOINT(j, 4).xyz, n), dot(JOINT(j, 5).xyz, n),
                            dot(JOINT(j, 6).xyz, n)) * w;
        }
    }
    return local_n;
}

// DQS (UsdSkel's): the blended unit dual quaternion of point i's joints, pivoted on its
// largest weight (first on ties): (real, dual), and the LBS blend of the joints'
// scale/shear remainders applied to the bind-space point ``bind_p``
void dqs_blend(int i, vec3 bind_p, out vec4 sum_real, out vec4 sum_dual, out vec3 scaled_p) {
    int base = i * u_influences;
    int pivot = -1;
    float max_w = -1.0;
    for (int k = 0; k < u_influences; ++k) {
        vec2 influence = fetch(influences, base + k).xy;
        int j = int(influence.x);
        float w = influence.y;
        if (j >= 0 && j < u_num_joints && (pivot < 0 || max_w < w)) {
            max_w = w;
            pivot = j;
        }
    }
    vec4 pivot_q = pivot >= 0 ? JOINT(pivot, 4) : vec4(0.0);
    scaled_p = vec3(0.0);
    sum_real = vec4(0.0);
    sum_dual = vec4(0.0);
    for (int k = 0; k < u_influences; ++k) {
        vec2 influence = fetch(influences, base + k).xy;
        int j = int(influence.x);
        float w = influence.y;
        if (w == 0.0 || j < 0 || j >= u_num_joints) continue;
        if (u_has_scale != 0) {
            // scale/shear by LBS, row-vector 3x3
            scaled_p += (bind_p.x * JOINT(j, 6).xyz
                       + bind_p.y * JOINT(j, 7).xyz
                       + bind_p.z * JOINT(j, 8).xyz) * w;
        }
        vec4 real = JOINT(j, 4);
        if (dot(real, pivot_q) < 0.0) w = -w;  // same hemisphere as the pivot
        sum_real += real * w;
        sum_dual += JOINT(j, 5) * w;
    }
    if (u_has_scale == 0) scaled_p = bind_p;
    float len = length(sum_real);
    if (len > 0.0) {
        sum_real /= len;
        sum_dual /= len;
    }
}

vec3 skin_dqs(int i, vec3 p) {
    // local -> skeleton bind space -> skeleton space -> prim (local) space
    vec3 bind_p = (u_geom_bind * vec4(p, 1.0)).xyz;
    vec4 real, dual;
    vec3 scaled_p;
    dqs_blend(i, bind_p, real, dual, scaled_p);
    vec3 skel_p = scaled_p;
    if (length(real) > 0.0) {
        vec3 t = 2.0 * (real.w * dual.xyz - dual.w * real.xyz + cross(real.xyz, dual.xyz));
        skel_p = quat_rotate(real, scaled_p) + t;
    }
    return (u_skel_to_local * vec4(skel_p, 1.0)).xyz;
}

// DQS normals: rotated by the blended rotation; geomBind and skel-to-local by their
// normal matrices (u_*_normal: inverse transposes, column-vector); the joints' scale
// remainders are left out (docs/method.md: a documented approximation)
uniform mat3 u_geom_bind_normal;
uniform mat3 u_skel_to_local_normal;

vec3 skin_dqs_normal(int i, vec3 n) {
    vec4 real, dual;
    vec3 scaled_p;
    dqs_blend(i, vec3(0.0), real, dual, scaled_p);
    vec3 bind_n = u_geom_bind_normal * n;
    vec3 skel_n = length(real) > 0.0 ? quat_rotate(real, bind_n) : bind_n;
    return u_skel_to_local_normal * skel_n;
}
