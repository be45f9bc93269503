//! Looking Glass quilts (Widmer et al. 2015, §5.3: "image retargeting for multi-view
//! displays"): `cols x rows` views of one reference, each synthesised by tracing its pixels'
//! rays through the reference's layers.
//!
//! **Views.** `n = cols rows` cameras on a horizontal line through the reference eye,
//! spread over the view cone `θ` as seen from the focal plane at distance `D` (the
//! reference's target distance, or `--focus`): view `i` sits at angle
//! `φ_i = -θ/2 + θ i / (n - 1)` (0 for a single view), i.e. `x_i = D tan φ_i` along the
//! reference's right axis, keeps the reference's orientation (no toe-in) and shifts its
//! image window back so that the focal plane's window is the reference's (an off-axis
//! frustum: `shift.x = -x_i / (D tan(fov_x / 2))` in units of the half-width). View 0 is
//! the leftmost camera.
//!
//! **Tiles** (the Looking Glass convention): view `i` is the tile in column `i mod cols`,
//! row `i div cols` counted from the **bottom**, so view 0 is bottom-left and the last view
//! top-right. The file name carries `_qs{cols}x{rows}a{aspect}` ([`QuiltSpec::suffix`],
//! aspect = view width / height, up to 6 significant digits).
//!
//! **Square pixels** (ours): every view is a pinhole with square pixels, so a preset's tile
//! is `view_w x round(view_w / aspect)`; device quilts with stretched tiles (e.g. the Go's
//! 4092 x 4092 at aspect 0.5625) are sampled by the display in normalised tile coordinates,
//! so our quilt of the same grid and aspect shows the same views.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `cols`, `rows` | u32 | 8 x 6 (preset `portrait`) | tile grid, `1..=`[`MAX_VIEWS`] views |
//! | `view_w`, `view_h` | u32 | 420 x 560 | tile size in pixels |
//! | `aspect` | f32 | `view_w / view_h` | aspect of the file name |
//! | `view_cone_deg` | f32 | 35 | horizontal view cone, `(0, 180)` degrees |
//!
//! Presets ([`QuiltSpec::preset`]): `portrait` (Looking Glass Portrait: 8 x 6, 420 x 560,
//! a0.75), `go` (Looking Glass Go: 11 x 6, 372 x 661, a0.5625), `16-landscape` (16"
//! landscape: 8 x 6, 960 x 540, a1.77778), `8.9in` (8.9": 5 x 9, 819 x 512, a1.6).

use glam::Vec2;
use parallax_core::{Image, Rgb};
use parallax_scene::CameraDesc;
use parallax_scene::camera::{CameraFrame, Pinhole};
use serde::Serialize;

use crate::SynthError;

/// Most views of a quilt.
pub const MAX_VIEWS: u32 = 1024;
/// Default horizontal view cone (degrees).
pub const DEFAULT_VIEW_CONE_DEG: f32 = 35.0;

/// The layout of a quilt (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct QuiltSpec {
    pub cols: u32,
    pub rows: u32,
    pub view_w: u32,
    pub view_h: u32,
    pub aspect: f32,
    pub view_cone_deg: f32,
}

/// The names of [`QuiltSpec::preset`].
pub const PRESETS: [&str; 4] = ["portrait", "go", "16-landscape", "8.9in"];

impl QuiltSpec {
    /// A grid of `cols x rows` tiles of `view_w x view_h` (aspect from the tile size).
    pub fn new(cols: u32, rows: u32, view_w: u32, view_h: u32) -> Self {
        Self {
            cols,
            rows,
            view_w,
            view_h,
            aspect: view_w as f32 / view_h.max(1) as f32,
            view_cone_deg: DEFAULT_VIEW_CONE_DEG,
        }
    }

    /// A device preset (module docs).
    pub fn preset(name: &str) -> Result<Self, SynthError> {
        let with = |cols, rows, w: u32, aspect: f32| Self {
            view_h: (w as f32 / aspect).round() as u32,
            aspect,
            ..Self::new(cols, rows, w, 1)
        };
        Ok(match name {
            "portrait" => with(8, 6, 420, 0.75),
            "go" => with(11, 6, 372, 0.5625),
            "16-landscape" => with(8, 6, 960, 1.77778),
            "8.9in" => with(5, 9, 819, 1.6),
            o => {
                return Err(SynthError::Invalid(format!(
                    "unknown quilt preset {o:?}; expected one of {}",
                    PRESETS.join(", ")
                )));
            }
        })
    }

