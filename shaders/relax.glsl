#version 430
// Relax pass. The phases live as unit phasors z = e^{i phi} during the iterations, so a
// Jacobi step is complex multiply-adds only: no sin, cos or atan per edge.
//
//   phi_i <- arg( a_i e^{i phi_i} + sum_j a_j e^{i (phi~_j - kbar_ij . (x_j - x_i))} )
//   e^{i (phi~_j - d_ij)} = z~_j * e^{-i d_ij},  z~_j = conj(z_j) when (k, phi) flips
//
// Each vertex has u_systems wave systems (1, or 2 with wrinkle:biaxial): each
// relaxes on its own, against the neighbour's partner system matched by direction
// (partner_system in common.glsl), since the two eigenvectors can swap between
// neighbours and between frames. Phasors are RGBA (xy: system 1, zw: system 2), phases
// RG.
//
// Entry points, selected by the loader's defines:
//   SEED      per vertex: the start phasors (previous frame's phases, sign-aligned, where
//             the wave was there last frame; for a new wave, the phase its ring's kept
//             waves ask for, or with none its previous phase; where there is no wave, and
//             on a shot's first frame, the material-anchored phases) and, per outgoing
//             edge and system, the rotation e^{-i d_ij}, the flip, the neighbour's pull
//             and system.
//   (default) one Jacobi step on the phasors (ping-pong); the last step also writes phi,
//             moved from the seed by only the vertex's mobility m of the way (below).
//             On a cold start (u_cold_start: no history, COLD_START_FACTOR times the
//             steps) a step is the weighted mean, not normalised: z_i <- (a_i z_i +
//             sum_j a_j z~_j e^{-i d_ij}) / (a_i + sum_j a_j), so a vertex whose ring
//             disagrees (a defect's core) keeps a short phasor and pulls less; where the
//             defects of the first frame settle was a lottery a 0.1 degree change of a
//             joint could tip (CesiumMan: 2 of 32 random axes over the 5% bar at the
//             slack 0.05, 29 at 0.055; 0 and 8 with the mean; docs/method.md, "Jacobi
//             step"). Every later frame normalises: with the mean there, a core that
//             a dislocation sweeps past, frozen by its mobility, unwinds either way as
//             it leaves (docs/physics.md, "Adopting it, tried").
//   FIT       per vertex and system, after the last step: the wave the relaxed phases
//             draw. Phases carried through a shot keep the crest count of the folds'
//             onset while coarsening asks for fewer; the corner waves of a triangle,
//             each extrapolated with crush's k, then disagreed inside it, and their
//             blend drew too much slope (docs/physics.md, "Inextensibility"). The
//             residual of each edge, r_ij = arg(z~_j e^{-i d_ij} conj(z_i)), is what the
//             phases advance beyond kbar_ij . (x_j - x_i); the least-squares c in the
//             tangent plane with c . (x_j - x_i)_t ~ r_ij (weights a_j) gives k + t c and
//             the amplitude a |k| / |k + t c|: the same slope a |k|, which restores the
//             cloth's length. t only makes waves shorter (fading in from 1x to
//             FIT_ONSET), so no fold grows taller than crush made it; it fades out where
//             the ring's directions are too few (FIT_CONDITION) or |k| would grow by more
//             than FIT_RANGE. Edges along which the wave advances more than pi / 2 count
//             less, beyond pi not at all. Every weight is smooth, so a small change of
//             the mesh is a small change of the fit. Writes the wave texels of the
//             fields in place (each vertex only its own).
//
// Mobility (docs/method.md, "Mobility"; reference/relax.py's mobility): with history, a
// vertex's relaxed phase moves from its seed by m = min(max(x - MOBILITY_DEADBAND, 0) /
// (1 - MOBILITY_DEADBAND), 1) of the way the steps take it, x = delta / MOBILITY_PHASE +
// turn / MOBILITY_TURN (the dead band: a creep of a fraction of a millimetre a frame after
// a pose stops moves no crest). Each ring edge counts by smoothstep(0, MOBILITY_RING,
// a_j / a_i): a neighbour without a wave, whose direction is its strain's noise, not at
// all (contract.py). The change since the previous grid
// frame of the phase difference its ring asks for along an edge, (kappa_now -
// kappa_before) . (X_j - X_i) averaged over the edge's two ends, kappa = (2 pi / L) d3 the
// material wave vector (rest space; crush keeps 2 pi / L in the state's damped table), is
// split into the wave number's part, (w_now - w_before) d3_now (delta: the largest over
// the ring), and the direction's, w_before (d3_now - d3_before) (turn). Input that does
// not change leaves the phases where they are: cloth whose pose stops keeps its folds,
// where the relaxation went on creeping towards its far-off fixed point (the referee's
// held sleeve: crests moving 8.6x the cloth's), and a direction that only turns a little
// (a nearly isotropic strain's wander) hardly moves them. A new wave, and a cold start,
// relax fully.
#include "include/common.glsl"
#include "include/topology.glsl"

