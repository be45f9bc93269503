//! Unit tests of `spatial.rs`: the chopped boxes, and the sweep against clipping every bin.

use super::*;

/// Uniform values in `[-half, half)` from a 32-bit LCG.
fn uniform(seed: u32, half: f32) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(747796405).wrapping_add(2891336453);
        (s >> 8) as f32 / (1 << 24) as f32 * 2.0 * half - half
    }
}

/// A random triangle and its bounding box.
fn triangle_and_box(rnd: &mut impl FnMut() -> f32) -> ([Vec3; 3], BoxA) {
    let mut corner = || Vec3::new(rnd(), rnd(), rnd());
    let tri = [corner(), corner(), corner()];
    let bx = BoxA {
        min: Vec3A::from(tri[0].min(tri[1]).min(tri[2])),
        max: Vec3A::from(tri[0].max(tri[1]).max(tri[2])),
    };
    (tri, bx)
}

/// The spatial binning as first written (kept as the reference): every bin a reference
/// crosses grows by the reference's box clipped to the bin's slab, and the sweep unions
/// the bins.
fn spatial_split_by_clipping(
    refs: &[PrimRef],
    bounds: &Aabb,
    block: usize,
) -> Option<SpatialSplit> {
    let grid = Grid::new(bounds, SPATIAL_BINS.min(4 + refs.len() / 20));
    let mut bins = [[(BoxA::EMPTY, 0u32, 0u32); SPATIAL_BINS]; 3];
    for r in refs {
        let bx = BoxA {
            min: r.min(),
            max: r.max(),
        };
        for (a, bins) in bins.iter_mut().enumerate() {
            if grid.scale[a] == 0.0 {
                continue;
            }
            let (b0, b1) = (grid.bin(bx.min[a], a), grid.bin(bx.max[a], a));
            bins[b0].1 += 1;
            bins[b1].2 += 1;
            for (i, bin) in bins.iter_mut().enumerate().take(b1 + 1).skip(b0) {
                let mut p = bx;
                if i > b0 {
                    p.min[a] = grid.plane(i, a).max(bx.min[a]);
                }
                if i < b1 {
                    p.max[a] = grid.plane(i + 1, a).min(bx.max[a]);
                }
                bin.0 = bin.0.union(p);
            }
        }
    }
    let mut best: Option<SpatialSplit> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if grid.scale[axis] == 0.0 {
            continue;
        }
        let nb = grid.bins;
        let mut right = [(BoxA::EMPTY, 0u32, 0.0f32); SPATIAL_BINS];
        let (mut acc, mut cnt) = (BoxA::EMPTY, 0u32);
        for i in (1..nb).rev() {
            acc = acc.union(bins[i].0);
            cnt += bins[i].2;
            right[i] = (acc, cnt, acc.aabb().surface_area() * sah_count(cnt, block));
        }
        let (mut acc, mut cnt) = (BoxA::EMPTY, 0u32);
        for i in 1..nb {
            acc = acc.union(bins[i - 1].0);
            cnt += bins[i - 1].1;
            let (rb, rn, rc) = right[i];
            if cnt == 0 || rn == 0 {
                continue;
            }
            let cost = acc.aabb().surface_area() * sah_count(cnt, block) + rc;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(SpatialSplit {
                    cost,
                    axis,
                    split: i,
                    grid,
                    left: acc,
                    right: rb,
                    n_l: cnt,
                    n_r: rn,
                });
            }
        }
    }
    best
}

#[test]
fn lane_bins_equal_the_scalar_bins() {
    let special = [
        0.0,
        -0.0,
        1e-30,
        -1e-30,
        0.999_999_9,
        1.0,
        2.5,
        3.999_999_8,
        4.0,
        15.999_999,
        16.0,
        1e9,
        3e9,
        -1.0,
        -3e9,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::MIN_POSITIVE,
    ];
    let mut rnd = uniform(7, 40.0);
    let mut seen = [0usize; SPATIAL_BINS];
    for bins in [1usize, 2, 5, 16] {
        for bounds in [
            Aabb::new(Vec3::ZERO, Vec3::splat(16.0)),
            Aabb::new(Vec3::new(-3.0, 0.5, -1e3), Vec3::new(5.0, 0.5, 7e3)),
        ] {
            let grid = Grid::new(&bounds, bins);
            let mut check = |p: Vec3| {
                let lanes = grid.bins3(Vec3A::from(p));
                for a in 0..3 {
                    assert_eq!(lanes[a], grid.bin(p[a], a), "{bins} {p:?} {a}");
                    seen[lanes[a]] += 1;
                }
            };
            for &x in &special {
                for &y in &special {
                    check(Vec3::new(x, y, -x));
                }
            }
            for _ in 0..20_000 {
                check(Vec3::new(rnd(), rnd(), rnd() * 100.0));
            }
        }
    }
    // Every bin index is produced.
    assert!(seen.iter().all(|&k| k > 100), "{seen:?}");
}

