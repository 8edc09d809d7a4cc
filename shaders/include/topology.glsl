// Mesh topology in one int table (CSR). Offsets of each part come as uniforms:
//   [neighbor_offsets (n+1) | neighbor_indices | triangle_offsets (n+1) |
//    triangle_indices (3m)]
// Triangle corners are a table of their own (ivec4 per triangle), read by the pass that
// needs them.
// The including pass defines TOPOLOGY_TABLE, the texture unit it binds the table to.
#ifndef USDWRINKLE_TOPOLOGY_GLSL
#define USDWRINKLE_TOPOLOGY_GLSL

layout(binding = TOPOLOGY_TABLE) uniform highp isampler2D topology_table;

uniform int u_neighbor_indices_base;
uniform int u_triangle_offsets_base;
uniform int u_triangle_indices_base;

#define TOPOLOGY(index) fetch(topology_table, (index)).x
#define NEIGHBOR_BEGIN(i) TOPOLOGY(i)
#define NEIGHBOR_END(i) TOPOLOGY((i) + 1)
#define NEIGHBOR(e) TOPOLOGY(u_neighbor_indices_base + (e))
#define TRIANGLE_BEGIN(i) TOPOLOGY(u_triangle_offsets_base + (i))
#define TRIANGLE_END(i) TOPOLOGY(u_triangle_offsets_base + (i) + 1)
#define INCIDENT_TRIANGLE(e) TOPOLOGY(u_triangle_indices_base + (e))

#endif