layout(local_size_x = LOCAL_SIZE) in;

uniform int u_num_points;
// the TWO_SYSTEMS variant loops over u_systems (wrinkle:biaxial); the default one is the
// paper's single system (as in wave.glsl)
// (phasors RGBA, one edge texel per edge and system) or the paper's single system (as in
// wave.glsl: phasors RG, one edge texel per edge, as before the second system existed)
#if defined TWO_SYSTEMS
uniform int u_systems;
#define SYSTEMS u_systems
#define PARTNER(k, s, j) partner_system(k, s, wave_of(fields, j, 0), wave_of(fields, j, 1))
#define EDGE(e, s) (2 * (e) + (s))
#define Z_FORMAT rgba32f
#else
#define SYSTEMS 1
#define PARTNER(k, s, j) 0
#define EDGE(e, s) (e)
#define Z_FORMAT rg32f
#endif

layout(binding = RELAX_FIELDS) uniform sampler2D fields;
// Per directed edge e (CSR order) and system s, texel EDGE(e, s): xy = e^{-i d_ij},
// z = flip * (a_j + WEIGHT_FLOOR) aligned(k_i, k_j) (the partner's pull, negative where
// its wave is flipped; 0 only at right angles; floor_aligned where i has no wave), w = j
// as a float (exact below 2^24 points), -(j + 1) when the partner is j's system 2. One
// fetch per edge: the step needs no topology lookup for j.
// SEED writes them (image), the steps read them (texture).

// WEIGHT_FLOOR (contract.py): a tiny floor on the weights keeps arg() defined where no
// vertex is wrinkled.

vec2 complex_mul(vec2 a, vec2 b) { return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }

// vertex i's system s: its wave vector k, and in w the fold the relaxation weighs its phase
// by (crush's weight: the fold law with the crests' slack; the drawn fold is FIELD_WAVE's w)
vec4 wave_of(sampler2D table, int i, int s) {
    return vec4(fetch(table, FIELD_WAVE_OF(i, s)).xyz, fetch(table, FIELD_LENGTH(i))[1 + s]);
}

// How much a neighbour's wave pulls a vertex's phase beside its amplitude (contract.py's
// RELAX_ALIGNED): fully within 78 degrees, not at all at right angles (no phase to agree
// on, and a coin toss for the sign test). An edge that aliases the wave still pulls: the
// phases agree modulo 2 pi, which is what the draw's blend of the corner waves needs
// (fading the pull beyond pi to 2 pi doubled the shirt's misfit, 0.555 to 1.22, at its
// cuff, whose painted waves advance 7-12 rad an edge; docs/method.md, "Three couplings
// that rounding could throw")
float abs_cos(vec3 a, vec3 b) { return abs(dot(a, b)) / max(length(a) * length(b), 1e-30); }

float aligned(vec3 k_i, vec3 k_j) { return smoothstep(0.0, RELAX_ALIGNED, abs_cos(k_i, k_j)); }

