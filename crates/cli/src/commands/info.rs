//! `parallax scenes` and `parallax info`.

use anyhow::Result;
use clap::Args;
use parallax_scene::{Light, MaterialKind, Scene, builtin};

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A built-in scene name or a scene file.
    pub scene: String,
}

pub fn scenes() -> Result<()> {
    for name in builtin::NAMES {
        println!("{name:<10} {}", builtin::describe(name));
    }
    Ok(())
}

pub fn run(a: &InfoArgs) -> Result<()> {
    let scene = Scene::load(&a.scene)?;
    let b = scene.bounds();
    println!("scene      {}", scene.name);
    println!("triangles  {}", scene.mesh.triangle_count());
    println!("vertices   {}", scene.mesh.vertex_count());
    println!("objects    {}", scene.mesh.objects.len());
    println!(
        "bounds     min {:?} max {:?}",
        b.min.to_array(),
        b.max.to_array()
    );
    println!("textures   {}", scene.textures.len());
    println!("materials  {}", scene.materials.len());
    for (i, m) in scene.materials.iter().enumerate() {
        let kind = match m.kind {
            MaterialKind::Standard => "standard".to_string(),
            MaterialKind::Mirror => "mirror".to_string(),
            MaterialKind::Dielectric { ior } => format!("dielectric ior {ior}"),
        };
        println!(
            "  [{i}] {:<24} {kind}, base {:?}{}, roughness {}, metallic {}{}",
            m.name,
            m.base_color.to_array(),
            if m.base_color_texture.is_some() {
                " x texture"
            } else {
                ""
            },
            m.roughness,
            m.metallic,
            if m.is_emissive() {
                format!(", emissive {:?}", m.emissive.to_array())
            } else {
                String::new()
            }
        );
    }
    println!("lights     {}", scene.lights.len());
    for l in &scene.lights {
        match l {
            Light::Point {
                position,
                intensity,
            } => println!(
                "  point at {:?}, {:?} W/sr",
                position.to_array(),
                intensity.to_array()
            ),
            Light::Spot {
                position,
                direction,
                ..
            } => {
                println!(
                    "  spot at {:?} towards {:?}",
                    position.to_array(),
                    direction.to_array()
                )
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                println!(
                    "  directional {:?}, {:?} W/m^2",
                    direction.to_array(),
                    irradiance.to_array()
                )
            }
        }
    }
    println!("environment {:?}", scene.environment.to_array());
    println!("cameras    {}", scene.cameras.len());
    for c in &scene.cameras {
        let d = c.desc;
        println!(
            "  {:<10} eye {:?} target {:?} fov-y {}",
            c.name,
            d.eye.to_array(),
            d.target.to_array(),
            d.fov_y_deg
        );
    }
    if let Some(p) = &scene.camera_path {
        println!(
            "path       {} keys, {} frames at {} fps",
            p.keys.len(),
            p.frames,
            p.fps
        );
    }
    if !scene.animations.is_empty() {
        println!("animations {}", scene.animations.len());
    }
    Ok(())
}
