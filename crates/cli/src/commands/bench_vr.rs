//! `parallax bench vr`: HVVR's Tables 1-6 (Hunt et al. 2018; `parallax_vr::bench`) as Markdown,
//! rows as JSON with `--json`.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, ValueEnum};
use parallax_bvh::Bvh;
use parallax_vr::bench::table3;
use parallax_vr::bench::table6::{self, Table6Options};
use parallax_vr::bench::{SCHEMES, VrBenchOptions, markdown, run, update_row};
use parallax_vr::frame::Visibility;
use parallax_vr::resolve::ShadingMode;

use crate::args::{ViewArgs, msaa_spp};
use crate::output;

/// A `--schemes` entry: one of [`SCHEMES`].
fn scheme(s: &str) -> Result<String, String> {
    if SCHEMES.contains(&s) {
        Ok(s.to_string())
    } else {
        Err(format!(
            "unknown scheme {s:?}; expected one of {}",
            SCHEMES.join(", ")
        ))
    }
}

/// `--table3-spp`: 0 (skip) or a `--msaa` value.
fn table3_spp(s: &str) -> Result<u32, String> {
    if s == "0" { Ok(0) } else { msaa_spp(s) }
}

/// `parallax bench vr` (HVVR Tables 1-6; see `parallax_vr::bench`).
#[derive(Args, Debug)]
pub struct VrBenchArgs {
    /// Scene and head pose (atrium, cornell, or e.g. the Sponza / classroom glTF paths).
    #[command(flatten)]
    pub view: ViewArgs,
    /// Both eyes' width (each eye gets half).
    #[arg(long, default_value_t = 2160)]
    pub width: u32,
    /// Height.
    #[arg(long, default_value_t = 1200)]
    pub height: u32,
    /// Subsamples per pixel: comma list of 1, 4, 8, 16, 32 (HVVR Table 2 uses 32).
    #[arg(long, default_value = "8", value_delimiter = ',', value_parser = msaa_spp)]
    pub msaa: Vec<u32>,
    /// Schemes: comma list of normal, post-distort, wide, dof-0.5, dof-0.25, dof-0.1, foveated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "normal,post-distort,wide,dof-0.5,dof-0.25,dof-0.1,foveated",
        value_parser = scheme
    )]
    pub schemes: Vec<String>,
    /// Also SSAA rows (HVVR Table 4).
    #[arg(long)]
    pub ssaa: bool,
    /// Visibility methods: comma list of per-ray, beam, beam-watertight, beam-exact.
    #[arg(long, value_delimiter = ',', default_value = "per-ray,beam", value_parser = Visibility::parse)]
    pub visibility: Vec<Visibility>,
    /// Timed repetitions (the best is reported).
    #[arg(long, default_value_t = 1)]
    pub repeats: u32,
    /// HVVR Table 6 (the beam caster against Embree's and our BVH's rays on the same
    /// subsample rays, `parallax_vr::bench::table6`): `with` the scheme rows, `skip`, or `only`.
    #[arg(long, value_enum, default_value_t = Table6::With)]
    pub table6: Table6,
    /// HVVR Table 3 at this spp (procedural subsample rays against a stored high-resolution
    /// ray buffer, `parallax_vr::bench::table3`); 0 skips it.
    #[arg(long, default_value_t = 0, value_parser = table3_spp)]
    pub table3_spp: u32,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Whether `bench vr` runs Table 6 (`--table6`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Table6 {
    With,
    Skip,
    Only,
}

pub fn bench(a: &VrBenchArgs, quiet: bool) -> Result<()> {
    let scene = a.view.load_scene()?;
    let head = a.view.camera_desc(&scene)?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let mut shading = vec![ShadingMode::Msaa];
    if a.ssaa {
        shading.push(ShadingMode::Ssaa);
    }
    let opts = VrBenchOptions {
        width: a.width,
        height: a.height,
        spp: a.msaa.clone(),
        schemes: a.schemes.clone(),
        shading,
        visibility: a.visibility.clone(),
        repeats: a.repeats,
    };
    let update = update_row(&scene, a.repeats.max(3))?;
    let rows = if a.table6 == Table6::Only {
        Vec::new()
    } else {
        run(&scene, &bvh, &head, &opts)?
    };
    let t6 = if a.table6 == Table6::Skip {
        None
    } else {
        let o = Table6Options {
            width: a.width,
            height: a.height,
            spp: a.msaa.clone(),
            repeats: a.repeats,
        };
        Some(table6::run(&scene, &bvh, &head, &o)?)
    };
    let t3 = match a.table3_spp {
        0 => None,
        spp => Some(table3::run(
            &scene, &bvh, &head, a.width, a.height, spp, a.repeats,
        )?),
    };
    if !quiet {
        println!(
            "| scene | vertices | triangles | moving objects | moving vertices | build ms | animate ms | refit ms |"
        );
        println!("|---|---|---|---|---|---|---|---|");
        println!(
            "| {} | {} | {} | {} | {} | {:.2} | {:.3} | {:.3} |\n",
            update.scene,
            update.vertices,
            update.triangles,
            update.moving_objects,
            update.moving_vertices,
            update.build_ms,
            update.animate_ms,
            update.refit_ms
        );
        if !rows.is_empty() {
            print!("{}", markdown(&rows));
        }
        if let Some(t) = &t6 {
            println!(
                "\nTable 6: the beam caster against ray tracers on the same rays (`normal` scheme; \
                 the beam caster's frame includes moving its hierarchy from the previous frame's \
                 head, turned by a degree)\n"
            );
            print!("{}", table6::markdown(t));
        }
        if let Some(t) = &t3 {
            println!(
                "\nTable 3: procedural subsample rays against a stored ray buffer (`normal` scheme, same rays)\n"
            );
            print!("{}", table3::markdown(t));
        }
    }
    let json = serde_json::json!({ "update": update, "rows": rows, "table6": t6, "table3": t3 });
    output::write_json(a.json.as_deref(), &json)
}