// ... and on a point without a wave (contract.py's FLOOR_ALIGNED): only along its own
// direction, fully within 18 degrees, not at all beyond 46 (waves at 84-88 degrees
// pulled the bare points beside the painted loop a million times harder than the floor,
// and the first waves that grew in there inherited a drift that means nothing)
float floor_aligned(vec3 k_i, vec3 k_j) {
    return smoothstep(FLOOR_ALIGNED_FROM, FLOOR_ALIGNED, abs_cos(k_i, k_j));
}

// The neighbour an edge texel names (EDGE(e, s), below), and its phasor of the partner
// system, conjugated where the partner's wave is flipped: z~_j.
vec2 neighbour_phasor(sampler2D phasors, vec4 edge, out int j) {
    j = edge.w >= 0.0 ? int(edge.w) : int(-edge.w) - 1;
    vec4 z_all = fetch(phasors, j);
    vec2 z_j = edge.w >= 0.0 ? z_all.xy : z_all.zw;
    if (edge.z < 0.0) z_j.y = -z_j.y;
    return z_j;
}

#if defined SEED

layout(binding = RELAX_PREVIOUS_FIELDS) uniform sampler2D previous_fields;
layout(binding = RELAX_ANCHOR) uniform sampler2D anchor_phase;
// the relaxed phases of the shot's previous grid frame (its wave state, read only), and
// this frame's phases: the seeds (the result when there are no iterations)
layout(binding = RELAX_PREVIOUS_PHASE) uniform sampler2D previous_phase;
layout(rg32f, binding = RELAX_PHASE) writeonly uniform image2D phase;
layout(binding = RELAX_POSED_POINTS) uniform sampler2D posed_points;
layout(Z_FORMAT, binding = RELAX_Z_OUT) writeonly uniform image2D z_out;
layout(rgba32f, binding = RELAX_EDGES_OUT) writeonly uniform image2D edges;
// the rest points, and this frame's and the previous grid frame's damped tables (w: the
// material wave number 2 pi / L); x: the mobility, yz: the seeds of systems 1 and 2
layout(binding = RELAX_REST_POINTS) uniform sampler2D rest_points;
layout(binding = RELAX_DAMPED) uniform sampler2D damped;
layout(binding = RELAX_PREVIOUS_DAMPED) uniform sampler2D previous_damped;
layout(rgba32f, binding = RELAX_MOBILITY_OUT) writeonly uniform image2D mobility_out;

uniform int u_has_history;

// vertex v's material wave vector kappa = (2 pi / L) d3 (rest space) of this frame, and
// its change since the previous grid frame's state split in two (the previous d3's sign
// matched first: (k, phi) and (-k, -phi) are one wave): the wave number's, (w_now -
// w_before) d3_now, and the direction's, w_before (d3_now - d3_before)
vec3 kappa_change(int v, out vec3 wave_part, out vec3 turn_part) {
    float w_now = fetch(damped, v).w;
    float w_before = fetch(previous_damped, v).w;
    vec3 d_now = fetch(fields, FIELD_DIRECTION(v)).xyz;
    vec3 d_before = fetch(previous_fields, FIELD_DIRECTION(v)).xyz;
    if (dot(d_now, d_before) < 0.0) d_before = -d_before;
    wave_part = (w_now - w_before) * d_now;
    turn_part = w_before * (d_now - d_before);
    return w_now * d_now;
}

