//! The adaptive quad-tree of Widmer et al. 2015, "An Adaptive Acceleration Structure for
//! Screen-space Ray Tracing" (§3-§4), as a [`crate::ScreenTracer`].
//!
//! - [`node`]: the 64-bit node of §3.4 (plane / AABB, tag in the sign bit);
//! - [`build`]: [`QuadTree`], one layer — per-pixel planes as leaves (§3.2) and bottom-up
//!   adaptive pruning with the three conditions and the least-squares proxy plane (§3.3);
//! - [`merge`]: one pruning step (proxy plane or conservative AABB);
//! - [`traverse`]: the stackless traversal of §4 (exact plane hits, child by entry
//!   quadrant, successor by exit edge, restart `findMSB((Qx^Qx*)|(Qy^Qy*))` levels up —
//!   Frisken & Perry 2002 — crack dilation, occlusion-volume extrusion, hard step bound);
//! - [`cascade`]: [`QuadTreeTracer`], all layers of one reference view, with the occlusion
//!   handling of §4.1 in the two [`LayerMode`]s, and the derivation that makes cascading
//!   exact.
//!
//! **Coordinates.** Construction and tracing happen in the unit cube of [`crate::UnitCube`]
//! (§3.2). The traversal works in *grid* units (`X = x W`, `Y = y H`, pixel `(i, j)` is the
//! square `[i, i+1] x [j, j+1]`) for the node rectangles and in cube units for plane tests.
//! The ray is the straight cube segment `P(s) = p0 + s (p1 - p0)`, `s ∈ [0, 1]`, of
//! [`crate::UnitCube::clip_ray`]; results map back with [`crate::CubeSegment::world_t`].
//!
//! **Levels.** Level 0 holds one node per pixel; level `l` nodes cover `2^l x 2^l` pixels.
//! The number of levels is `min(max_levels, ceil(log2 max(W, H)) + 1)` (§3.2: "our
//! implementation caps it to 9 levels"); the top level then has several nodes. Every level is
//! one flat row-major array; the image is padded to a multiple of `2^(levels-1)` with empty
//! nodes, so non-power-of-two sizes need no special case.

//! **API.** [`QuadTreeTracer::build`] (all layers of a view; `build_ms`, `bytes`,
//! `unsafe_pixels`, `trace_layers` = result + number of layers traversed) implements
//! [`crate::ScreenTracer`]; [`QuadTree::build`] builds one layer (`bytes`, `node_count`,
//! `plane_node_count`, `effective_planes` = its brute-force twin).
//!
//! **Deviations from / additions to the paper** (its supplement is not public):
//! - the plane word stores `z_c` (the plane's `z` at the node centre) instead of an
//!   `-(P·N)` offset, and two flag bits in its lowest mantissa bits ([`node`]);
//! - the two f16 of a plane node are the plane's `z` slopes across the node's footprint
//!   instead of `N.x`, `N.y`: reconstructing `N.z` made grazing planes vertical in the cube
//!   ([`node`], measured there);
//! - default normals are the G-buffer's ([`QuadTreeOptions::normals`]);
//! - the distance-adaptive thresholds of §6 are our definition ([`QuadTreeOptions::adaptive`]);
//! - crack dilation extends flagged planes *backwards along the ray* by
//!   [`QuadTreeOptions::crack_dilation`] pixels (an extra option field);
//! - inpainting reports the point [`INPAINT_DILATION_PX`] pixels before the occlusion entry;
//! - cascading is made exact by trigger depths for "unsafe" pixels and by never merging over
//!   them ([`cascade`], with the proof);
//! - the traversal starts at the level matching the segment's screen extent instead of the
//!   root (same result, [`traverse`]);
//! - every level is stored in full (pruned subtrees stay in the arrays but are never
//!   visited), so [`QuadTree::bytes`] is the padded pyramid (8 bytes x ~4/3 x padded
//!   pixels), while [`QuadTree::node_count`] counts the reachable nodes; a side array of one
//!   byte per pixel (the level of the pixel's effective plane node, for the traversal's
//!   start) is not counted there;
//! - construction runs on the CPU, in parallel over rows per level (rayon).

