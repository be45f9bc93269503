//! Depth layers against the BVH's all-hits query: layer k = k-th surface along the pixel-centre
//! ray; k-buffer == depth peeling; minimum separation.

mod raster_support;

use parallax_bvh::Bvh;
use parallax_core::NO_ID;
use parallax_raster::{LayerMethod, RasterOptions, capture_layers, capture_layers_filtered};
use raster_support::*;

#[test]
fn layer_k_matches_the_kth_bvh_hit() {
    const K: usize = 4;
    for (name, scene, desc) in scenes(false) {
        let bvh = Bvh::build(&scene.mesh);
        let (cam, view) = pinhole(&desc, 120, 68);
        let cap = capture_layers(&scene, &view, &RasterOptions::layers(K)).unwrap();
        let hits = all_hits(&bvh, &cam, 120, 68);
        for k in 0..K {
            let g = cap.layers.layer(k);
            let (mut agree, mut strict, mut surfaced) = (0usize, 0usize, 0usize);
            for (i, h) in hits.iter().enumerate() {
                let (bp, bd) = h
                    .get(k)
                    .map_or((NO_ID, f32::INFINITY), |(h, d)| (h.prim, *d));
                let (rp, rd) = (g.primitive_id[i], g.depth[i]);
                surfaced += (bp != NO_ID) as usize;
                if bp == rp {
                    strict += 1;
                    agree += 1;
                    if bp != NO_ID {
                        assert!(rel(bd, rd) <= 1e-4, "{name} layer {k}: {bd} vs {rd}");
                    }
                } else if bp != NO_ID && rp != NO_ID && rel(bd, rd) <= TIE_REL {
                    agree += 1; // two surfaces through the same point, ordered either way
                }
            }
            let n = hits.len() as f64;
            eprintln!(
                "{name} layer {k}: {:.5} agree ({:.5} same id), {surfaced} pixels with a k-th hit",
                agree as f64 / n,
                strict as f64 / n
            );
            assert!(agree as f64 / n >= 0.995, "{name} layer {k}");
        }
        // Layers are sorted per pixel.
        for i in 0..cap.layers.layer(0).len() {
            for k in 1..K {
                assert!(cap.layers.layer(k).depth[i] >= cap.layers.layer(k - 1).depth[i]);
            }
        }
    }
}

#[test]
fn kbuffer_equals_depth_peeling() {
    let scene = parallax_scene::Scene::load("foliage").unwrap();
    let desc = scene.camera(None).unwrap();
    let (_, view) = pinhole(&desc, 100, 64);
    let k = RasterOptions::layers(5);
    let p = RasterOptions {
        method: LayerMethod::Peel,
        ..k
    };
    let a = capture_layers(&scene, &view, &k).unwrap();
    let b = capture_layers(&scene, &view, &p).unwrap();
    assert!(
        a.layers.layer(4).hit_count() > 0,
        "foliage should have 5 layers somewhere"
    );
    assert_eq!(a.layers, b.layers);
}

#[test]
fn min_separation_skips_close_surfaces() {
    let scene = parallax_scene::Scene::load("foliage").unwrap();
    let desc = scene.camera(None).unwrap();
    let (cam, view) = pinhole(&desc, 80, 48);
    let delta = 0.25;
    let opts = RasterOptions {
        layers: 3,
        min_separation: delta,
        ..Default::default()
    };
    let cap = capture_layers(&scene, &view, &opts).unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let hits = all_hits(&bvh, &cam, 80, 48);
    let (mut checked, mut agree) = (0, 0);
    for (i, h) in hits.iter().enumerate() {
        // Greedy reference: the nearest hit, then each next at least delta behind the last.
        let mut want: Vec<(u32, f32)> = Vec::new();
        for (hit, d) in h {
            if want.last().is_none_or(|l| *d >= l.1 + delta) && want.len() < 3 {
                want.push((hit.prim, *d));
            }
        }
        for k in 0..3 {
            let g = cap.layers.layer(k);
            let got = (g.primitive_id[i], g.depth[i]);
            if k > 0 && got.0 != NO_ID {
                assert!(got.1 >= cap.layers.layer(k - 1).depth[i] + delta * (1.0 - 1e-6));
            }
            checked += 1;
            let w = want.get(k).copied().unwrap_or((NO_ID, f32::INFINITY));
            if w.0 == got.0 || (w.0 != NO_ID && got.0 != NO_ID && rel(w.1, got.1) <= TIE_REL) {
                agree += 1;
            }
        }
    }
    eprintln!("min separation: {agree}/{checked} agree");
    assert!(agree as f64 / checked as f64 >= 0.995);
}

#[test]
fn filter_keeps_only_accepted_triangles() {
    let scene = parallax_scene::Scene::load("atrium").unwrap();
    let desc = scene.camera(None).unwrap();
    let (_, view) = pinhole(&desc, 64, 40);
    let even = |p: u32| p.is_multiple_of(2);
    let cap =
        capture_layers_filtered(&scene, &view, &RasterOptions::layers(2), Some(&even)).unwrap();
    let g = cap.gbuffer();
    assert!(g.hit_count() > 0);
    assert!(g.primitive_id.iter().all(|&p| p == NO_ID || p % 2 == 0));
    assert_eq!(cap.stats.raster.filtered, scene.mesh.indices.len() / 2);
    assert_eq!(cap.bytes(), 2 * 64 * 40 * 56);
}