// The share of the relaxation's move a vertex takes this frame (the header: mobility)
float mobility(int i, bool history, vec4 before0) {
    if (!history || !(wave_of(fields, i, 0).w > 0.0) || !(before0.w > 0.0)) return 1.0;
    vec3 wave_i, turn_i;
    vec3 kappa_i = kappa_change(i, wave_i, turn_i);
    vec3 X_i = fetch(rest_points, i).xyz;
    float delta = 0.0;
    float turn = 0.0;
    float a_i = max(wave_of(fields, i, 0).w, 1e-30);
    for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
        int j = NEIGHBOR(e);
        // a neighbour without a wave has its strain's noise for a direction: it counts
        // from none to fully over MOBILITY_RING of the vertex's amplitude
        float a_j = min(wave_of(fields, j, 0).w, wave_of(previous_fields, j, 0).w);
        float counts = smoothstep(0.0, MOBILITY_RING, a_j / a_i);
        if (!(counts > 0.0)) continue;
        vec3 wave_j, turn_j;
        vec3 kappa_j = kappa_change(j, wave_j, turn_j);
        counts *= aligned(kappa_i, kappa_j);
        float sign_j = dot(kappa_j, kappa_i) < 0.0 ? -1.0 : 1.0;
        vec3 edge = fetch(rest_points, j).xyz - X_i;
        delta = max(delta, counts * abs(dot(0.5 * (wave_i + sign_j * wave_j), edge)));
        turn = max(turn, counts * abs(dot(0.5 * (turn_i + sign_j * turn_j), edge)));
    }
    float moved = delta / MOBILITY_PHASE + turn / MOBILITY_TURN;
    return min(max(moved - MOBILITY_DEADBAND, 0.0) / (1.0 - MOBILITY_DEADBAND), 1.0);
}

// Whether vertex v's system s (its wave (k, w) now) keeps last frame's phase: it has a
// wave now and had one last frame (its partner system then). ``kept``: last frame's
// phase, flipped where k flipped (where v has a wave now, whether or not it had one). A
// point without a wave starts again from its material-anchored phase (the flip test
// decided the sign of such a point's meaningless k by rounding, and a wrinkle that grew
// there later inherited it; docs/method.md: stability); a wave that is new starts from
// the phase its ring's kept waves ask for, and with none beside it from ``kept`` (main).
bool kept_phase(int v, int s, vec4 wave, out float kept) {
    kept = 0.0;
    if (u_has_history == 0 || !(wave.w > 0.0)) return false;
    vec4 before0 = wave_of(previous_fields, v, 0);
#if defined TWO_SYSTEMS
    vec4 before1 = wave_of(previous_fields, v, 1);
    int was = partner_system(wave.xyz, s, before0, before1);
    vec4 wave_before = was == 0 ? before0 : before1;
#else
    int was = 0;
    vec4 wave_before = before0;
#endif
    kept = (dot(wave.xyz, wave_before.xyz) < 0.0 ? -1.0 : 1.0) * fetch(previous_phase, v)[was];
    return wave_before.w > 0.0;
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec2 anchor = fetch(anchor_phase, i).xy;
    bool history = u_has_history != 0;
    vec4 before0 = history ? wave_of(previous_fields, i, 0) : vec4(0.0);
    vec2 start = anchor;
    vec4 z = vec4(0.0);
    vec3 x_i = fetch(posed_points, i).xyz;  // posed, local space
    for (int s = 0; s < SYSTEMS; ++s) {
        vec4 wave_i = wave_of(fields, i, s);
        vec3 k_i = wave_i.xyz;
        float kept;
        bool keeps = kept_phase(i, s, wave_i, kept);
        // a new wave starts from the phase its ring's kept waves ask for (their pulls,
        // as a Jacobi step would), where it has such neighbours: its own last phase was
        // what the floor weights made of them along its meaningless k, which a 0.01
        // degree change moved by 1.6-3.1 rad at the shirt's elbow. With none beside it,
        // it keeps that phase (its region's onset): its anchor lies anywhere against
        // the waves around (the pull's misfit 0.39 -> 0.51; the referee's held 25 cm
        // sleeve's crests 1.18x -> 1.78x the cloth's motion)
        vec2 ask = vec2(0.0);
        for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
            int j = NEIGHBOR(e);
            int partner = PARTNER(k_i, s, j);
            vec4 wave_j = wave_of(fields, j, partner);
            float flip = dot(k_i, wave_j.xyz) < 0.0 ? -1.0 : 1.0;
            vec3 k_bar = 0.5 * (k_i + flip * wave_j.xyz);
            float drift = dot(k_bar, fetch(posed_points, j).xyz - x_i);
            float align = wave_i.w > 0.0 ? aligned(k_i, wave_j.xyz)
                                         : floor_aligned(k_i, wave_j.xyz);
            float pull = wave_j.w * align;
            STORE(edges, EDGE(e, s), vec4(cos(drift), -sin(drift),
                                         flip * (wave_j.w + WEIGHT_FLOOR) * align,
                                         partner == 0 ? float(j) : -float(j) - 1.0));
            float kept_j;
            if (!keeps && history && wave_i.w > 0.0 && kept_phase(j, partner, wave_j, kept_j)) {
                float asked = flip * kept_j - drift;
                ask += pull * vec2(cos(asked), sin(asked));
            }
        }
        if (keeps) start[s] = kept;
        else if (dot(ask, ask) > 0.0) start[s] = atan(ask.y, ask.x);
        else if (history && wave_i.w > 0.0) start[s] = kept;
        z[2 * s] = cos(start[s]);
        z[2 * s + 1] = sin(start[s]);
    }
    STORE(mobility_out, i, vec4(mobility(i, history, before0), start, 0.0));
    STORE(phase, i, vec4(start, 0.0, 0.0));
    STORE(z_out, i, z);
}