//!
//! **Speed: what we tried** (atrium 1600x900, stereo eye 3.25 cm beside the reference eye,
//! 1 layer, default settings; `examples/quadtree_speed.rs`, which times every method on the
//! same 1.44 M rays in *thread CPU time*, best of 7 interleaved rounds — wall-clock figures
//! on the shared 2-core machine varied by 2-3x between identical runs):
//!
//! | variant | quad-tree ns/ray | DDA (16 steps) ns/ray | quad-tree / DDA speed |
//! |---|---|---|---|
//! | before (commit 9cc0d18) | 204 | 130 | 0.64 |
//! | after (all changes below) | 178-206 | 128-155 | 0.70-0.75 |
//!
//! - `half`'s `f16::to_f32` dispatches at run time (F16C detection) to an out-of-line
//!   function: two calls per plane test that forced the loop state to be spilled. Replaced by
//!   the exact branch-free [`node::f16_bits_to_f32`] (bit-identical, tested over all finite
//!   halves). Gain: within the ±10 % noise.
//! - Counters of [`crate::TraceStats`] kept in registers and written once per layer; the
//!   successor across the exit edge computed branch-free; `trace_layer` inlined into the
//!   cascade loop (its `LayerEvents` result was returned through memory). Gain: within noise.
//! - Per-ray start: `perf annotate` attributes ~30 % of the tracer's samples to the start
//!   (the two `cell` floors and the plane-ancestor check, one node load per level above the
//!   start level, each from a different level array) and ~10 % to `RaySetup::new`'s
//!   divisions. The ancestor check now stops at [`QuadTree::plane_top`], the highest level
//!   holding a plane (exact); on atrium planes reach level 7 of 9, so it saves one load and
//!   no measurable time. Fitting `ns/ray = a + b nodes/ray` to the ipd 0.065 / 0.3 runs
//!   (noisy, two points) gives a ≈ 150-175 ns fixed per ray (the f64 clip's ~30 ns included)
//!   and b ≈ 8-16 ns per node for the quad-tree, against a ≈ 50 ns and b ≈ 6 ns per step
//!   for the DDA: on short rays the quad-tree's per-ray set-up weighs as much as its
//!   per-node work.
//! - The baselines' f32 cube clip instead of the f64 [`crate::UnitCube::clip_ray`]
//!   ([`QuadTreeTracer::with_f32_clip`], default off): the f64 clip costs ~28-30 ns per ray
//!   alone (measured), yet the f32 clip gained nothing measurable (0.96-1.16x, noise), and it
//!   is **not exact**: a ray lying exactly on a pixel boundary (test `quadtree_edge.rs`)
//!   lands on the other side after f32 rounding and hits a different plane than the f64
//!   brute-force twin. Kept opt-in, off.
//! - Not the limit: the number of visited nodes (3.6 per ray against the DDA's 12.7 steps),
//!   node bytes (8: a cache line holds 8 nodes of a level row) or the clip alone. Outside
//!   the start block the samples are spread evenly over the loop body (no line above ~2 %):
//!   per node the traversal takes 3-5 data-dependent branches (plane or box, hit or miss,
//!   descend or advance, exit edge x or y, level jump) that a DDA step does not. On the
//!   short epipolar segments of a 6.5 cm stereo baseline the DDA finishes in ~13
//!   predictable steps, so the quad-tree's lower node count does not pay off; at a 30 cm
//!   baseline (DDA 54.7 steps per ray) the quad-tree (6.6 nodes per ray) is 1.6-1.7x faster
//!   than the DDA.
//!
//! **Session 3: instruction counts and the cube's near plane.** `valgrind --tool=callgrind
//! --branch-sim=yes --toggle-collect='*profile_trace*'` on `quadtree_speed -- 0.065
//! --profile quadtree` (every 4th stereo ray, 360,000 rays; instruction counts are
//! repeatable on the loaded machine, unlike time): **1754 instructions and 3.6 branch
//! mispredictions per ray** before (≈ 600 cycles at ~3 IPC: instructions, not
//! mispredictions, are the cost) — f64 clip ~360, start (two `cell`s, start level,
//! ancestor check) ~150, cascade/result mapping ~130, the loop ~1100 over 4.6 iterations
//! (~100-120 instructions per node). Changes, each kept exact (all exactness tests pass):
//!
//! | change | instructions / ray | mispredicts / ray |
//! |---|---|---|
//! | before | 1754 | 3.57 |
//! | per-pixel plane level ([`QuadTree`] `plane_level`, one `u8` load replaces the plane-ancestor check over the levels above the start) + `RaySetup` without its third division (`1/max(|a|,|b|) = min(1/|a|,1/|b|)` exactly) + clip: direction without the translation column, one reciprocal per end point instead of three divisions, plain compares | 1638 | 4.17 |
//! | branch-free `cell` (tie rule as a per-ray `0/1`, select clamps) | (1660; clip clamps as compares mispredicted: +0.9/ray) | 5.10 |
//! | clip clamps back to branch-free `max`/`min` | **1557 (-11 %)** | **3.53** |
//!
//! With the camera-near cube (`-- 0.065 --near 0.1 --profile quadtree`, 6.9 nodes per ray):
//! 2202 -> 2038 instructions per ray (-7 %), 6.4 mispredicts per ray. For scale, the DDA
//! on the fitted cube (`--profile dda`, 12.8 steps per ray): 1282 instructions and 1.0
//! mispredicts per ray.
//!
//! Thread CPU time (best of 7 interleaved rounds, same process as the baselines):
//! quad-tree 200 -> 186 ns/ray at ipd 0.065 (fitted cube), 245 -> 223 ns/ray with the
//! camera-near cube. What remains is the loop body itself: ~100 instructions per visited
//! node (slab entry/exit on two axes with per-axis zero checks, level-array indirection
//! with bounds checks, integer <-> float conversions of the node rectangle, the plane /
//! box / descend / successor logic) against ~10 for a DDA step. The leaner loop below
//! took part of that.
//!
//! **Session 3b: the leaner loop** ([`traverse`]; results unchanged — all exactness tests
//! pass — and the visit / step counts are identical). Changes: slab entry/exit without the
//! per-node zero-direction check and order select (per-ray near/far sides; an axis with
//! `dg == 0` gets the start pixel's centre as slab origin and `+inf` as reciprocal, which
//! yields exactly the `(-inf, +inf)` slab — common: a horizontal stereo baseline makes every
//! epipolar segment horizontal); node loads with `get_unchecked` under a documented,
//! debug-asserted invariant; one successor bound check (`nx <= (W - 1) >> l` replaces four
//! compares and two level-array loads); `2^l` from exponent bits; a step budget counting
//! down and the box-test / visit counters derived at the end (two loop counters fewer);
//! the box test's `z` interval with min/max and one combined branch. Callgrind
//! (`--profile quadtree`, every 4th ray; instructions and branch mispredictions per ray):
//!
//! | setting | nodes / ray | before (f493b71) | after | MinMax flat | MinMax bilinear | Hi-Z | DDA (200) |
//! |---|---|---|---|---|---|---|---|
//! | ipd 0.065, fitted | 3.6 | 1557 / 3.5 | **1512 / 3.2** | 1832 / 12.1 | 1984 / 12.6 | 1509 / 7.7 | 1282 / 1.0 |
//! | ipd 0.065, near 0.1 | 6.9 | 2038 / 6.4 | **1914 / 3.8** | 2448 / 17.6 | 2596 / 18.1 | 2080 / 10.8 | 12399 / 1.0 |
//! | ipd 0.3, fitted | 6.6 | 1985 / 6.1 | **1868 / 4.7** | 2176 / 15.3 | 2333 / 16.2 | 1965 / 9.7 | 3964 / 1.1 |
//! | ipd 0.3, near 0.1 | 9.5 | 2472 / 8.5 | **2270 / 6.3** | 2638 / 18.7 | 2785 / 19.5 | 2383 / 12.9 | 12231 / 1.0 |
//!
//! In the loop itself (per-instruction counts, `--dump-instr=yes`, near 0.1, ipd 0.065):
//! ~126 -> ~105 instructions per step (7.8 steps per ray: 47 common to every node, +20 for
//! a box test, +34 for a descent, +59 for a successor with its level jump). The rest of a
//! ray's ~1900 instructions is per ray: the exact f64 cube clip (~280), the start (two
//! `cell`s, start level), plane decodes (~60 per plane test, `node_centre`'s two
//! divisions included), hit pixel and result mapping. A lesson: the branch-free descent
//! child choice (`(ex > mid) | (ex == mid & pos)`) saved instructions and mispredictions
//! but was ~15 % *slower* in time — it put the choice on the loop's data-dependency chain
//! (`t_in -> P(t_in) -> child -> next node's slab`), which predicted branches cut; it is
//! back to short-circuit compares. Time (`quadtree_speed -- IPD [--near 0.1] --profile
//! quadtree --time`, all 1.44 M rays, thread CPU time, best of 7, the two builds run
//! alternately, best of 2 runs each; loaded machine, ±10 %): near 0.1: 227 -> 211 ns/ray
//! (ipd 0.065), 269 -> 244 (ipd 0.3); fitted: 178 -> 183 (ipd 0.065), 214 -> 210 (ipd 0.3)
//! — a gain of a few percent at most; the per-node work was not the bottleneck it looked
//! like. Head to head after (`quadtree_speed -- 0.065 --near 0.1 --quick`, same process,
//! interleaved, best of 7): quad-tree 204 ns/ray, 7.2x the minimal artifact-free DDA
//! (254 steps), 1.69x MinMax bilinear, 1.62x MinMax flat, 1.32x Hi-Z (before: 218 ns/ray,
//! 6.7x, 1.64x, 1.56x, 1.24x); at ipd 0.3, near 0.1: 254 ns/ray, 15.7x the minimal DDA
//! (1159 steps), 1.53x / 1.43x MinMax bilinear / flat, 1.20x Hi-Z (before, run at the
//! same time: 251 ns/ray, 1.61x / 1.44x, 1.23x: no change). The 2x bar against MinMax is
//! still missed. MinMax (as implemented: f32 clip, flat mode still bisecting `refine_steps` times
//! on its flat patch) has 3-5x the quad-tree's mispredictions per ray, which is why its
//! time ratio to the quad-tree (1.3-1.6x) exceeds its instruction ratio (1.2-1.4x).
//!
//! **The cube's near plane decides the head-to-head.** With [`crate::CubeNear::Fitted`]
//! (our default: near = half the nearest captured depth, a global empty-space skip that
//! is not in the paper) every stereo ray is a 13-28 px epipolar segment and the DDA needs
//! only 17 steps (minimal artifact-free, below); with [`crate::CubeNear::Camera`]`(0.1)`
//! (Widmer's NDC cube = the camera frustum; `quadtree_speed -- 0.065 --near 0.1`) the rays
//! start at the camera's near plane, the DDA needs 230 steps per ray (254 minimal
//! artifact-free, 200 loses 87 % of the hits — Widmer tuned 200), and the quad-tree
//! (6.9 nodes per ray) is **6.6x the DDA** (bar 4x: met in this setting) and 1.6x / 1.5x
//! Tevs bilinear / flat (bar 2x: missed). "Minimal artifact-free" (`quadtree_speed`
//! module docs): the smallest `max_steps` whose results differ from the converged DDA
//! (`max_steps` 100000) on at most 0.01 % of the rays, found by a sweep and bisection; a
//! capped DDA runs the uncapped one's iterations until the cap, so only truncated rays can
//! differ.
//!
//! **Session 4: latency, not instructions.** Results unchanged throughout (all exactness
//! tests pass; the traversal statistics — visits, box / plane tests, steps, hits — are
//! identical to the last digit). Instructions per ray: `valgrind --tool=callgrind
//! --toggle-collect='*profile_trace*' quadtree_speed 0.065 [--near 0.1] --profile quadtree`
//! (every 4th ray). Time: `quadtree_speed 0.065 [--near 0.1] --profile quadtree --time`
//! (all rays, thread CPU time, best of 7), builds run alternately, best of 5 runs each,
//! loaded machine (±5 %):
//!
//! | change | instr/ray camera | ns/ray camera | ns/ray fitted |
//! |---|---|---|---|
//! | before (fd42ce8) | 1942 | ~201 | ~150 |
//! | both axes' slabs as one 4-lane op (`RaySetup::slabs`; no per-axis `tie`/`far` loads), no finiteness check after the f64 clip (it clamps to [0, 1]), `cell` truncation without saturation code | 1768 | ~197 | |
//! | descent on an axis the ray does not move along: integer test on `floor(o)` instead of a data-dependent float branch | 1802 | ~195 | |
//! | **successor of a ray moving along one axis only: a predicted branch for the exit edge**; start / hit pixel on the other axis from the per-ray cell | 1814 | **~178** | ~150 |
//! | raising the start level to the plane ancestor: a (cold) branch instead of a select on the `plane_level` load | 1826 | ~176 | ~145 |
//! | one layer in cascade mode: the layer traversal inlined with a fixed query | 1671 | ~169 | ~141 |
//! | the successor's top-level cap: a (cold) branch instead of a select | 1692 | ~163 | ~139 |
//!
//! Fitted cube, instructions per ray: 1527 before, 1300 after. The cascade (both layers,
//! `--profile quadtree2`, which takes the general multi-layer path): camera cube 2103 ->
//! 1990 instructions and ~218 -> ~197 ns/ray, fitted cube ~175 -> ~153 ns/ray (same
//! timing protocol).
//!
//! The lesson: on these rays the CPU runs ~3 instructions per cycle and the time was set by
//! dependency chains, not by the instruction count (the first row's -9 % instructions
//! gained ~2 %). The branch-free successor (session 3) put `txo <= tyo` — node index ->
//! int-to-float corner -> slab products -> compare — on the chain to the *next* node's
//! index, ~30 cycles per successor; with a predicted branch the next index (and its node
//! load) is known at once and the loop runs ahead speculatively. Stereo rays of a
//! horizontal baseline have `dg.y == 0` exactly, so the branch never mispredicts there;
//! rays moving along both axes keep the branch-free form (their exit axis is
//! data-dependent). Tried and dropped (slower or no gain, within noise): a 1-layer fast
//! path *before* the chain fixes (+5 % time: spills), per-axis slabs with a sign branch
//! (+2 % instructions), node-centre divisions replaced by a multiplication (timing only:
//! no gain, so the plane decode's latency is not the limit), carrying the node corner as
//! floats across descents (+4 %: a select on the chain), `#[inline]` on
//! `UnitCube::clip_ray` (no gain).
//!
//! Head to head after (`cd crates/screen && cargo run --release --example quadtree_speed
//! -- 0.065 --near 0.1 --quick`, same process, interleaved, best of 7, loaded machine):
//! quad-tree 164.5 ns/ray (6.85 nodes), **1.98x MinMax flat** (325.7 ns), 2.08x MinMax
//! bilinear, 8.04x the minimal artifact-free DDA (254 steps), 6.51x DDA 200, 1.62x Hi-Z
//! (before: 1.56x, 6.46x, 1.28x from 200 / 311 / 1292 / 256 ns); fitted cube (`-- 0.065
//! --quick`): 141.6 ns/ray (3.61 nodes), 1.74x MinMax flat, 1.89x bilinear, 1.35x Hi-Z,
//! 0.93x the DDA (17 steps). The 2x bar against MinMax flat is at the edge in the camera
//! cube (1.95-2.0x over runs) and missed in the fitted cube. Where the remaining ~165 ns go
//! (camera cube, ~1690 instructions): the exact f64 clip ~280 instructions and ~25 ns (its chain of
//! two dependent f64 divisions feeds the start), ray set-up and start ~190, result mapping
//! ~60, the loop ~100 instructions per visited node (7.8 steps), plane tests ~100 each
//! (1.4 per ray); about 3 branch mispredictions per ray remain (callgrind's model: node
//! type 1.3, box hit 1.2, plane hit 0.4), each resolved only after the node load and the
//! slab or plane arithmetic.
//!
//! **Session 5: the per-ray fixed cost.** Results unchanged (all tests pass, debug build
//! included; traversal statistics identical to the last digit). Instructions per ray as in
//! session 4 (callgrind, every 4th ray); time `quadtree_speed 0.065 [--near 0.1] --profile
//! quadtree --time` (all rays, thread CPU time, best of 7), the builds run alternately,
//! best of 3-5 runs each, loaded machine (±5 %):
//!
//! | change | instr/ray camera | ns/ray camera | instr/ray fitted | ns/ray fitted |
//! |---|---|---|---|---|
//! | before (435d5c5) | 1692 | ~162 | 1315 | ~137 |
//! | the start pixel from `s = 0` with an integer tie rule and clamps (`RaySetup::cell0`: ~15 cycles of latency to the start node's index instead of ~45) *alone* | 1653 | ~196 (!) | 1282 | ~150 |
//! | `raise_level` returns `black_box(pl)` *alone* | 1689 | ~166 | | |
//! | **both** (9f0bda3) | **1678** | **~157** | **1298** | **~132** |
//!
//! The second row is the lesson: with fewer instructions and a shorter start chain the
//! loop got ~4 ns slower per visited node, because LLVM had inferred that the cold
//! `raise_level` returns its argument and folded the successor's top-level cap back into a
//! `cmov` on the chain to the next node index (session 4 had made it a branch for exactly
//! that reason). Any edit of the inlined traversal can flip that, so `raise_level` now hides
//! its identity behind `black_box`; after an edit, check that the traversal loop of
//! `trace_layers` holds no `cmov` after the `bsr` of the level jump (objdump).
//!
//! Tried and dropped (results identical each time, measured slower): the f64 clip with all
//! six face divisions unconditional (three packed SSE2 divisions) and the faces folded by
//! selects — bit-identical to the branching form (checked on 20,000 random and edge rays),
//! but +70 instructions per ray (spills) and ~+2 % time; moving the multi-layer cascade
//! path out of line (`#[inline(never)]`, -21 instructions per ray) — +25 % time, the same
//! `cmov` fold as above. Measured and not pursued: with the camera cube the clip's entry
//! point has `W == near` exactly for 78 % of the rays and the exit `W == far` for 75 % (60 %
//! both), so a branch to a precomputed `1 / near` would skip the second division of the
//! clip's chain only for ~60 % of the rays while mispredicting for ~25 %: no net gain
//! expected. An f32 clip with an error bound and an f64 fallback cannot return the f64
//! clip's bits (its end points and `t` are roundings of f64 values), and the brute-force
//! twin and the example's statistics need exactly those, so it was not attempted.
//!
//! Head to head after (`cd crates/screen && cargo run --release --example quadtree_speed
//! -- 0.065 --near 0.1 --quick`, same process, interleaved, best of 7, loaded machine):
//! quad-tree 158.1 ns/ray, **2.07x MinMax flat** (327.7 ns), 2.17x MinMax bilinear, 1.68x
//! Hi-Z, 8.34x the minimal artifact-free DDA (254 steps); fitted cube (`-- 0.065 --quick`,
//! second run; the first, disturbed, gave 169 ns): 132.4 ns/ray, 1.86x MinMax flat, 2.01x
//! bilinear, 1.43x Hi-Z, 0.98x the DDA (17 steps).
//!
//! **Session 6: skip what the `z` slabs exclude.** Every result bit-identical (all kinds,
//! layers, pixels, `t` and position bits of all 1.44 M stereo rays, atrium, ipd 0.065 and
//! 0.3, both cubes, 1 and 2 layers: `quadtree_speed IPD [--near 0.1] --profile
//! quadtree[2] --dump FILE` with the old build, `--check FILE` with the new; `parallax
//! bench warp` PSNR / SSIM identical to 6 digits on atrium (1 and 2 layers) and Sponza).
//! Instructions per ray as in session 4 (callgrind, every 4th ray); time `quadtree_speed
//! 0.065 [--near 0.1] --profile quadtree --time` (all rays, thread CPU time, best of 7),
//! builds run alternately, best of 3 runs each, loaded machine (±3 %):
//!
//! | change | instr/ray camera | ns/ray camera | instr/ray fitted | ns/ray fitted |
//! |---|---|---|---|---|
//! | before (a395804) | 1652 | ~157 | 1291 | ~127 |
//! | hit pixel `cell` in integers (the float floor/tie/clamp chain), `f32::clamp` (an out-of-line call per hit) inlined | 1611 | ~157 | 1259 | |
//! | **`z` slabs** ([`traverse`]): start where the ray's `z` reaches the top level's lower bound (`QuadTree::z_floor`), descend from a box's `z` entry; visits 6.7 -> 2.1 / 3.6 -> 2.7 per ray | 1130 | **~125** | 1175 | ~128 |
//! | plane test with the unscaled normal `(g_x, g_y, -1)` (bit-identical: power-of-two scaling commutes with rounding) | 1146 | ~120 | 1183 | ~122 |
//! | start one level below the extent level | 1175 | ~118 | 1189 | ~119 |
//! | `ScreenTracer::trace` inlines the traversal (no call and no copy of the returned pair) | 1165 | ~115 | 1180 | ~118 |
//!
//! Session 6 (second part), **regional `z` floors** ([`traverse`]): the start's floor over only the
//! top-level nodes the segment can cross (row and direction for `x`-only rays, rectangle
//! otherwise), when at least 0.05 above the global floor and the global floor is > 0.
//! Bit-identical (`--check`, atrium, both cubes, 1 and 2 layers). Japanese classroom
//! (`parallax bench warp`, camera cube 0.1 m, see the session notes of issue 4): 5.73 -> 2.69
//! nodes/ray, quad-tree / min-max trace CPU 1.82x -> 2.10x (1 layer), 1.77x -> 2.03x
//! (2 layers); atrium unchanged visits, ~+3 % ns/ray on the camera cube (the lookup).
//!
//! In the fitted cube the top-level floor is 0 (a plane steep in the cube near the top
//! level spans the whole depth range), so only the descent rule acts there; its visits
//! drop by a quarter but the time hardly moves: the fitted cube's ~120 ns are mostly the
//! per-ray fixed part. Measured there: tracing pre-clipped segments (the f64
//! `UnitCube::clip_ray` taken out of the timed loop) saves ~38 ns/ray, the result mapping
//! (`world_t`) ~3 ns. The fitted cube's floor of 0 comes from one steep plane: at every
//! level from 3 to 8 exactly one node has `zmin < 0.05` (median 0.56-0.76), and a floor
//! of 0.5 there (not exact; timing only) would give ~113 instead of ~119 ns/ray.
//!
//! Tried and dropped (measured): a shared f32 clip for the quad-tree and brute force
//! (`UnitCube` with an eye-relative f32 matrix, faces as two 4-lane divisions and a
//! horizontal max / min, the exit point as `p0 + d` with a cancellation-free `d` so that
//! horizontal stereo rays keep `d.y == 0` exactly): only -2..-3 ns/ray (~225 instead of
//! ~280 instructions: glam's lane construction), results changed by ulps, and the
//! regression test `cascade_regression_24x45_hit_vs_entry`, pinned to an f64 rounding case,
//! lost its case — not worth it; an f32 clip that rounds the two ends' `y` separately
//! loses that exact horizontality and the traversal's one-axis fast path (+27 ns/ray). The
//! f64 clip rewritten over named scalars (LLVM compiled it to the same code), `#[inline]`
//! on it (+5 % time, again), a cheaper float form of the ray validity test (-12
//! instructions, no time), the f16 decode's subnormal branch by a magic subtraction
//! instead of an integer conversion (+1.5 ns), starting two levels below the extent level
//! (slower on the camera cube), and a per-ray floor: a table of floors over every
//! rectangle of top-level nodes (`(c r)^2` entries), looked up for the segment's bounding
//! box — exact (same bits), visits 2.14 -> 1.09 (camera) and 2.54 -> 1.46 (fitted) per
//! ray, but ~+14 ns/ray on both cubes: the lookup (conversions, clamps, index, load) and
//! the division sit on the chain to the start node, and the fitted cube's rays then leave
//! the `s = 0` fast path of the start pixel.
//!
//! Head to head after (`cd crates/screen && cargo run --release --example quadtree_speed
//! -- 0.065 [--near 0.1] --quick`, same process, interleaved, best of 7, loaded machine):
//! camera cube 117.4 ns/ray (2.14 nodes), **2.79x MinMax flat** (327.2 ns), 2.96x MinMax
//! bilinear, 2.28x Hi-Z, 11.3x the minimal artifact-free DDA (254 steps); fitted cube
//! 119.7 ns/ray (2.54 nodes), **2.02x MinMax flat** (242.1 ns), 2.18x bilinear, 1.58x
//! Hi-Z, 1.08x the DDA (17 steps). Before (same protocol, first run of this session):
//! 167.5 ns, 2.04x flat (camera); the fitted cube was at 1.86-1.90x. `parallax bench warp`
//! (trace CPU Mrays/s, `--near 0.1`, 1 layer): atrium quad-tree 4.91 -> 7.27 (MinMax 2.80:
//! 2.6x), Sponza 7.65 -> 11.78 (MinMax 5.80-6.39: ~1.9-2.0x; single noisy runs).

