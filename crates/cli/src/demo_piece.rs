//! One piece of `parallax demo`: what a command's demo function rendered, for the summary
//! table on stdout and the captioned page (`parallax_experiment::report::GalleryItem`).

use parallax_experiment::report::GalleryItem;

/// A demo piece: its table row and its place on the page.
#[derive(Clone, Debug)]
pub struct DemoPiece {
    /// The first column of the table.
    pub label: String,
    /// The page section (the technique or paper).
    pub section: &'static str,
    /// Title on the page.
    pub title: String,
    /// What it shows, with its settings and scores.
    pub what: String,
    /// Image size as printed (e.g. `960x540`, `2x 480x540`).
    pub size: String,
    /// Samples per pixel or configuration column (`-` where none).
    pub spp: String,
    /// Rays per second in millions, where measured.
    pub mrays: Option<f64>,
    /// Wall-clock milliseconds of the piece.
    pub ms: f64,
    /// Its images in the demo folder; the first is the result.
    pub images: Vec<String>,
    /// The ground truth of the first image, where the piece has one.
    pub truth: Option<String>,
}

impl DemoPiece {
    /// The Markdown row of the summary table (columns: piece, what, size, spp, Mrays/s, ms,
    /// files).
    pub fn row(&self, out: &std::path::Path) -> String {
        let files: Vec<String> = self
            .images
            .iter()
            .chain(&self.truth)
            .map(|f| out.join(f).display().to_string())
            .collect();
        format!(
            "| {} | {} | {} | {} | {} | {:.0} | {} |",
            self.label,
            self.what,
            self.size,
            self.spp,
            self.mrays.map_or("-".into(), |m| format!("{m:.1}")),
            self.ms,
            files.join(", ")
        )
    }

    /// Its item of the demo page.
    pub fn gallery_item(&self) -> GalleryItem {
        GalleryItem {
            section: self.section.to_string(),
            title: self.title.clone(),
            caption: format!("{} ({}, {:.0} ms)", self.what, self.size, self.ms),
            images: self.images.clone(),
            truth: self.truth.clone(),
        }
    }
}

/// Page sections, in the order the demo renders them.
pub mod section {
    pub const CAMERAS: &str = "Camera models: the BVH reference renderer (the ground truth)";
    pub const PATH: &str = "Path tracing and DIRT (Vardis et al. 2017)";
    pub const WIDMER: &str =
        "Widmer et al. 2015: ray tracing through a quad-tree over depth layers";
    pub const HVVR: &str = "HVVR (Hunt et al. 2018): beam-culled ray casting for VR";
    pub const LDC: &str = "Layered depth cubes (Bürger et al. 2007): secondary rays";
    pub const REPROJECT: &str = "Stereo and temporal reprojection (Mäkitalo et al. 2019)";
}