#elif defined FIT

layout(binding = RELAX_EDGES) uniform sampler2D edges;
layout(binding = RELAX_Z_IN) uniform sampler2D z_in;  // the relaxed phasors
layout(binding = RELAX_POSED_POINTS) uniform sampler2D posed_points;
layout(rgba32f, binding = RELAX_FIELDS_OUT) writeonly uniform image2D fields_out;  // = fields
// x: the point's coarsening cap (crush.glsl's; folds.coarsening_cap)
layout(binding = RELAX_COARSENING) uniform sampler2D coarsening;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec3 n = fetch(fields, FIELD_NORMAL(i)).xyz;
    vec3 x_i = fetch(posed_points, i).xyz;
    vec4 z_i = fetch(z_in, i);
    vec4 weights = fetch(fields, FIELD_LENGTH(i));
    for (int s = 0; s < SYSTEMS; ++s) {
        vec4 wave = wave_of(fields, i, s);
        if (wave.w <= 0.0) continue;
        vec2 own = s == 0 ? z_i.xy : z_i.zw;
        mat3 normal_equations = mat3(0.0);
        vec3 rhs = vec3(0.0);
        float trace = 0.0;
        for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
            vec4 edge = fetch(edges, EDGE(e, s));
            float weight = abs(edge.z) - WEIGHT_FLOOR;  // a_j: only neighbours with a wave
            if (weight <= 0.0) continue;
            int j;
            vec2 z_j = neighbour_phasor(z_in, edge, j);
            vec2 rel = complex_mul(complex_mul(z_j, edge.xy), vec2(own.x, -own.y));
            float residual = atan(rel.y, rel.x);
            vec3 dx = fetch(posed_points, j).xyz - x_i;
            // an edge along which the wave advances more than pi / 2 counts less, beyond
            // pi not at all: the ring does not sample the wave there
            weight *= 1.0 - smoothstep(0.5 * PI, PI, abs(dot(wave.xyz, dx)));
            dx -= dot(dx, n) * n;
            normal_equations += weight * outerProduct(dx, dx);
            rhs += weight * residual * dx;
            trace += weight * dot(dx, dx);
        }
        if (!(trace > 0.0)) continue;
        // the equations over their trace, so that float32 keeps their digits whatever the
        // scene's units and the weights' size (CesiumMan: a ring of 2 cm edges whose one
        // neighbour with a wave, 5e-6 m high, lay near the pi cutoff had a trace of 7e-14,
        // whose cube, 3e-40, an NVIDIA GPU flushed to zero and took to NaN in c); n n^T
        // at the tangent block's scale pins c to the tangent plane; two independent
        // tangent directions: the determinant, the tangent block's over trace^2 (at most
        // 1/4)
        mat3 unit_equations = normal_equations / trace + outerProduct(n, n);
        float spread = determinant(unit_equations);
        if (!(spread > FIT_CONDITION)) continue;
        vec3 c = inverse(unit_equations) * (rhs / trace);
        if (!(dot(c, c) < 1e30)) continue;  // never a non-finite wave (GLSL leaves NaN to the GL)
        float change = length(wave.xyz + c) / max(length(wave.xyz), 1e-30);
        // only a wave the phases draw shorter (the history's twist), fully from FIT_ONSET
        // ... and only where the folds coarsen: the twist is coarsening's (where the cap
        // holds them at W, a ring that barely samples the wave switched the fit on and off)
        float trust = smoothstep(FIT_CONDITION, 2.0 * FIT_CONDITION, spread)
            * smoothstep(1.0, FIT_ONSET, change)
            * (1.0 - smoothstep(0.75 * FIT_RANGE, FIT_RANGE, change))
            * smoothstep(1.0, COARSENING_MAX, fetch(coarsening, i).x);
        vec3 k = wave.xyz + trust * c;
        // never a longer wave than crush's (a partly trusted c that turns k could shorten
        // it): k keeps at least crush's length
        k *= max(1.0, length(wave.xyz) / max(length(k), 1e-30));
        float scale = length(wave.xyz) / max(length(k), 1e-30);
        // the drawn fold and the weight alike keep their slope a|k|
        STORE(fields_out, FIELD_WAVE_OF(i, s),
              vec4(k, fetch(fields, FIELD_WAVE_OF(i, s)).w * scale));
        weights[1 + s] = wave.w * scale;
    }
    STORE(fields_out, FIELD_LENGTH(i), weights);
}

