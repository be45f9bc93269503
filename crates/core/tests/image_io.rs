//! EXR and PNG round trips and error cases, G-buffer export.

use std::path::PathBuf;

use parallax_core::glam::{Vec2, Vec3};
use parallax_core::image::png::{
    ToneMapping, Tonemap, read_image, srgb_eotf, srgb_oetf, write_depth_png, write_id_png,
    write_png, write_png_linear_clamped,
};
use parallax_core::{CoreError, GBuffer, GSample, Image, NO_ID, read_exr, write_exr};

/// A fresh per-test directory under cargo's target tmp dir (emptied at the start of a test).
fn tmp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("core-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn exr_round_trips_named_channels_with_infinities() {
    let dir = tmp_dir("exr");
    let (w, h) = (7u32, 5u32);
    let n = (w * h) as usize;
    let depth: Vec<f32> = (0..n)
        .map(|i| {
            if i % 3 == 0 {
                f32::INFINITY
            } else {
                0.1 + i as f32 * 0.37
            }
        })
        .collect();
    let r: Vec<f32> = (0..n).map(|i| i as f32 / n as f32).collect();
    let g: Vec<f32> = (0..n).map(|i| -(i as f32) * 1e-3).collect();
    let b: Vec<f32> = (0..n).map(|i| 1e6 + i as f32).collect();
    let nx: Vec<f32> = (0..n).map(|i| (i as f32).sin()).collect();
    let id: Vec<f32> = (0..n).map(|i| i as f32 * 1000.0).collect();
    let path = dir.join("multi.exr");
    let chans: [(&str, &[f32]); 6] = [
        ("R", &r),
        ("G", &g),
        ("B", &b),
        ("depth", &depth),
        ("normal.X", &nx),
        ("id", &id),
    ];
    write_exr(&path, w, h, &chans).unwrap();
    let img = read_exr(&path).unwrap();
    assert_eq!((img.width, img.height), (w, h));
    assert_eq!(img.channels.len(), 6);
    for (name, data) in chans {
        let got = img
            .channel(name)
            .unwrap_or_else(|| panic!("missing {name}"));
        // Bit-exact: EXR f32 with ZIP is lossless, +inf included.
        let same = got
            .iter()
            .zip(data)
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "channel {name} differs");
    }
    assert!(img.channel("depth").unwrap()[0].is_infinite());
    assert!(img.channel("nope").is_none());
    // EXR sorts channels by name.
    let names: Vec<&str> = img.names().collect();
    assert_eq!(names, ["B", "G", "R", "depth", "id", "normal.X"]);
}

#[test]
fn exr_errors_name_the_path() {
    let dir = tmp_dir("exr-err");
    let data = vec![0.0f32; 6];
    let short = vec![0.0f32; 5];
    let path = dir.join("bad.exr");
    let err = write_exr(&path, 3, 2, &[("R", &data), ("G", &short)]).unwrap_err();
    assert!(matches!(err, CoreError::Format { .. }) && err.to_string().contains("bad.exr"));
    let err = write_exr(&path, 3, 2, &[("R", &data), ("R", &data)]).unwrap_err();
    assert!(err.to_string().contains("duplicate"));
    assert!(write_exr(&path, 3, 2, &[]).is_err());
    assert!(write_exr(&path, 0, 2, &[("R", &data)]).is_err());
    assert!(write_exr(&path, 3, 2, &[("", &data)]).is_err());

    let missing = dir.join("missing.exr");
    let err = read_exr(&missing).unwrap_err();
    assert!(matches!(err, CoreError::ImageIo { .. }));
    assert!(err.to_string().contains("missing.exr"), "{err}");
    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"this is not an exr file at all").unwrap();
    let err = read_exr(&garbage).unwrap_err();
    assert!(err.to_string().contains("garbage.exr"), "{err}");
    // A truncated real file fails cleanly too.
    let good = dir.join("good.exr");
    write_exr(&good, 3, 2, &[("R", &data)]).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let cut = dir.join("cut.exr");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert!(read_exr(&cut).is_err());
}

#[test]
fn gbuffer_exports_to_exr() {
    let dir = tmp_dir("gbuf");
    let mut g = GBuffer::new(4, 3).unwrap();
    let s = GSample {
        depth: 2.0,
        position: Vec3::new(1.0, 2.0, -2.0),
        normal: Vec3::new(0.0, 0.6, 0.8),
        albedo: Vec3::new(0.1, 0.2, 0.3),
        material_id: 4,
        primitive_id: 123_456,
        barycentrics: Vec2::new(0.25, 0.5),
    };
    g.set(1, 2, s);
    let path = dir.join("g.exr");
    g.write_exr(&path).unwrap();
    let e = read_exr(&path).unwrap();
    let i = g.index(1, 2);
    assert_eq!(e.channel("depth").unwrap()[i], 2.0);
    assert!(e.channel("depth").unwrap()[0].is_infinite());
    assert_eq!(e.channel("N.Z").unwrap()[i], 0.8);
    assert_eq!(e.channel("albedo.B").unwrap()[i], 0.3);
    assert_eq!(e.channel("primitiveId").unwrap()[i], 123_456.0);
    assert_eq!(e.channel("materialId").unwrap()[0], -1.0);
    assert_eq!(e.channel("bary.V").unwrap()[i], 0.5);
    assert_eq!(e.channels.len(), 14);
}

