//! Images are written in the format their extension names, linear or tone
//! mapped as the contract says, and atomically.

use glam::Vec3;
use tracer::film::read::read_pfm;
use tracer::film::tonemap::{to_8bit, Tonemap};
use tracer::film::write::write_image;
use tracer::film::Image;

fn gradient() -> Image {
    let mut image = Image::new(7, 5);
    for y in 0..5 {
        for x in 0..7 {
            image.set(
                x,
                y,
                Vec3::new(x as f32 * 0.3, y as f32 * 0.11, 12.5 + x as f32),
            );
        }
    }
    image
}

fn no_temporaries_left(dir: &std::path::Path) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "left behind {name}");
    }
}

#[test]
fn pfm_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.pfm");
    let image = gradient();
    write_image(&path, &image, Tonemap::Srgb, 0.0).unwrap();
    assert_eq!(read_pfm(&path).unwrap(), image);
    no_temporaries_left(dir.path());
}

#[test]
fn exr_is_linear_float() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.exr");
    let image = gradient();
    write_image(&path, &image, Tonemap::Aces, 3.0).unwrap();
    let read = read_first_rgba_layer_from_file(
        &path,
        |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b)
        },
    )
    .unwrap();
    assert_eq!(read.layer_data.size.width(), 7);
    assert_eq!(
        read.layer_data.channel_data.pixels.1, image.pixels,
        "no tone mapping, no exposure"
    );
}

#[test]
fn png_and_tga_are_tone_mapped() {
    let dir = tempfile::tempdir().unwrap();
    let image = gradient();
    for (name, tonemap, exposure) in [
        ("a.png", Tonemap::Srgb, 0.0),
        ("b.tga", Tonemap::Aces, -1.0),
        ("c.png", Tonemap::Gamma, 1.5),
    ] {
        let path = dir.path().join(name);
        write_image(&path, &image, tonemap, exposure).unwrap();
        let decoded = image::open(&path).unwrap().to_rgb8();
        assert_eq!(decoded.dimensions(), (7, 5));
        for y in 0..5 {
            for x in 0..7 {
                assert_eq!(
                    decoded.get_pixel(x, y).0,
                    to_8bit(image.get(x, y), tonemap, exposure),
                    "{name} at {x},{y}"
                );
            }
        }
    }
    no_temporaries_left(dir.path());
}

#[test]
fn failed_write_leaves_previous_file_intact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("keep.pfm");
    std::fs::write(&path, b"precious").unwrap();
    // An unknown extension fails before touching anything.
    assert!(write_image(
        &dir.path().join("keep.bmp"),
        &gradient(),
        Tonemap::Srgb,
        0.0
    )
    .is_err());
    // A folder that does not exist: an error naming the file, nothing written.
    let missing = dir.path().join("no/such/folder/out.png");
    let err = write_image(&missing, &gradient(), Tonemap::Srgb, 0.0).unwrap_err();
    assert!(err.to_string().contains("out.png"), "{err}");
    assert_eq!(std::fs::read(&path).unwrap(), b"precious");
    // A successful write replaces the old file whole.
    write_image(&path, &gradient(), Tonemap::Srgb, 0.0).unwrap();
    assert_eq!(read_pfm(&path).unwrap(), gradient());
    no_temporaries_left(dir.path());
}