#[test]
fn side_of_plane_in_lanes_equals_the_scalar_bins() {
    let mut rnd = uniform(9, 40.0);
    let special = [
        0.0,
        -0.0,
        4.0,
        8.0,
        15.999_999,
        16.0,
        -1.0,
        3e9,
        -3e9,
        f32::NAN,
    ];
    let (mut after, mut before) = (0, 0);
    for bins in [2usize, 3, 7, 16] {
        let bounds = Aabb::new(Vec3::new(-3.0, 0.0, -1e3), Vec3::new(5.0, 16.0, 7e3));
        let grid = Grid::new(&bounds, bins);
        let mut check = |p: Vec3| {
            for split in 1..bins {
                let m = grid.at_or_after(Vec3A::from(p), split);
                for a in 0..3 {
                    let want = grid.bin(p[a], a) >= split;
                    assert_eq!(m >> a & 1 == 1, want, "{bins} {split} {p:?} {a}");
                    if want { after += 1 } else { before += 1 }
                }
            }
        };
        for &x in &special {
            check(Vec3::new(x, x, x));
        }
        for _ in 0..20_000 {
            check(Vec3::new(rnd() * 0.2, rnd() * 0.4 + 8.0, rnd() * 200.0));
        }
        // Values on the planes themselves.
        for i in 0..=bins {
            check(Vec3::new(
                grid.plane(i, 0),
                grid.plane(i, 1),
                grid.plane(i, 2),
            ));
        }
    }
    // Coordinates whose `f` is exactly the split index: the floats next to where the
    // boundary lies (positive boxes, so that stepping the bits steps the value).
    let mut exact = 0;
    for (bins, lo, hi) in [
        (16, 1.0, 9.0),
        (7, 2.5, 1000.0),
        (11, 0.125, 0.75),
        (5, 3.0, 4.0),
    ] {
        let grid = Grid::new(&Aabb::new(Vec3::splat(lo), Vec3::splat(hi)), bins);
        for split in 1..bins {
            let x0 = lo + split as f32 / grid.scale[0];
            for k in -64i32..=64 {
                let x = f32::from_bits(x0.to_bits().wrapping_add_signed(k));
                exact += usize::from((x - grid.lo[0]) * grid.scale[0] == split as f32);
                let m = grid.at_or_after(Vec3A::splat(x), split);
                assert_eq!(m & 1 == 1, grid.bin(x, 0) >= split, "{bins} {split} {x}");
            }
        }
    }
    assert!(
        after > 100_000 && before > 100_000 && exact > 4,
        "{after} {before} {exact}"
    );
}

#[test]
fn sweep_of_entry_and_exit_boxes_equals_clipping_to_every_bin() {
    let mut rnd = uniform(11, 1.0);
    let (mut compared, mut crossing) = (0, 0);
    for case in 0..600 {
        let n = 1 + (rnd().abs() * 700.0) as usize;
        // Some nodes of long thin references, some of small ones, corners snapped to a
        // coarse grid in some (references that start or end on bin planes).
        let size = [0.02, 0.3, 2.0][case % 3];
        let snap = case % 4 == 0;
        let refs: Vec<PrimRef> = (0..n)
            .map(|i| {
                let mut c = || {
                    let x = rnd() * 10.0;
                    if snap { (x * 4.0).round() / 4.0 } else { x }
                };
                let lo = Vec3::new(c(), c(), c());
                let e = Vec3::new(rnd().abs(), rnd().abs(), rnd().abs()) * size * 10.0;
                let e = if case % 5 == 1 {
                    e * Vec3::new(1.0, 0.0, 1.0)
                } else {
                    e
                };
                PrimRef::new(lo, lo + e, i as u32)
            })
            .collect();
        let (bounds, _) = node_bounds(&refs);
        let block = 1 + case % 4;
        let got = find_spatial_split(&refs, &bounds, block);
        let want = spatial_split_by_clipping(&refs, &bounds, block);
        assert_eq!(got.is_some(), want.is_some(), "case {case}");
        let (Some(g), Some(w)) = (got, want) else {
            continue;
        };
        assert_eq!(g.cost.to_bits(), w.cost.to_bits(), "case {case}");
        assert_eq!(
            (g.axis, g.split, g.n_l, g.n_r),
            (w.axis, w.split, w.n_l, w.n_r)
        );
        for (a, b) in [(g.left, w.left), (g.right, w.right)] {
            assert_eq!(Vec3::from(a.min), Vec3::from(b.min), "case {case}");
            assert_eq!(Vec3::from(a.max), Vec3::from(b.max), "case {case}");
        }
        compared += 1;
        crossing += usize::from(g.n_l + g.n_r > n as u32);
    }
    // Most nodes have a split, and in most of those references cross the plane.
    assert!(compared > 500 && crossing > 300, "{compared} {crossing}");
}