#[test]
fn png_round_trip_is_within_quantisation() {
    let dir = tmp_dir("png");
    let img = Image::from_fn(16, 8, |x, y| {
        Vec3::new(x as f32 / 15.0, y as f32 / 7.0, ((x + y) % 5) as f32 / 4.0)
    })
    .unwrap();
    let path = dir.join("rgb.png");
    write_png(&path, &img, &ToneMapping::default()).unwrap();
    let back = read_image(&path).unwrap();
    assert_eq!((back.width(), back.height()), (16, 8));
    // Compare in the encoded domain: at most half an 8-bit step plus rounding.
    for (a, b) in img.data().iter().zip(back.data()) {
        for c in 0..3 {
            let d = (srgb_oetf(a[c]) - srgb_oetf(b[c])).abs();
            assert!(d <= 0.5 / 255.0 + 1e-4, "{a} vs {b}");
        }
    }
    // Exposure and ACES change the output; HDR values stay below white with ACES.
    let hdr = Image::new(2, 2, Vec3::splat(4.0)).unwrap();
    let aces = ToneMapping {
        exposure: 0.0,
        tonemap: Tonemap::AcesFilmic,
    };
    let p2 = dir.join("hdr.png");
    write_png(&p2, &hdr, &aces).unwrap();
    let v = read_image(&p2).unwrap().data()[0].x;
    assert!(v < 1.0 && v > 0.7, "{v}");
    // Unencoded previews store the clamped value itself: 0.5 -> code 128.
    let p3 = dir.join("raw.png");
    let raw = Image::new(2, 2, Vec3::new(0.5, 2.0, -1.0)).unwrap();
    write_png_linear_clamped(&p3, &raw).unwrap();
    let c = read_image(&p3).unwrap().data()[0];
    let want = Vec3::new(srgb_eotf(128.0 / 255.0), 1.0, 0.0);
    assert!((c - want).abs().max_element() < 1e-6, "{c}");
}

#[test]
fn depth_and_id_previews_are_written() {
    let dir = tmp_dir("preview");
    let depth = Image::from_fn(8, 4, |x, _| if x == 0 { f32::INFINITY } else { x as f32 }).unwrap();
    let p = dir.join("depth.png");
    write_depth_png(&p, &depth).unwrap();
    let back = read_image(&p).unwrap();
    assert_eq!(back.get(0, 0).x, 0.0); // miss -> black
    assert_eq!(back.get(1, 0).x, 1.0); // nearest -> white
    assert_eq!(back.get(7, 0).x, 0.0); // farthest -> black
    let ids = Image::from_fn(8, 4, |x, y| if x == 0 { NO_ID } else { x + 8 * y }).unwrap();
    let p = dir.join("ids.png");
    write_id_png(&p, &ids).unwrap();
    let back = read_image(&p).unwrap();
    assert_eq!(*back.get(0, 1), Vec3::ZERO);
    assert!(back.get(1, 1).max_element() > 0.0);
    assert_ne!(back.get(1, 1), back.get(2, 1));
}

#[test]
fn reading_bad_images_fails_with_the_path() {
    let dir = tmp_dir("png-err");
    let p = dir.join("not-a.png");
    std::fs::write(&p, b"\x89PNG\r\n\x1a\n garbage").unwrap();
    let err = read_image(&p).unwrap_err();
    assert!(err.to_string().contains("not-a.png"), "{err}");
    assert!(read_image(dir.join("absent.jpg")).is_err());
    // Writing into a missing directory reports the path.
    let img = Image::new(2, 2, Vec3::ZERO).unwrap();
    let err = write_png(dir.join("no/such/dir.png"), &img, &ToneMapping::default()).unwrap_err();
    assert!(err.to_string().contains("dir.png"), "{err}");
}

#[test]
fn jpeg_is_read_and_srgb_decoded() {
    let dir = tmp_dir("jpeg");
    let p = dir.join("grey.jpg");
    let grey = image::RgbImage::from_pixel(16, 16, image::Rgb([128, 128, 128]));
    grey.save(&p).unwrap();
    let back = read_image(&p).unwrap();
    assert_eq!((back.width(), back.height()), (16, 16));
    // sRGB 128/255 decodes to linear ~0.2158 (JPEG may shift a code value or so).
    let v = back.get(8, 8).x;
    assert!((v - 0.2158).abs() < 0.01, "{v}");
}
