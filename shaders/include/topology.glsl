// Mesh topology in one int SSBO (CSR). Offsets of each part come as uniforms:
//   [neighbor_offsets (n+1) | neighbor_indices | triangle_offsets (n+1) |
//    triangle_indices (3m) | triangles (3m)]
#ifndef USDWRINKLE_TOPOLOGY_GLSL
#define USDWRINKLE_TOPOLOGY_GLSL

uniform int u_neighbor_indices_base;
uniform int u_triangle_offsets_base;
uniform int u_triangle_indices_base;
uniform int u_triangles_base;

#define NEIGHBOR_BEGIN(i) topology[(i)]
#define NEIGHBOR_END(i) topology[(i) + 1]
#define NEIGHBOR(e) topology[u_neighbor_indices_base + (e)]
#define TRIANGLE_BEGIN(i) topology[u_triangle_offsets_base + (i)]
#define TRIANGLE_END(i) topology[u_triangle_offsets_base + (i) + 1]
#define INCIDENT_TRIANGLE(e) topology[u_triangle_indices_base + (e)]
#define TRIANGLE_CORNER(t, c) topology[u_triangles_base + 3 * (t) + (c)]

#endif