pub mod build;
pub mod cascade;
pub mod merge;
pub mod node;
pub mod traverse;
pub mod tree;

pub use cascade::QuadTreeTracer;
pub use node::Node;
pub use tree::QuadTree;

use crate::NormalSource;

/// How a [`QuadTreeTracer`] treats occlusion volumes (§4.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerMode {
    /// Multi-layer: only rays that enter layer `k`'s occlusion volume (before hitting layer
    /// `k`) are traced through layer `k + 1`. With lossless settings the result equals
    /// [`crate::BruteForcePlanes`] over all layers (see [`cascade`] for the proof).
    Cascade,
    /// Single-layer inpainting (§4.1): on the last layer the traversal stops at the first
    /// entry into the (slightly dilated) occlusion volume and returns
    /// [`crate::TraceResult::OcclusionVolume`] with the pixel the ray was over just before
    /// (the background side of the silhouette), so the application can take its colour.
    /// Earlier layers (if several are given) cascade as in [`LayerMode::Cascade`].
    Inpaint,
}

/// Construction and traversal settings (§3.3, §4, §6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadTreeOptions {
    /// Cosine of the maximum angle between the proxy normal and a child normal for merging
    /// (§3.3 condition 2; merge iff `cos > gamma_norm`). Default `cos(3°)` (§6). `1.0` never
    /// merges.
    pub gamma_norm: f32,
    /// Maximum corner distance (cube `z` units, along the view direction `v = (0, 0, 1)` of
    /// the least-squares fit) between the children's planes and the proxy plane at the 16
    /// child footprint corners (§3.3 condition 3; merge iff `max < gamma_dist`). Default
    /// `1e-5` (§6). `0.0` never merges.
    pub gamma_dist: f32,
    /// Distance-adaptive thresholds (§6, Fig. 14/15): both tolerances grow linearly with
    /// the node's linear depth fraction `u = (d - near) / (far - near)` of the proxy's
    /// centre depth: the angle `acos(gamma_norm)` by up to `ADAPTIVE_SCALE` times (capped at
    /// 25°, the end of Fig. 15's range) and `gamma_dist` by up to `ADAPTIVE_SCALE` times
    /// (capped at `1e-1`). Lossless settings stay lossless. Default `false`.
    pub adaptive: bool,
    /// Maximum number of levels including the pixel level (§3.2 caps at 9). Default 9.
    pub max_levels: u32,
    /// Per-pixel normals. Default [`NormalSource::GBuffer`]: Widmer reconstructs normals from
    /// depth but notes (§3.2, §6 "Limitations") that G-buffer normals are more precise and
    /// avoid the cracks between unaligned planes; exact normals also make coplanar pixels
    /// merge. With `Depth { .. }` or `GBufferFlagged { .. }` the flag `O` drives
    /// [`Self::crack_dilation`]; plain `GBuffer` flags none (measured worse, see `planes.rs`).
    pub normals: NormalSource,
    /// Occlusion handling across layers. Default [`LayerMode::Cascade`] (exact).
    pub mode: LayerMode,
    /// Crack dilation (§3.2 / §4) in pixels: a plane flagged `O` is also intersected over the
    /// last `crack_dilation` pixels of ray travel *before* it enters the plane's footprint,
    /// which masks the cracks between unaligned neighbouring planes. Only flagged planes are
    /// affected ([`NormalSource::GBuffer`] flags none). Default 0.5. Not part of the paper's
    /// parameter list; set 0 for results identical to brute force with depth normals.
    pub crack_dilation: f32,
}

/// §6: the adaptive thresholds grow up to this factor at the far plane.
pub const ADAPTIVE_SCALE: f32 = 10.0;

/// Inpaint mode: the occlusion volume is dilated by this many pixels of ray travel (§4.1,
/// "a slightly dilated occlusion volume").
pub const INPAINT_DILATION_PX: f32 = 1.0;

impl Default for QuadTreeOptions {
    fn default() -> Self {
        Self {
            gamma_norm: 3f32.to_radians().cos(),
            gamma_dist: 1e-5,
            adaptive: false,
            max_levels: 9,
            normals: NormalSource::GBuffer,
            mode: LayerMode::Cascade,
            crack_dilation: 0.5,
        }
    }
}

impl QuadTreeOptions {
    /// Settings under which pruning never merges (`gamma_norm = 1`, `gamma_dist = 0`): the
    /// tree's leaves are exactly the (quantised) per-pixel planes.
    pub fn lossless() -> Self {
        Self {
            gamma_norm: 1.0,
            gamma_dist: 0.0,
            ..Self::default()
        }
    }
}