#else

layout(binding = RELAX_EDGES) uniform sampler2D edges;
layout(binding = RELAX_Z_IN) uniform sampler2D z_in;
layout(Z_FORMAT, binding = RELAX_Z_OUT) writeonly uniform image2D z_out;
layout(rg32f, binding = RELAX_PHASE) writeonly uniform image2D phase;
layout(binding = RELAX_MOBILITY) uniform sampler2D mobility;  // x: m, yz: the seeds

uniform int u_write_phase;  // the last iteration also stores phi = arg z, moved by m
// a cold start (no history: the shot's first frame): the steps are the weighted mean
uniform int u_cold_start;

float wrap_angle(float a) { return a - TWO_PI * floor((a + PI) / TWO_PI); }

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_num_points) return;
    vec4 z_i = fetch(z_in, i);
    vec4 z = z_i;
    for (int s = 0; s < SYSTEMS; ++s) {
        vec2 own = s == 0 ? z_i.xy : z_i.zw;
        float total = wave_of(fields, i, s).w + WEIGHT_FLOOR;
        vec2 sum = total * own;
        for (int e = NEIGHBOR_BEGIN(i); e < NEIGHBOR_END(i); ++e) {
            vec4 edge = fetch(edges, EDGE(e, s));
            int j;
            sum += abs(edge.z) * complex_mul(neighbour_phasor(z_in, edge, j), edge.xy);
            total += abs(edge.z);
        }
        float len2 = dot(sum, sum);
        vec2 next = !(len2 > 0.0) ? own
                  : u_cold_start != 0 ? sum / total : sum * inversesqrt(len2);
        if (s == 0) z.xy = next; else z.zw = next;
    }
    if (u_write_phase == 0) {
        STORE(z_out, i, z);
        return;
    }
    // the last step: m of the way from the seed, exactly the seed where m = 0 (the fit
    // reads these phasors too)
    vec4 seed = fetch(mobility, i);
    vec2 phi = vec2(atan(z.y, z.x), SYSTEMS > 1 ? atan(z.w, z.z) : 0.0);
    if (seed.x < 1.0) {
        for (int s = 0; s < SYSTEMS; ++s) {
            phi[s] = seed[1 + s] + seed.x * wrap_angle(phi[s] - seed[1 + s]);
            vec2 unit = vec2(cos(phi[s]), sin(phi[s]));
            if (s == 0) z.xy = unit; else z.zw = unit;
        }
    }
    STORE(z_out, i, z);
    STORE(phase, i, vec4(phi, 0.0, 0.0));
}

#endif