    /// Number of views.
    pub fn views(&self) -> u32 {
        self.cols * self.rows
    }

    /// Checks the ranges of the parameter table.
    pub fn validate(&self) -> Result<(), SynthError> {
        let n = self.cols as u64 * self.rows as u64;
        if n == 0 || n > MAX_VIEWS as u64 {
            return Err(SynthError::Invalid(format!(
                "a quilt needs 1..={MAX_VIEWS} views, got {} x {} = {n}",
                self.cols, self.rows
            )));
        }
        if !(self.view_cone_deg.is_finite()
            && self.view_cone_deg > 0.0
            && self.view_cone_deg < 180.0)
        {
            return Err(SynthError::Invalid(format!(
                "the view cone must be in (0, 180) degrees, got {}",
                self.view_cone_deg
            )));
        }
        if !(self.aspect.is_finite() && self.aspect > 0.0) {
            return Err(SynthError::Invalid(format!(
                "the quilt aspect must be > 0, got {}",
                self.aspect
            )));
        }
        parallax_core::image::check_size(self.view_w, self.view_h)?;
        parallax_core::image::check_size(self.view_w * self.cols, self.view_h * self.rows)?;
        Ok(())
    }

    /// The file-name suffix `_qs{cols}x{rows}a{aspect}`.
    pub fn suffix(&self) -> String {
        format!("_qs{}x{}a{}", self.cols, self.rows, format_g6(self.aspect))
    }

    /// Top-left pixel of view `i`'s tile in the quilt image (y down; module docs).
    pub fn tile_origin(&self, i: u32) -> (u32, u32) {
        let (c, r) = (i % self.cols, i / self.cols);
        (c * self.view_w, (self.rows - 1 - r) * self.view_h)
    }

    /// Quilt image size.
    pub fn size(&self) -> (u32, u32) {
        (self.cols * self.view_w, self.rows * self.view_h)
    }
}

