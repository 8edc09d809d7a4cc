"""The Python <-> GLSL contract: every constant that both sides use, written once.

The shaders get these as ``#define``s (``SHADER_DEFINES``, injected by render/shaders.py
with the binding units of render/bindings.py); the numpy references, the GPU resources
and the layer writer import the same names. ``tests/test_contract.py`` fails when a
shader uses a name that neither defines.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

#: Floor of the compression ratio r: |k| <= 2 pi / (W * MIN_RATIO) (crush).
MIN_RATIO = 0.05
#: The fold law beyond the paper (docs/method.md, "The fold law"; usdwrinkle/method/folds.py):
#: - inextensible: a wave restores, per posed length, the length the cloth has there (its
#:   excess length rho), exactly for the mesh's profile (folds.slope_table);
#: - coarsening: L = W * min(rho ** COARSENING_EXPONENT, COARSENING_MAX). The cloth
#:   referee's folds widen about 1.8x by 32% compression; a steeper law (exponent 2, cap
#:   1.7) matched that but moved the crests, so a = 1 keeps the posed wavelength uniform
#:   and the cap 1.5 keeps the crests stable (docs/method.md, "The fold law"); the cap
#:   falls to 1 where the rest surface curves one way (CURVED_COARSENING below);
#: - room: a fold rises at most FOLD_ROOM over the rate at which the posed normals turn
#:   (FOLD_ROOM of the posed surface's radius of curvature), so that the displaced
#:   surface does not pass through itself.
#: - area: where the mesh is compressed across the wave too (r2 < 1, an elbow's pinch),
#:   the one wave restores the area the cloth has, not only its length along the wave:
#:   its excess length takes r * max(r2, ACROSS_MIN). The referee's sleeves are compressed
#:   both ways in the pinch (the low-passed cloth's larger principal stretch is 0.91 at
#:   the median, 0.74 at the 10th percentile), and their folds kept 0.78-0.82 of the rest
#:   area (docs/physics.md, "The area across"). Where the mesh is stretched across
#:   instead (a squashed pillow's bulging sides), the posed surface holds some of the
#:   cloth's area already, and the surface draws the fold lowered to restore only the
#:   rest: its slope for r * min(r2 / STRETCH_ONSET, ACROSS_MAX) where r2 exceeds
#:   STRETCH_ONSET. Only the drawn height is lowered (FIELD_NORMAL's w); the relaxation
#:   weighs the phases by the whole fold, since weighing them by the lowered one moved
#:   the shirt's crests past their bar. The onset: a wrinkling cloth is stretched across
#:   its folds by itself (the referee's shears, curtains and sleeves by 1-6%), and
#:   counting a stretch from 1 lowered the referee's sheared folds to 0.49-0.76x; from
#:   10%, only an animation's stretch (a squashed pillow's sides, 10-20%) counts, and the
#:   referee's rows stay within 0.03. The pillow drew 1.289 of its rest area where
#:   stretched across by over 10% (1.082 over its compressed region), 1.086 (1.026) now
#:   (docs/physics.md, "The pillow").
COARSENING_EXPONENT = 1.0
COARSENING_MAX = 1.5
#: Curved cloth holds its wavelength: where the rest surface curves one way (a sleeve, a
#: trouser leg, a rounded cushion) tightly enough that its tube's fold wavelength (the
#: curvature law's, scene/params.tube_width) is about W, the cap on the mesh's coarsening
#: falls from COARSENING_MAX to 1 (folds.coarsening_cap) by the product of two terms: W
#: over the tube's wavelength within the window CURVED_COARSENING (in from [0] to [1],
#: out from [2] to [3], smoothsteps; 1 where the curvature law narrows the fallback W),
#: and a smoothstep of how one way the surface curves within
#: ONE_WAY_REACH W of the point (scene/topology.one_way: 1 on a tube or a dome, under 0.3
#: on the pleated curtain sample, whose pleats are folds themselves) from ONE_WAY[0] to
#: [1]. The converged referee's sleeves (5-10 cm, silk and cotton) and the simulated shirt
#: elbow keep their material wavelength while the compression doubles (docs/physics.md,
#: the elbow's fold table); coarsening them moved the bending 10 cm cotton sleeve's crests
#: 2.09x the cloth's (bar 1.5x). The shirt sample's sleeve (radius 0.39 m, W 0.1, its
#: tube's 0.15) keeps its coarsening: uncoarsened, its coarse elbow drew 1.13 of its rest
#: area. W far beyond the tube's (an authored look; the shirt at W 0.28, 1.85x its tube's)
#: is not the tube law's fold and coarsens: uncoarsened, that shirt's elbow folds were too
#: fine for its 2048-texel maps, and Cycles decoded them 40 degrees off at p99 (bar 3).
#: Painting coarsens up to the same cap (anchor.painted_wavelength): a gather that
#: coarsened past it made the painted forearm's crests jump at the paint's edge. Two
#: gates that read the curvature along the crests (a tube's, not a pleat's) switched
#: with the turning direction and moved the crests (bend 1.89x, held 3.4x), or, frozen
#: where the fold formed, coarsened most of the sleeve (bend 2.12x): docs/method.md.
#: The window's lower edge: the referee's 25 cm cotton sleeve (W 10.2 cm, the cotton
#: preset until 2026-12-06, 0.84 of its tube's 12.2) folds at 7.9-9.4 cm through its
#: bend, not coarsening; at (0.75, 0.9) its cap was 1.19 and its wavelength 1.32x the
#: cloth's, at (0.68, 0.8) 1 and 1.07x (at cotton's 9.5 cm since, 0.78 of its tube's,
#: 1.04x). The shirt's sleeve lies below 0.68 throughout (its cap stays 1.5); the pillow's
#: cap fell at 130 of its 1202 points (mean 1.390 -> 1.376, misfit 0.600 -> 0.612), CesiumMan's at
#: 4 of 3273, no other sample stage's (2026-12-03).
CURVED_COARSENING = (0.68, 0.8, 1.2, 1.5)
ONE_WAY = (0.5, 0.9)
ONE_WAY_REACH = 2.0
#: The slack's onset (crush.glsl excess_of, folds.restored): folds begin at a compression
#: of c (wrinkle:slack) and restore the whole rest length from SLACK_RAMP c on, a
#: smoothstep between. The referee's curtains buckle at once, and at their first phase
#: (8%) stand 0.71-0.78x the cloth's height at matched W. A narrower ramp lifts that
#: (2.5: 0.77-0.85x; 2: 0.89-0.98x) but moves no row's worst case (the curtains' tallest
#: heights are at 32-48%), pushes the cotton curtain's onset wavelength past its bar
#: (1.30x -> 1.31x at 2.5), and costs the crests' stability near the onset (the painted
#: shirt 1.1% of its pixels under a 0.01 degree change at 3, 1.5% at 2.5, 1.9% at 2, bar
#: 2%; CesiumMan 12-14% under 0.1 degrees at 1.5, bar 5%): docs/physics.md, the heights
SLACK_RAMP = 3.0
#: The drawn folds' slack, a share of wrinkle:slack c (crush.glsl fold, folds.restored):
#: the folds are drawn from a compression of DRAWN_SLACK c on (restoring all from
#: SLACK_RAMP DRAWN_SLACK c), while the crests are set, and the waves coarsen, by the folds
#: beyond c alone (the relaxation weighs the phases by the law with c: FIELD_LENGTH's yz).
#: A fold between the two takes its phase from its neighbours'. The referee's cloth
#: buckles at once: with the folds drawn from c (the same share as the crests', 1) the
#: curtains stood 0.71-0.80x its height at their first phase (8%); a lower c for both
#: made the crests tip under a 0.1 degree change of a joint (the shirt 13 of 32 draws
#: over the 5% bar at c = 0.045, CesiumMan 17 of 32 at 0.04). At 0.6 (2026-12-07): the
#: onsets 0.99-1.11x, every draw holds (docs/physics.md, "Folds drawn before the crests
#: settle").
DRAWN_SLACK = 0.6
FOLD_ROOM = 0.5
#: Deepening (docs/method.md, "Deepened pleats"; method/deepen.py): where the room lowers
#: a fold, the length the lowered fold does not draw goes into an offset of the surface
#: along its normal, away from its centre of curvature along the wave (the referee's
#: cloth sharpens the pleats that a low-pass rounds): c = (D - 1) / |kappa|, D the full
#: fold's length over the lowered fold's, kappa the posed surface's normal curvature
#: along the wave; at most DEEPEN_CAP times the full fold's height, and at most a |kappa|
#: a / FOLD_ROOM of it, so that it fades where the surface turns flat along the wave.
#: Measured (docs/physics.md, "Deepening the pleats where the room is short"; cap: held
#: 25 cm sleeve's crest motion over the cloth's, the leather curtain's correlation and
#: area (its 2 cm run), the curtain sample's area): 0: 1.01x, 0.74, 0.729, 0.627; 0.6:
#: 0.99x, 0.91, 0.994, 0.911; 0.75: 0.99x, 0.91, 1.02, 0.990; 1: 0.99x, 1.026 (the
#: curtain sample). So 0.75: the curtain sample keeps its area (bar 0.95) and no other
#: bar moved. On the leather curtain's 1 cm run, judged since 2026-12-06: 0.82, 0.870 at
#: 0; 0.79, 0.938 at 0.75 (docs/physics.md, "The leather curtain at 1 cm"). Until the crest
#: damping became a play (2026-12-06) the held sleeve's crests moved 1.35-1.54x the
#: cloth's from cap 0.7 on, in one frame's catch-up after the arm stopped, and the cap
#: was 0.6.
DEEPEN_CAP = 0.75
ACROSS_MIN = 0.7
ACROSS_MAX = 1.0 / ACROSS_MIN
STRETCH_ONSET = 1.1
#: The blend keeps the interpolated amplitude where the corner waves drift out of phase
#: inside a coarse triangle (wave.glsl, blend_corner_waves): it is divided by its
#: coherence |sum b a e^(i theta)| / sum b a, at least this (so at most 2x where the
#: corners cancel). Measured choice (docs/method.md, "Coherence"): the referee's cotton
#: sleeve kept 0.834 of its rest area where compressed without it, 0.887 with it.
BLEND_COHERENCE_FLOOR = 0.5
#: The length law (docs/method.md, "The cloth's length"; shaders/length.glsl): no ring of
#: the wrinkled surface draws more than the cloth's rest area around it. Per vertex, over
#: the triangles around it, the blend's surface is sampled with its exact gradient; where
#: the ring is compressed beyond the slack, the vertex's folds (both systems' amplitudes)
#: are scaled by the largest s <= 1 at which the ring draws at most the rest area the
#: slack leaves, ramped in with the slack's ramp. A blend that is one plane wave over the
#: ring (the analytic cases) keeps s = 1. LENGTH_LAW 0 turns it off.
LENGTH_LAW = 1
#: samples per vertex at most (over its whole ring: each triangle gets m x m, m from its
#: waves' phase advance, 4 a wavelength, and at most what this budget leaves it)
LENGTH_SAMPLES = 192
#: a blend whose gradient is that of its corners carrying one wave, to this relative
#: difference over the ring (RMS), is that plane wave: its scale is exactly 1 (rounding
#: of the corners' phases differs by ~1e-7)
LENGTH_SNAP = 1e-4
#: a ring may draw this much more than its allowance: its samples' own error (4 a
#: wavelength) is no reason to scale a fold (0.03 left the shirt 0.965 of its rest area
#: where compressed; none cut it to 0.952, and a calibration of the samples on a plane
#: wave of the blend's slope to 0.922-0.939)
LENGTH_TOLERANCE = 0.03
#: a vertex whose drawn folds are less steep than this (a|k|: they draw a 1e-8 of the
#: length) keeps scale 1
LENGTH_MIN_SLOPE = 1e-4
#: Newton steps of the scale's solve (each kept inside its bracket, else bisected)
LENGTH_STEPS = 16
#: Irregularity (wrinkle:irregularity, docs/method.md "Irregular folds"; beyond the
#: paper): three smooth fields N = (N_x, N_y, N_z) over the rest surface. A corner whose
#: wave runs along the rest-space unit direction u has its phase moved by beta u . N:
#: neighbouring corners, whose directions agree, move alike, so the blend loses nothing,
#: and a wave's arbitrary sign ((k, phi) or (-k, -phi), u or -u) draws the same folds.
#: The gradient changes the local wave vector k' = k + beta grad (u . N): folds of
#: unequal width whose crests meander, each corner's amplitude scaled by |k| / |k'|
#: (within IRREGULARITY_FACTOR_MIN..MAX) so that the slope, and with it the length the
#: fold law restores, stays the law's: the wider folds stand taller.
#: Each N_i = sqrt(2 / m) sum_j sin(s_ij u_j . X / Lambda * 2 pi + psi_ij) over the m = 6
#: axes u_j of the icosahedron (a spherical 5-design: the directional derivative's variance
#: is the same along every direction), at relative scales s_ij (root mean square 1; each
#: field takes them in another order) and phases psi_ij; Lambda = IRREGULARITY_SCALE x the
#: mesh's median width W. The derivative of u . N along a direction then has the root mean
#: square 2 pi / (sqrt(3) Lambda), so beta = IRREGULARITY_GAIN x the irregularity gives
#: the local wave number a coefficient of variation equal to the irregularity where the
#: material wavelength is W.
IRREGULARITY_SCALE = 3.0
IRREGULARITY_GAIN = 3.0 * 3.0 ** 0.5
IRREGULARITY_FACTOR_MIN = 0.5
IRREGULARITY_FACTOR_MAX = 2.0
IRREGULARITY_FIELDS = 3
_GOLDEN = (1.0 + 5.0 ** 0.5) / 2.0
_AXES = ((0.0, 1.0, _GOLDEN), (0.0, -1.0, _GOLDEN), (1.0, _GOLDEN, 0.0),
         (-1.0, _GOLDEN, 0.0), (_GOLDEN, 0.0, 1.0), (-_GOLDEN, 0.0, 1.0))
IRREGULARITY_TERMS_PER_FIELD = len(_AXES)
_SCALES = (1.0, 0.8, 1.25, 0.9, 1.12, 0.78)
_RMS = (sum(s * s for s in _SCALES) / len(_SCALES)) ** 0.5
_PHASES = ((0.3, 2.1, 4.4, 1.2, 5.6, 3.3), (5.1, 0.7, 2.9, 4.0, 1.8, 6.0),
           (2.4, 4.9, 0.1, 3.7, 1.1, 5.3))
#: the fields' terms, field by field: (s_ij u_j, psi_ij), s_ij u_j in cycles per Lambda
IRREGULARITY_TERMS = tuple(
    (tuple(_SCALES[(j + 2 * i) % len(_SCALES)] / _RMS * c / (1.0 + _GOLDEN ** 2) ** 0.5
           for c in axis), _PHASES[i][j])
    for i in range(IRREGULARITY_FIELDS) for j, axis in enumerate(_AXES))
#: the most a painted gather adds: |q| = 1 gathers the cloth to half its length (the
#: paper's r = 1 - |q|^2 would reach 1 / r_min = 20 times it, folds 7 W tall)
PAINT_GATHER_MAX = 1.5
#: crush starts a wave from the paint's stripe pattern (method/anchor.py) where its rest
#: direction is within 45 degrees of the painted q: |cos| at least this
ANCHOR_ALIGNED = 0.7071
#: samples of the length-exact slope table: a|k| at u = sqrt(rho^2 - 1) = i * SLOPE_STEP
SLOPE_SAMPLES = 64
SLOPE_STEP = 0.3125
#: A tiny floor on the relax weights keeps arg() defined where no vertex is wrinkled. It is
#: a length (the amplitudes' units), so it stays far below any amplitude a shot in metres
#: draws: with the cold start's weighted mean (relax.glsl) 1e-7 moved the fitted heights
#: of a cloth in metres by up to 0.26% from the same cloth in centimetres (the any-units
#: test in tests/test_crush_relax.py, bar 0.1%); 1e-12 keeps them within it.
WEIGHT_FLOOR = 1e-12
#: A ring neighbour's wave pulls a vertex's phase (relax's steps, its seed, its fit) by
#: its amplitude (plus WEIGHT_FLOOR) times smoothstep(0, RELAX_ALIGNED, |cos|) of the
#: angle between their wave vectors: fully within 78 degrees, not at all at right angles.
#: Crests that cross at right angles have no phase to agree on, and the sign test that
#: pairs (k, phi) with (-k, -phi) is a coin toss there: on the shirt a 0.01 degree joint
#: change flipped it for a new wave beside a strong one at 88 degrees, and the relaxation
#: settled 2-3 rad apart (docs/method.md, "Sensitivity"). At 0.5 (fully within 60
#: degrees) the shirt's displaced geometry drew 1.138 of its rest area where uniaxially
#: compressed (bar 1.05; 1.036 at 0.2): its blend, divided by the corners' coherence,
#: grew where they no longer agreed.
RELAX_ALIGNED = 0.2
#: A point without a wave (its relaxed phase is what the floor weights make of its
#: neighbours', and a wave that grows in there starts from it) is pulled by a neighbour's
#: wave only along its own direction: smoothstep(FLOOR_ALIGNED_FROM, FLOOR_ALIGNED, |cos|),
#: fully within 18 degrees, not at all beyond 46. Beside the painted loop, waves at 84-88
#: degrees (|cos| 0.03-0.1) pulled the elbow's bare points with a weight of their
#: amplitude times 0.06-0.4, a million times the floor, along a drift that means nothing
#: at right angles; the region's first waves inherited that and a 0.01 degree change
#: placed them 0.2-0.3 rad apart (docs/method.md, "Three couplings"). Over 64 random
#: axes the loop's worst draw was 2.9% at (0.3, 0.7), 1.4% at (0.5, 0.9), 1.1% here.
FLOOR_ALIGNED_FROM = 0.7
FLOOR_ALIGNED = 0.95
#: The fit of the wave to the relaxed phases (relax.glsl's FIT, reference/relax.fit)
#: needs two independent tangent directions in a vertex's wrinkled ring: the tangent
#: normal equations' determinant over their trace squared (at most 1/4, a ring as wide as
#: long) above FIT_CONDITION, fully trusted from twice that.
FIT_CONDITION = 0.01
#: ... and it fades out where it would make a wave shorter by more than 0.75 x this
#: factor, and is gone at it (beyond, the phases there are not one wave). It only makes
#: waves shorter (the phase history's twist under coarsening), fading in from 1x to
#: FIT_ONSET: lengthening them too moved the 5 cm sleeve's elbow crests 4.1x the
#: referee's instead of 3.0x (docs/method.md, "The fit").
#: Ring edges along which the wave advances more than pi / 2 count less, beyond pi not at
#: all (the ring does not sample the wave: one far finer than the mesh is not fitted).
FIT_RANGE = 2.0
FIT_ONSET = 1.05
#: Mobility (relax.glsl, reference/relax.mobility): with phase history a vertex's relaxed
#: phase moves from its seed by min(delta / MOBILITY_PHASE + turn / MOBILITY_TURN, 1) of
#: the way the Jacobi steps take it. delta and turn (radians) are the largest changes
#: since the previous grid frame of the phase difference its ring's material waves ask
#: for along an edge, split into the part the wave number's change asks (the folds
#: coarsening: delta) and the part the direction's turn asks (turn). Unchanged input
#: keeps the phases. A direction that turns a little (a nearly isotropic strain's
#: wander; crest damping's catch-up after a pose stopped, before it became a play) moves
#: them 30x less than a wave number that changes as much: the referee's held sleeves
#: crept 4.4x and 1.5x the cloth's when both counted alike, 1.2x and 0.6x now
#: (docs/method.md, "Mobility"); since curved cloth holds its wavelength
#: (CURVED_COARSENING), 1.09x and 1.06x (at 30: 1.08x and 1.13x, the shirt's misfit 0.529
#: against 0.510).
MOBILITY_PHASE = 0.1
MOBILITY_TURN = 3.0
#: ... less a dead band: m = min(max(x - MOBILITY_DEADBAND, 0) / (1 - MOBILITY_DEADBAND),
#: 1) with x = delta / MOBILITY_PHASE + turn / MOBILITY_TURN, so a change of an edge's
#: phase difference under 0.005 rad a frame (cloth that creeps by a fraction of a
#: millimetre a frame after its pose stops) keeps the phases: the referee's 25 cm sleeve
#: held still crept 1.90x the cloth's, 1.18x with it, and the other held sleeves 0.13-0.98x
#: (docs/method.md, "A dead band").
MOBILITY_DEADBAND = 0.05
#: ... over the ring edges to neighbours with a wave: an edge counts by smoothstep(0,
#: MOBILITY_RING, a_j / a_i), a_j the smaller of the neighbour's amplitudes now and the
#: frame before, a_i the vertex's. A neighbour without a wave has the direction of its
#: strain's noise (a 0.01 degree joint change turned the shirt's uncompressed points
#: beside its painted cuff by up to 90 degrees, and took its painted waves' mobility from
#: 0 to 1 and back: the crests moved on 2.2% of the wrinkled pixels on an H200, where
#: the bar is 2%; docs/method.md, "Sensitivity"); the relaxation barely feels it
#: (WEIGHT_FLOOR), so neither may the mobility.
MOBILITY_RING = 0.25
#: A frame with no phase history starts from the material-anchored phase and relaxes
#: this many times longer (render/delegate.py, reference/relax.py).
COLD_START_FACTOR = 4
#: Relief (render --relief, draw.glsl's RELIEF): the view ray is marched down through the
#: folds in steps no longer than the height it stands above them over the bound of their
#: slope, and no shorter than 1 / RELIEF_MAX_STEPS of the height range; the first crossing
#: is refined by RELIEF_SECANT secant steps. A ray at a grazing angle is taken at
#: RELIEF_MIN_COSINE, and the relief fades out from there to RELIEF_FADE (towards the
#: silhouette, where the ray would run far), so its march stays bounded. The heights
#: and slopes are bounded over the fragment's triangle times RELIEF_BOUND_MARGIN (for its
#: neighbours' folds); the ray walks at most RELIEF_HOPS triangles a step. Where the seen
#: point jumps from fold to fold, the texture's footprint is held within RELIEF_FOOTPRINT
#: times the coarse surface's. A multisample's march starts where the centre's knew that
#: no ray within RELIEF_SAMPLE_REACH half pixel diagonals of it meets the folds above
RELIEF_MAX_STEPS = 32.0
RELIEF_SECANT = 2
RELIEF_MIN_COSINE = 0.5
RELIEF_FADE = 0.2
RELIEF_FOOTPRINT = 4.0
RELIEF_HOPS = 3
RELIEF_BOUND_MARGIN = 1.25
RELIEF_SAMPLE_REACH = 1.5
#: The horizon (draw.glsl's bend): a normal that the folds bend is turned back towards the
#: eye until its cosine with the view direction is at least HORIZON_COSINE (or the coarse
#: normal's own, where that is less). A point seen on a surface faces the eye; a bent
#: normal that faced away was shaded with the preview surface's specular cut off at
#: n.e = 0 (its limit above is not 0), dark beads and bands on the flanks that face away
#: (the pillow's front at frame 24: 8% of its pixels; the zeppelin's 12%). At 0 the cut
#: stays on the horizon; 0.1 puts those flanks where their neighbours are. Measured
#: against the displaced geometry (bake --geometry) at frame 24, 540 px, the luminance
#: correlation of the plain draw: pillow 0.549 -> 0.640, zeppelin 0.615 -> 0.647, pull
#: 0.763 -> 0.778, shirt 0.8445 -> 0.8444 (docs/method.md, "The horizon").
HORIZON_COSINE = 0.1
#: Lights the draw pass sums (more are ignored, with a warning).
MAX_LIGHTS = 8
#: Anisotropic filtering of textures: Hydra's GL samplers ask for 16 (hgiGL/sampler.cpp),
#: so a texture seen at a grazing angle is as sharp as in usdview; the draw pass takes at
#: most this many trilinear probes per lookup (draw.glsl: anisotropic_probes)
TEXTURE_ANISOTROPY = 16.0
#: Texels per joint in the joints table (skin.glsl documents the layout).
JOINT_TEXELS = 9
#: UDIM tiles a normal map may have: u and v in 0..9, tiles 1001..1100 (draw.glsl
#: looks each tile's texture layer up in a table of this many entries).
UDIM_TILES = 100
#: the UDIM layer table's first entry when the normal map is one texture that repeats,
#: not a UDIM set (render/resources.py writes it, draw.glsl tests it)
UDIM_REPEAT = -2

#: Per-vertex fields table (crush writes it; relax and draw read it): FIELD_TEXELS RGBA
#: texels per vertex, in this order:
#:   normal     xyz: posed unit normal (local space); w: 0 if the 1-ring is not usable,
#:              else 1 + the share of the wave's amplitude the surface draws (below 1
#:              where the mesh is stretched across the wave beyond STRETCH_ONSET)
#:   wave       xyz: wave vector k (local space, posed); w: amplitude h
#:   direction  xyz: rest-space unit direction d of strongest compression; w: r
#:   wave2      the second wave system (biaxial compression): k2, h2 (h2 = 0: none)
#:   direction2 xyz: rest-space direction of the other principal stretch; w: r2
#:   deepen     x: the offset o along the normal (DEEPEN_CAP; scene units, local
#:              space); yzw: its gradient over the posed surface (local space)
#:   length     x: the length pass's scale of the drawn folds, both systems (1: none;
#:              docs/method.md, "The cloth's length"); yz: the folds the relaxation
#:              weighs each system's phase by (the law with wrinkle:slack itself, where
#:              the drawn folds take DRAWN_SLACK of it; a frame drawn from a bake: its
#:              amplitudes); w: 0
#: Phases are per system too: the phase tables are RG (x: system 1, y: system 2).
FIELD_TEXELS = 7
FIELD_NORMAL_TEXEL = 0
FIELD_WAVE_TEXEL = 1
FIELD_DIRECTION_TEXEL = 2
FIELD_WAVE2_TEXEL = 3
FIELD_DIRECTION2_TEXEL = 4
FIELD_DEEPEN_TEXEL = 5
FIELD_LENGTH_TEXEL = 6
#: floats per vertex in the fields table
FIELD_FLOATS = 4 * FIELD_TEXELS
#: wave systems per vertex: the strongest compression (or tension), and the second
#: compression of a biaxially compressed patch
WAVE_SYSTEMS = 2

#: Tension wrinkles (Cerda, Ravi-Chandar & Mahadevan, Nature 2002; Cerda & Mahadevan,
#: PRL 2003): wavelength ~ gamma^(-1/4), amplitude / wavelength = sqrt(2 nu) / pi *
#: sqrt(gamma). W is the wavelength at the reference strain (docs/method.md).
TENSION_REFERENCE_STRAIN = 0.1
#: Poisson ratio of the law (a knitted or woven cloth's in-plane response)
TENSION_POISSON = 0.5
TENSION_SLOPE = (2.0 * TENSION_POISSON) ** 0.5 / 3.141592653589793


def glsl_literal(value) -> str:
    """A Python number as a GLSL literal (floats keep their decimal point)."""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int):
        return str(value)
    text = repr(float(value))
    return text if any(c in text for c in ".en") else text + ".0"


#: What every shader gets as #defines.
SHADER_DEFINES = {name: glsl_literal(value) for name, value in (
    ("MIN_RATIO", MIN_RATIO), ("WEIGHT_FLOOR", WEIGHT_FLOOR),
    ("RELAX_ALIGNED", RELAX_ALIGNED), ("FLOOR_ALIGNED_FROM", FLOOR_ALIGNED_FROM),
    ("FLOOR_ALIGNED", FLOOR_ALIGNED), ("MAX_LIGHTS", MAX_LIGHTS),
    ("FIT_CONDITION", FIT_CONDITION), ("FIT_RANGE", FIT_RANGE),
    ("FIT_ONSET", FIT_ONSET), ("MOBILITY_PHASE", MOBILITY_PHASE),
    ("MOBILITY_TURN", MOBILITY_TURN), ("MOBILITY_DEADBAND", MOBILITY_DEADBAND),
    ("MOBILITY_RING", MOBILITY_RING),
    ("TEXTURE_ANISOTROPY", TEXTURE_ANISOTROPY),
    ("RELIEF_MAX_STEPS", RELIEF_MAX_STEPS),
    ("RELIEF_SECANT", RELIEF_SECANT), ("RELIEF_MIN_COSINE", RELIEF_MIN_COSINE),
    ("RELIEF_FADE", RELIEF_FADE), ("RELIEF_FOOTPRINT", RELIEF_FOOTPRINT),
    ("RELIEF_HOPS", RELIEF_HOPS), ("RELIEF_BOUND_MARGIN", RELIEF_BOUND_MARGIN),
    ("RELIEF_SAMPLE_REACH", RELIEF_SAMPLE_REACH), ("HORIZON_COSINE", HORIZON_COSINE),
    ("JOINT_TEXELS", JOINT_TEXELS), ("UDIM_TILES", UDIM_TILES), ("UDIM_REPEAT", UDIM_REPEAT),
    ("FIELD_TEXELS", FIELD_TEXELS),
    ("FIELD_NORMAL_TEXEL", FIELD_NORMAL_TEXEL), ("FIELD_WAVE_TEXEL", FIELD_WAVE_TEXEL),
    ("FIELD_DIRECTION_TEXEL", FIELD_DIRECTION_TEXEL), ("FIELD_WAVE2_TEXEL", FIELD_WAVE2_TEXEL),
    ("FIELD_DIRECTION2_TEXEL", FIELD_DIRECTION2_TEXEL),
    ("FIELD_DEEPEN_TEXEL", FIELD_DEEPEN_TEXEL), ("DEEPEN_CAP", DEEPEN_CAP),
    ("FIELD_LENGTH_TEXEL", FIELD_LENGTH_TEXEL), ("LENGTH_LAW", LENGTH_LAW),
    ("LENGTH_SAMPLES", LENGTH_SAMPLES), ("LENGTH_SNAP", LENGTH_SNAP),
    ("LENGTH_STEPS", LENGTH_STEPS), ("LENGTH_MIN_SLOPE", LENGTH_MIN_SLOPE),
    ("LENGTH_TOLERANCE", LENGTH_TOLERANCE),
    ("WAVE_SYSTEMS", WAVE_SYSTEMS),
    ("TENSION_REFERENCE_STRAIN", TENSION_REFERENCE_STRAIN), ("TENSION_SLOPE", TENSION_SLOPE),
    ("COARSENING_EXPONENT", COARSENING_EXPONENT), ("COARSENING_MAX", COARSENING_MAX),
    ("SLACK_RAMP", SLACK_RAMP), ("DRAWN_SLACK", DRAWN_SLACK),
    ("FOLD_ROOM", FOLD_ROOM), ("PAINT_GATHER_MAX", PAINT_GATHER_MAX),
    ("ANCHOR_ALIGNED", ANCHOR_ALIGNED),
    ("ACROSS_MIN", ACROSS_MIN), ("ACROSS_MAX", ACROSS_MAX), ("STRETCH_ONSET", STRETCH_ONSET),
    ("BLEND_COHERENCE_FLOOR", BLEND_COHERENCE_FLOOR),
    ("SLOPE_SAMPLES", SLOPE_SAMPLES), ("SLOPE_STEP", SLOPE_STEP),
    ("IRREGULARITY_FACTOR_MIN", IRREGULARITY_FACTOR_MIN),
    ("IRREGULARITY_FACTOR_MAX", IRREGULARITY_FACTOR_MAX),
    ("IRREGULARITY_COUNT", len(IRREGULARITY_TERMS)),
    ("IRREGULARITY_FIELDS", IRREGULARITY_FIELDS),
    ("IRREGULARITY_TERMS_PER_FIELD", IRREGULARITY_TERMS_PER_FIELD))}
#: the irregularity field's terms as a GLSL array: (2 pi s_j u_j, psi_j)
SHADER_DEFINES["IRREGULARITY_TERMS"] = "vec4[{}]({})".format(
    len(IRREGULARITY_TERMS), ", ".join(
        "vec4({})".format(", ".join(glsl_literal(2.0 * 3.141592653589793 * c)
                                    for c in (*axis, psi / (2.0 * 3.141592653589793))))
        for axis, psi in IRREGULARITY_TERMS))


@dataclass(frozen=True)
class WrinkleFields:
    """One mesh's computed wrinkle fields, read back from the GPU (``read_fields``): what
    the bake writes and the tests compare with the numpy references.

    Attributes
    ----------
    points : (n, 3) float32
        Posed points (local space).
    normals : (n, 3) float32
        Posed unit normals (local space).
    usable : (n,) bool
        The vertex's 1-ring could be fitted.
    wave_vector : (n, 3) float32
        Wave vector k (local space, posed).
    amplitude : (n,) float32
        Amplitude h (scene units): the fold law's, which the relaxation weighs by.
    drawn : (n,) float32
        The share of ``amplitude`` the surface draws (1, less where the mesh is stretched
        across the wave): ``drawn_amplitude`` is what the draw pass, the maps, the
        geometry and the bake's primvar carry.
    direction : (n, 3) float32
        Rest-space unit direction of strongest compression.
    compression : (n,) float32
        Compression ratio r in [MIN_RATIO, 1].
    phase : (n,) float32
        Relaxed phase (radians).
    anchor_phase : (n,) float32
        The material-anchored phase crush starts relax from.
    wave_vector2, amplitude2, direction2, compression2, phase2, anchor_phase2
        The second wave system (biaxial compression; amplitude2 = 0 where there is none).
    wavenumber : (n,) float32
        The material wave number 2 pi / L of the first system (rest space; the anchored
        phase's), which relax's mobility reads from the wave state; 0 where not computed.
    offset : (n,) float32
        The deepened pleats' offset along the normal (scene units; DEEPEN_CAP).
    offset_gradient : (n, 3) float32
        Its gradient over the posed surface (local space).
    length_scale : (n,) float32
        The length pass's scale of the drawn folds, both systems (1: none; docs/method.md,
        "The cloth's length"): ``drawn_amplitude`` and ``drawn_amplitude2`` carry it,
        ``amplitude`` and ``amplitude2`` are the fold law's as drawn (with the drawn folds'
        slack, DRAWN_SLACK of wrinkle:slack).
    weight, weight2 : (n,) float32
        The folds the relaxation weighs each system's phase by: the fold law with the
        crests' slack (wrinkle:slack itself), 0 where the compression is within it.
    """

    points: np.ndarray
    normals: np.ndarray
    usable: np.ndarray
    wave_vector: np.ndarray
    amplitude: np.ndarray
    drawn: np.ndarray
    direction: np.ndarray
    compression: np.ndarray
    phase: np.ndarray
    anchor_phase: np.ndarray
    wave_vector2: np.ndarray
    amplitude2: np.ndarray
    direction2: np.ndarray
    compression2: np.ndarray
    phase2: np.ndarray
    anchor_phase2: np.ndarray
    wavenumber: np.ndarray
    offset: np.ndarray
    offset_gradient: np.ndarray
    length_scale: np.ndarray
    weight: np.ndarray
    weight2: np.ndarray

    @classmethod
    def from_tables(cls, posed: np.ndarray, fields: np.ndarray, phase: np.ndarray,
                    anchor_phase: np.ndarray, damped: np.ndarray | None = None
                    ) -> WrinkleFields:
        """From the read-back tables: posed (n, 4), fields (n * FIELD_TEXELS, 4), phases
        (n, WAVE_SYSTEMS), and the wave state's damped table (n, 4; w: the wave number)."""
        texels = np.asarray(fields, np.float32).reshape(-1, FIELD_TEXELS, 4)
        normal = texels[:, FIELD_NORMAL_TEXEL]
        wave = texels[:, FIELD_WAVE_TEXEL]
        direction = texels[:, FIELD_DIRECTION_TEXEL]
        wave2 = texels[:, FIELD_WAVE2_TEXEL]
        direction2 = texels[:, FIELD_DIRECTION2_TEXEL]
        deepen = texels[:, FIELD_DEEPEN_TEXEL]
        length = texels[:, FIELD_LENGTH_TEXEL]
        phase = np.asarray(phase, np.float32).reshape(-1, WAVE_SYSTEMS)
        anchor = np.asarray(anchor_phase, np.float32).reshape(-1, WAVE_SYSTEMS)
        return cls(points=posed[:, :3].copy(), normals=normal[:, :3].copy(),
                   usable=normal[:, 3] > 0.5, wave_vector=wave[:, :3].copy(),
                   amplitude=wave[:, 3].copy(),
                   drawn=np.where(normal[:, 3] > 0.5, np.clip(normal[:, 3] - 1.0, 0.0, 1.0),
                                  1.0).astype(np.float32),
                   direction=direction[:, :3].copy(),
                   compression=direction[:, 3].copy(), phase=phase[:, 0].copy(),
                   anchor_phase=anchor[:, 0].copy(), wave_vector2=wave2[:, :3].copy(),
                   amplitude2=wave2[:, 3].copy(), direction2=direction2[:, :3].copy(),
                   compression2=direction2[:, 3].copy(), phase2=phase[:, 1].copy(),
                   anchor_phase2=anchor[:, 1].copy(),
                   wavenumber=(np.zeros(len(posed), np.float32) if damped is None else
                               np.asarray(damped, np.float32).reshape(-1, 4)[:, 3].copy()),
                   offset=deepen[:, 0].copy(), offset_gradient=deepen[:, 1:].copy(),
                   length_scale=length[:, 0].copy(), weight=length[:, 1].copy(),
                   weight2=length[:, 2].copy())

    @property
    def drawn_amplitude(self) -> np.ndarray:
        """The first system's amplitude as the surface draws it (``amplitude`` times
        ``drawn`` and ``length_scale``): what a bake writes as primvars:wrinkle:amplitude."""
        return (self.amplitude * self.drawn * self.length_scale).astype(np.float32)

    @property
    def drawn_amplitude2(self) -> np.ndarray:
        """The second system's amplitude as the surface draws it (``amplitude2`` times
        ``length_scale``): what a bake writes as primvars:wrinkle:amplitude2."""
        return (self.amplitude2 * self.length_scale).astype(np.float32)

    def arrays(self) -> dict:
        """Name -> array, in field order."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
