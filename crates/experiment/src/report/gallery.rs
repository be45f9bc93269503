//! Gallery pages of an image folder: every PNG of a plain folder (`parallax report DIR` on a
//! folder without `results.json`), and the captioned gallery that `parallax demo` leaves, its
//! pieces in sections, each with what it shows and its scores, a wipe slider and an error
//! heatmap where the piece has a ground-truth image. Images are referenced beside the page.
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | `dir` | folder | the images, and where `index.html` goes |
//! | `title` | text | the page's title |
//! | `intro` | text | a paragraph under the title (captioned gallery) |
//! | `items` | [`GalleryItem`]s | the pieces, in page order; sections in order of first use |

use std::path::{Path, PathBuf};

use super::html::{self, esc};
use super::{Sources, image_figures, io, truth_figures};
use crate::error::ExperimentError;

/// One captioned piece of a gallery.
#[derive(Clone, Debug)]
pub struct GalleryItem {
    /// The section heading it belongs to (e.g. the paper it implements).
    pub section: String,
    /// The piece's title.
    pub title: String,
    /// What the piece shows, its settings and scores (plain text).
    pub caption: String,
    /// Its images (file names in the folder); the first is the result.
    pub images: Vec<String>,
    /// The ground truth of the first image (a file name in the folder), if it has one.
    pub truth: Option<String>,
}

/// The PNGs directly in `dir` (not error maps the pages generate), sorted.
fn folder_images(dir: &Path) -> Result<Vec<String>, ExperimentError> {
    let mut images: Vec<String> = Vec::new();
    for e in std::fs::read_dir(dir).map_err(io(dir))? {
        let e = e.map_err(io(dir))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with(".png") && !name.ends_with(".error.png") && e.path().is_file() {
            images.push(name);
        }
    }
    images.sort();
    Ok(images)
}

fn sources(dir: &Path) -> Sources {
    Sources {
        base: dir.to_path_buf(),
        inline: false,
        generated: PathBuf::from("report"),
    }
}

fn write_page(dir: &Path, title: &str, body: &str) -> Result<PathBuf, ExperimentError> {
    let page = dir.join("index.html");
    std::fs::write(&page, html::page(title, body)).map_err(io(&page))?;
    Ok(page)
}

/// Writes `DIR/index.html`: every PNG in `dir` (not its subfolders), sorted, with the same
/// figures as a report's points. Returns the page's path.
pub fn write_gallery(dir: &Path, title: &str) -> Result<PathBuf, ExperimentError> {
    let images = folder_images(dir)?;
    let body = format!(
        "<p class=\"meta\">{} images in <code>{}</code></p>{}",
        images.len(),
        esc(&dir.display().to_string()),
        image_figures(&images, &sources(dir), "")?
    );
    write_page(dir, title, &body)
}

/// Writes `DIR/index.html` with `items` in sections (in the order they first appear), each
/// item's caption under its title, its result beside its ground truth (wipe slider, error
/// heatmap, the truth itself) and its other images; PNGs of the folder that no item names
/// follow under "Other images". Every named image must exist. Returns the page's path.
pub fn write_captioned_gallery(
    dir: &Path,
    title: &str,
    intro: &str,
    items: &[GalleryItem],
) -> Result<PathBuf, ExperimentError> {
    let src = sources(dir);
    let mut sections: Vec<&str> = Vec::new();
    for it in items {
        if !sections.contains(&it.section.as_str()) {
            sections.push(&it.section);
        }
    }
    let mut named: Vec<&str> = Vec::new();
    let mut body = format!("<p>{}</p>", esc(intro));
    for section in sections {
        body += &format!("<h2>{}</h2>", esc(section));
        for it in items.iter().filter(|it| it.section == section) {
            body += &format!(
                "<h3>{}</h3><p class=\"meta\">{}</p><div class=\"grid\">",
                esc(&it.title),
                esc(&it.caption)
            );
            let mut rest = it.images.iter().map(String::as_str);
            if let (Some(truth), Some(first)) = (&it.truth, it.images.first()) {
                rest.next();
                let stem = first.strip_suffix(".png").unwrap_or(first);
                body += &truth_figures(first, truth, stem, &src, "")?;
                body += &html::figure(&src.file(truth)?, &format!("{truth}: ground truth (BVH)"));
                named.extend([first.as_str(), truth.as_str()]);
            }
            for img in rest {
                body += &html::figure(&src.file(img)?, img);
                named.push(img);
            }
            body += "</div>";
        }
    }
    for img in named.iter() {
        let p = dir.join(img);
        if !p.is_file() {
            return Err(ExperimentError::Report(format!(
                "gallery image {} does not exist",
                p.display()
            )));
        }
    }
    let others: Vec<String> = folder_images(dir)?
        .into_iter()
        .filter(|i| !named.contains(&i.as_str()))
        .collect();
    if !others.is_empty() {
        body += &format!("<h2>Other images</h2>{}", image_figures(&others, &src, "")?);
    }
    write_page(dir, title, &body)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(dir: &Path, name: &str, v: u8) {
        let img = image::RgbImage::from_fn(8, 4, |x, _| image::Rgb([v, x as u8 * 16, 0]));
        img.save(dir.join(name)).unwrap();
    }

    #[test]
    fn captioned_gallery_has_sections_captions_wipes_and_the_rest() {
        let dir = std::env::temp_dir().join(format!("parallax-gallery-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (n, v) in [
            ("a.png", 10),
            ("a_bvh.png", 20),
            ("b.png", 30),
            ("loose.png", 40),
        ] {
            png(&dir, n, v);
        }
        let items = [
            GalleryItem {
                section: "Paper one".into(),
                title: "A against its truth".into(),
                caption: "scores <1 dB".into(),
                images: vec!["a.png".into()],
                truth: Some("a_bvh.png".into()),
            },
            GalleryItem {
                section: "Paper two".into(),
                title: "B".into(),
                caption: "plain".into(),
                images: vec!["b.png".into()],
                truth: None,
            },
        ];
        let page = write_captioned_gallery(&dir, "t", "intro", &items).unwrap();
        let html = std::fs::read_to_string(page).unwrap();
        let at = |s: &str| html.find(s).unwrap_or_else(|| panic!("{s} missing"));
        assert!(at("<h2>Paper one") < at("<h2>Paper two"));
        assert!(html.contains("scores &lt;1 dB"), "caption escaped");
        assert!(html.contains("class=\"wipe\""), "a has a wipe");
        assert!(
            dir.join("report/a.error.png").is_file(),
            "error heatmap written"
        );
        assert!(at("<h2>Other images") < at("src=\"loose.png\""));
        assert_eq!(html.matches("src=\"b.png\"").count(), 1, "b only once");
        let missing = [GalleryItem {
            images: vec!["nope.png".into()],
            truth: None,
            ..items[1].clone()
        }];
        assert!(write_captioned_gallery(&dir, "t", "", &missing).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
