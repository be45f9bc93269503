//! Helpers shared by the baseline tests: eye-ray directions and every baseline tracer over
//! the same layers.

use glam::{Vec2, Vec3};
use parallax_core::GBuffer;
use parallax_scene::camera::Pinhole;
use parallax_screen::{
    DdaOptions, DdaTracer, HiZOptions, HiZTracer, MinMaxOptions, MinMaxTracer, ScreenTracer,
    UnitCube,
};

pub fn pixel_dir(cam: &Pinhole, x: u32, y: u32) -> Vec3 {
    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    cam.frame.dir_to_world(cam.camera_dir(film)).normalize()
}

/// All baselines over `layers` with thickness `thick` (1 and 2 layer DDA).
pub fn tracers(
    cube: &UnitCube,
    layers: &[GBuffer],
    thick: f32,
) -> Vec<(&'static str, Box<dyn ScreenTracer>)> {
    let dda = |n| DdaOptions {
        layers: n,
        z_thickness: thick,
        ..Default::default()
    };
    let mm = MinMaxOptions {
        z_thickness: thick,
        ..Default::default()
    };
    let hz = HiZOptions {
        z_thickness: thick,
        ..Default::default()
    };
    let mut v: Vec<(&'static str, Box<dyn ScreenTracer>)> = vec![
        (
            "dda1",
            Box::new(DdaTracer::new(cube, layers, &dda(1)).unwrap()),
        ),
        (
            "minmax",
            Box::new(MinMaxTracer::new(cube, layers, &mm).unwrap()),
        ),
        (
            "minmax-flat",
            Box::new(
                MinMaxTracer::new(
                    cube,
                    layers,
                    &MinMaxOptions {
                        bilinear: false,
                        ..mm
                    },
                )
                .unwrap(),
            ),
        ),
        ("hiz", Box::new(HiZTracer::new(cube, layers, &hz).unwrap())),
    ];
    if layers.len() > 1 {
        v.insert(
            1,
            (
                "dda2",
                Box::new(DdaTracer::new(cube, layers, &dda(2)).unwrap()),
            ),
        );
    }
    v
}