#[test]
fn split_boxes_contain_the_triangle_parts() {
    let mut rnd = uniform(3, 100.0);
    for _ in 0..20_000 {
        let (tri, bx) = triangle_and_box(&mut rnd);
        let a = (rnd().abs() as usize) % 3;
        let pos = rnd();
        let (l, r) = split_box(&tri, bx, a, pos);
        // Points of the triangle (barycentric samples, in f64) lie in the box of their side.
        for i in 0..=16 {
            for j in 0..=16 - i {
                let (u, v) = (i as f64 / 16.0, j as f64 / 16.0);
                let p: [f64; 3] = std::array::from_fn(|k| {
                    (1.0 - u - v) * tri[0][k] as f64 + u * tri[1][k] as f64 + v * tri[2][k] as f64
                });
                let inside =
                    |b: BoxA| (0..3).all(|k| b.min[k] as f64 <= p[k] && p[k] <= b.max[k] as f64);
                if p[a] <= pos as f64 {
                    assert!(inside(l), "{tri:?} {a} {pos} {p:?}");
                }
                if p[a] >= pos as f64 {
                    assert!(inside(r), "{tri:?} {a} {pos} {p:?}");
                }
            }
        }
    }
}

#[test]
fn crossing_points_on_the_plane_lie_in_both_boxes() {
    // The exact crossing of each edge (in f64) must lie in both boxes.
    let mut rnd = uniform(5, 1000.0);
    for _ in 0..50_000 {
        let (tri, bx) = triangle_and_box(&mut rnd);
        let a = 1;
        let pos = rnd() * 0.5;
        let (l, r) = split_box(&tri, bx, a, pos);
        for k in 0..3 {
            let (v, w) = (tri[k], tri[(k + 1) % 3]);
            let (va, wa) = (v[a] as f64, w[a] as f64);
            let p = pos as f64;
            if (va < p && wa > p) || (va > p && wa < p) {
                let t = (p - va) / (wa - va);
                for c in 0..3 {
                    let x = v[c] as f64 + t * (w[c] as f64 - v[c] as f64);
                    let x = if c == a { p } else { x };
                    for b in [l, r] {
                        assert!(b.min[c] as f64 <= x && x <= b.max[c] as f64);
                    }
                }
            }
        }
    }
}

/// The bins of [`bin_spatial_avx`] and [`bin_spatial_portable`] are bit for bit equal, and
/// their [`NegBox::boxa`] is bit for bit the union of the references' [`BoxA`]s taken in the
/// same order (the layout with the maximum negated changes no bit: signed zeros, NaNs and
/// infinities included).
#[test]
fn negated_max_bins_equal_the_box_unions() {
    let special = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        3.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ];
    let mut rnd = uniform(11, 8.0);
    let mut pick = uniform(12, 1.0);
    let mut coord = |rnd: &mut dyn FnMut() -> f32| {
        let u = pick();
        if u < -0.5 {
            special[((u + 1.0) * 16.0) as usize % special.len()]
        } else {
            (rnd() * 4.0).round() / 4.0
        }
    };
    let mut refs = Vec::new();
    for id in 0..4000u32 {
        let a = Vec3::new(coord(&mut rnd), coord(&mut rnd), coord(&mut rnd));
        let b = Vec3::new(coord(&mut rnd), coord(&mut rnd), coord(&mut rnd));
        refs.push(PrimRef::new(a.min(b), a.max(b), id));
    }
    let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
    for bins in [2usize, 7, 16] {
        let grid = Grid::new(&Aabb::new(Vec3::splat(-8.0), Vec3::splat(8.0)), bins);
        let portable = bin_spatial_portable(&refs, &grid);
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX checked.
            let avx = unsafe { bin_spatial_avx(&refs, &grid) };
            for (p, v) in portable.iter().flatten().zip(avx.iter().flatten()) {
                let lanes = |b: NegBox| b.0.map(|x| x.to_array().map(f32::to_bits));
                assert_eq!(lanes(p.enter_box), lanes(v.enter_box));
                assert_eq!(lanes(p.exit_box), lanes(v.exit_box));
                assert_eq!((p.enter, p.exit), (v.enter, v.exit));
            }
        }
        let mut want = [[(BoxA::EMPTY, BoxA::EMPTY, 0u32, 0u32); SPATIAL_BINS]; 3];
        for r in &refs {
            let bx = BoxA {
                min: r.min(),
                max: r.max(),
            };
            let (b0, b1) = (grid.bins3(bx.min), grid.bins3(bx.max));
            for a in 0..3 {
                let e = &mut want[a][b0[a]];
                e.0 = e.0.union(bx);
                e.2 += 1;
                let x = &mut want[a][b1[a]];
                x.1 = x.1.union(bx);
                x.3 += 1;
            }
        }
        let mut special_lanes = 0;
        for (p, w) in portable.iter().flatten().zip(want.iter().flatten()) {
            let (e, x) = (p.enter_box.boxa(), p.exit_box.boxa());
            assert_eq!((bits(e.min), bits(e.max)), (bits(w.0.min), bits(w.0.max)));
            assert_eq!((bits(x.min), bits(x.max)), (bits(w.1.min), bits(w.1.max)));
            assert_eq!((p.enter, p.exit), (w.2, w.3));
            if p.enter > 0 {
                let lanes = [e.min.to_array(), e.max.to_array()];
                special_lanes += lanes.iter().flatten().filter(|m| m.is_infinite()).count();
            }
        }
        // The special values reached the bins.
        assert!(special_lanes > 0);
    }
}