/// `x` with up to 6 significant digits and no trailing zeros (C's `%g` for the values of a
/// quilt aspect): 0.75, 0.5625, 1.6, 1.77778.
pub fn format_g6(x: f32) -> String {
    let x = x as f64;
    if !(x.is_finite() && x > 0.0) {
        return format!("{x}");
    }
    let decimals = (5 - x.log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// The view cameras of a quilt around a reference pose (module docs).
#[derive(Clone, Debug)]
pub struct QuiltViews {
    pub spec: QuiltSpec,
    /// The reference (centre) camera at tile size.
    pub centre: Pinhole,
    /// Distance of the focal plane.
    pub focus: f32,
}

impl QuiltViews {
    /// The views of `spec` around `desc` with the focal plane at `focus` (default: the
    /// target distance).
    pub fn new(spec: QuiltSpec, desc: &CameraDesc, focus: Option<f32>) -> Result<Self, SynthError> {
        spec.validate()?;
        let centre = Pinhole::new(desc, spec.view_w, spec.view_h)?;
        let focus = focus.unwrap_or_else(|| (desc.target - desc.eye).length());
        if !(focus.is_finite() && focus > 0.0) {
            return Err(SynthError::Invalid(format!(
                "the focal plane distance must be finite and > 0, got {focus}"
            )));
        }
        Ok(Self {
            spec,
            centre,
            focus,
        })
    }

    /// Sideways offset (metres, along the reference's right axis) of view `i`.
    pub fn offset(&self, i: u32) -> f32 {
        let n = self.spec.views();
        if n <= 1 {
            return 0.0;
        }
        let cone = self.spec.view_cone_deg.to_radians();
        let phi = -0.5 * cone + cone * i as f32 / (n - 1) as f32;
        self.focus * phi.tan()
    }

    /// The largest sideways offset (metres).
    pub fn max_offset(&self) -> f32 {
        self.offset(0)
            .abs()
            .max(self.offset(self.spec.views() - 1).abs())
    }

    /// The off-axis camera of view `i`.
    pub fn camera(&self, i: u32) -> Pinhole {
        let c = &self.centre;
        let x = self.offset(i);
        let frame = CameraFrame {
            position: c.frame.position + c.frame.right() * x,
            basis: c.frame.basis,
        };
        Pinhole::from_frame(frame, c.width, c.height, c.tan_half_y)
            .with_shift(Vec2::new(-x / (self.focus * c.tan_half_x()), 0.0))
    }
}

/// Assembles views (in view order) into the quilt image.
pub fn assemble(spec: &QuiltSpec, views: &[Image<Rgb>]) -> Result<Image<Rgb>, SynthError> {
    if views.len() != spec.views() as usize
        || views
            .iter()
            .any(|v| (v.width(), v.height()) != (spec.view_w, spec.view_h))
    {
        return Err(SynthError::Invalid(format!(
            "a {} x {} quilt of {} x {} tiles needs {} views of that size",
            spec.cols,
            spec.rows,
            spec.view_w,
            spec.view_h,
            spec.views()
        )));
    }
    let (w, h) = spec.size();
    let mut q = Image::new(w, h, Rgb::ZERO)?;
    for (i, v) in views.iter().enumerate() {
        let (x0, y0) = spec.tile_origin(i as u32);
        for y in 0..spec.view_h {
            for x in 0..spec.view_w {
                q.set(x0 + x, y0 + y, *v.get(x, y));
            }
        }
    }
    Ok(q)
}

/// View `i`'s tile cut out of a quilt image.
pub fn tile(spec: &QuiltSpec, quilt: &Image<Rgb>, i: u32) -> Result<Image<Rgb>, SynthError> {
    let (x0, y0) = spec.tile_origin(i);
    Ok(Image::from_fn(spec.view_w, spec.view_h, |x, y| {
        *quilt.get(x0 + x, y0 + y)
    })?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn suffix_and_presets() {
        assert_eq!(
            QuiltSpec::preset("portrait").unwrap().suffix(),
            "_qs8x6a0.75"
        );
        assert_eq!(QuiltSpec::preset("go").unwrap().suffix(), "_qs11x6a0.5625");
        assert_eq!(
            QuiltSpec::preset("16-landscape").unwrap().suffix(),
            "_qs8x6a1.77778"
        );
        assert_eq!(QuiltSpec::preset("8.9in").unwrap().suffix(), "_qs5x9a1.6");
        assert_eq!(QuiltSpec::preset("portrait").unwrap().size(), (3360, 3360));
        assert!(QuiltSpec::preset("nope").is_err());
        assert_eq!(format_g6(2.0), "2");
    }

    #[test]
    fn view_order_bottom_left_to_top_right() {
        let s = QuiltSpec::new(3, 2, 10, 20);
        assert_eq!(s.tile_origin(0), (0, 20));
        assert_eq!(s.tile_origin(2), (20, 20));
        assert_eq!(s.tile_origin(3), (0, 0));
        assert_eq!(s.tile_origin(5), (20, 0));
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -4.0), Vec3::Y, 40.0);
        let v = QuiltViews::new(s, &desc, None).unwrap();
        assert!(v.offset(0) < 0.0 && v.offset(5) > 0.0, "view 0 leftmost");
        assert!((v.offset(0) + v.offset(5)).abs() < 1e-6);
        // Every view sees the focal plane's centre at its image centre (no toe-in, shifted
        // window): the target projects to the centre of every view.
        for i in 0..6 {
            let c = v.camera(i);
            assert_eq!(c.frame.basis, v.centre.frame.basis);
            let f = c
                .film_of_camera_point(c.frame.to_camera(desc.target))
                .unwrap();
            assert!((f - Vec2::new(5.0, 10.0)).length() < 1e-4, "{i}: {f}");
        }
    }

    #[test]
    fn bad_specs_are_errors() {
        let mut s = QuiltSpec::new(0, 6, 10, 10);
        assert!(s.validate().unwrap_err().to_string().contains("views"));
        s.cols = 8;
        s.view_cone_deg = 180.0;
        assert!(s.validate().unwrap_err().to_string().contains("view cone"));
        s.view_cone_deg = 0.0;
        assert!(s.validate().is_err());
        s.view_cone_deg = 35.0;
        s.view_w = 0;
        assert!(s.validate().is_err());
    }
}
