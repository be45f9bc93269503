//! Instruction counts of the BVH build and of DIRT's build (camera view 1024 x 512 + cube map)
//! under callgrind, for A/B comparisons on a busy machine (`none` measures the scene load
//! alone, to subtract):
//!
//! (`DIRT_CAMERA=WxH` sets the camera film, default 1024x512.)
//!
//! `RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file=/dev/null
//!  target/release/examples/dirt_build_count none|bvh|dirt FACE S B [SCENE]`
use parallax_raster::dirt::{DirtOptions, DirtViews, DirtViewsOptions};
use parallax_scene::camera::Pinhole;
fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let scene = parallax_scene::Scene::load(a.get(4).map_or("atrium", |s| s.as_str())).unwrap();
    match a[0].as_str() {
        "bvh" => {
            let b = parallax_bvh::Bvh::build(&scene.mesh);
            println!("{}", b.triangles().len());
        }
        "dirt" => {
            let desc = scene.camera(None).unwrap();
            let (w, h) = match std::env::var("DIRT_CAMERA") {
                Ok(v) => {
                    let (a, b) = v.split_once('x').expect("DIRT_CAMERA=WxH");
                    (a.parse().unwrap(), b.parse().unwrap())
                }
                Err(_) => (1024, 512),
            };
            let cam = Pinhole::new(&desc, w, h).unwrap();
            let p = |i: usize| a[i].parse::<u32>().unwrap();
            let o = DirtViewsOptions {
                face_size: p(1),
                capture: DirtOptions {
                    tile_size: p(2),
                    buckets: p(3),
                    ..Default::default()
                },
                camera_tile_size: None,
            };
            let v = DirtViews::build(&scene.mesh, Some(&cam), desc.eye, &o).unwrap();
            for c in v.views() {
                let st = c.stats();
                println!(
                    "{}x{} cells, {} in view, {} fragments, {} entries",
                    st.cells_x, st.cells_y, st.triangles_in_view, st.fragments, st.entries
                );
            }
        }
        _ => {}
    }
}
