//! EXR and PNG files: round trips, byte determinism, atomic writes, error messages.

use std::path::Path;
use vkvcm::image::{read_exr, write_exr, write_exr_with, write_png, ExrCompression, Image};

fn meta(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

/// An image with smooth areas, noise-like detail, negative and extreme values.
fn test_image(w: u32, h: u32) -> Image {
    Image::from_fn(w, h, |x, y| {
        let n = (x.wrapping_mul(2_654_435_761) ^ y.wrapping_mul(40_503)) as f32 / u32::MAX as f32;
        [x as f32 / w as f32, (y as f32 * 0.37).sin() * 10.0, n * 1e-3 + if x == 3 && y == 1 { 6.5e4 } else { 0.0 }]
    })
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.data.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn exr_round_trip_is_exact_with_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let mut img = test_image(37, 21);
    img.set(0, 0, [f32::INFINITY, -0.0, f32::MIN_POSITIVE / 4.0]); // inf, negative zero, subnormal
    img.set(36, 20, [f32::MAX, -1e-30, 1.0]);
    let m = meta(&[
        ("vkvcm:seed", "42"),
        ("vkvcm:estimator", "vcm"),
        ("vkvcm:iterations", "1000"),
        ("vkvcm:seconds", "12.5"),
        ("vkvcm:device", "llvmpipe (LLVM 19.1.7, 256 bits) — ünïcode"),
        ("vkvcm:empty", ""),
        ("vkvcm:a-key-longer-than-thirty-one-bytes", "needs the long-names flag"),
    ]);
    for compression in [ExrCompression::Zip, ExrCompression::None] {
        let path = dir.path().join(format!("{compression:?}.exr"));
        write_exr_with(&path, &img, &m, compression).unwrap();
        let (back, back_meta) = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (37, 21));
        assert_eq!(bits(&back), bits(&img), "{compression:?} changed pixel bits");
        let mut sorted = m.clone();
        sorted.sort();
        assert_eq!(back_meta, sorted, "metadata comes back sorted by key");
    }
    // ZIP is smaller on a smooth image.
    let smooth = Image::from_fn(256, 64, |x, _| [x as f32 / 256.0, 0.5, 0.25]);
    let (zip, raw) = (dir.path().join("s_zip.exr"), dir.path().join("s_raw.exr"));
    write_exr_with(&zip, &smooth, &[], ExrCompression::Zip).unwrap();
    write_exr_with(&raw, &smooth, &[], ExrCompression::None).unwrap();
    let (zl, rl) = (std::fs::metadata(&zip).unwrap().len(), std::fs::metadata(&raw).unwrap().len());
    assert!(zl * 4 < rl, "zip {zl} bytes, raw {rl} bytes");
    assert!(rl > 256 * 64 * 12, "float32 RGB");
    assert_eq!(read_exr(&zip).unwrap().0, smooth);
}

#[test]
fn exr_bytes_are_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let img = test_image(64, 40);
    let m = meta(&[("vkvcm:b", "2"), ("vkvcm:a", "1"), ("vkvcm:c", "3")]);
    let mut reversed = m.clone();
    reversed.reverse();
    for compression in [ExrCompression::Zip, ExrCompression::None] {
        let (p1, p2) = (dir.path().join("one.exr"), dir.path().join("two.exr"));
        write_exr_with(&p1, &img, &m, compression).unwrap();
        write_exr_with(&p2, &img.clone(), &reversed, compression).unwrap();
        let (b1, b2) = (std::fs::read(&p1).unwrap(), std::fs::read(&p2).unwrap());
        assert_eq!(b1, b2, "{compression:?}: same image and metadata must give the same bytes");
        // Any change shows.
        let mut other = img.clone();
        other.data[100][1] += 1e-3;
        write_exr_with(&p2, &other, &m, compression).unwrap();
        assert_ne!(b1, std::fs::read(&p2).unwrap());
    }
    // The header is what we promise: magic, version 2, attributes in order, no time stamps.
    let p = dir.path().join("h.exr");
    write_exr_with(&p, &Image::new(2, 1), &meta(&[("vkvcm:seed", "7")]), ExrCompression::None).unwrap();
    let b = std::fs::read(&p).unwrap();
    assert_eq!(&b[..8], &[0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0]);
    let text = String::from_utf8_lossy(&b);
    let order = ["channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio"];
    let pos: Vec<usize> = order.iter().map(|n| text.find(n).unwrap()).collect();
    assert!(pos.windows(2).all(|w| w[0] < w[1]), "{pos:?}");
    assert!(text.contains("vkvcm:seed\0string\0"));
    // header + 1 offset + chunk (y, size, 2 px x 3 ch x 4 bytes)
    let header_end = b.len() - 8 - 8 - 24;
    assert_eq!(b[header_end - 1], 0, "header ends with a null byte");
}

#[test]
fn exr_written_by_the_exr_crate_reads_back() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("half.exr");
    // Half-float RGBA with a custom text attribute and a non-text attribute.
    let mut attributes = LayerAttributes::named("beauty");
    attributes.other.insert(Text::new_or_panic("vkvcm:estimator"), AttributeValue::Text(Text::new_or_panic("pt")));
    attributes.other.insert(Text::new_or_panic("vkvcm:number"), AttributeValue::F32(3.0));
    let layer = Layer::new(
        (5, 3),
        attributes,
        Encoding::SMALL_LOSSLESS,
        SpecificChannels::rgba(|Vec2(x, y)| {
            (f16::from_f32(x as f32), f16::from_f32(y as f32 * 0.5), f16::from_f32(0.25), f16::from_f32(1.0))
        }),
    );
    exr::image::Image::from_layer(layer).write().to_file(&path).unwrap();
    let (img, m) = read_exr(&path).unwrap();
    assert_eq!((img.width, img.height), (5, 3));
    assert_eq!(img.get(4, 2), [4.0, 1.0, 0.25]);
    assert_eq!(m, meta(&[("vkvcm:estimator", "pt")]));

    // Missing channels: the error names the file and the channels found.
    let path = dir.path().join("luma.exr");
    let layer = Layer::new(
        (2, 2),
        LayerAttributes::default(),
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(SmallVec::from_vec(vec![AnyChannel::new("Y", FlatSamples::F32(vec![0.5; 4]))])),
    );
    exr::image::Image::from_layer(layer).write().to_file(&path).unwrap();
    let err = read_exr(&path).unwrap_err().to_string();
    assert!(err.contains(&path.display().to_string()) && err.contains("R, G and B") && err.contains('Y'), "{err}");
}

#[test]
fn read_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.exr");
    let err = read_exr(&missing).unwrap_err().to_string();
    assert!(err.contains(&missing.display().to_string()), "{err}");
    let garbage = dir.path().join("garbage.exr");
    std::fs::write(&garbage, b"not an exr file").unwrap();
    let err = read_exr(&garbage).unwrap_err().to_string();
    assert!(err.contains(&garbage.display().to_string()), "{err}");
}

#[test]
fn invalid_inputs_are_rejected_before_touching_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.exr");
    let img = test_image(8, 8);
    write_exr(&path, &img, &[]).unwrap();
    let before = std::fs::read(&path).unwrap();
    for bad in [
        meta(&[("owner", "someone")]),               // standard attribute
        meta(&[("channels", "x")]),                  // required attribute
        meta(&[("", "x")]),                          // empty key
        meta(&[("a\0b", "x")]),                      // NUL
        meta(&[("vkvcm:x", "1"), ("vkvcm:x", "2")]), // duplicate
    ] {
        let err = write_exr(&path, &img, &bad).unwrap_err().to_string();
        assert!(err.contains(&path.display().to_string()), "{err}");
    }
    let err = write_exr(&path, &Image::new(0, 4), &[]).unwrap_err().to_string();
    assert!(err.contains("empty"), "{err}");
    let err = write_png(&path.with_extension("png"), &Image::new(3, 0), 1.0).unwrap_err().to_string();
    assert!(err.contains("empty"), "{err}");
    assert_eq!(std::fs::read(&path).unwrap(), before, "a failed write must leave the old file alone");
    assert_eq!(files_in(dir.path()), vec!["good.exr".to_string()], "no temporary files left behind");
}

#[test]
fn unwritable_paths_give_one_line_errors_with_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let img = test_image(4, 4);

    let missing = dir.path().join("no/such/dir/out.exr");
    let err = write_exr(&missing, &img, &[]).unwrap_err().to_string();
    assert!(err.contains(&missing.display().to_string()) && err.contains("does not exist"), "{err}");
    assert!(!err.contains('\n'), "one line: {err}");
    let err = write_png(&missing.with_extension("png"), &img, 1.0).unwrap_err().to_string();
    assert!(err.contains("out.png") && err.contains("does not exist"), "{err}");

    let file = dir.path().join("plain-file");
    std::fs::write(&file, b"x").unwrap();
    let under_file = file.join("out.exr");
    let err = write_exr(&under_file, &img, &[]).unwrap_err().to_string();
    assert!(err.contains(&under_file.display().to_string()) && err.contains("not a directory"), "{err}");

    let is_dir = dir.path().join("a-directory.exr");
    std::fs::create_dir(&is_dir).unwrap();
    let err = write_exr(&is_dir, &img, &[]).unwrap_err().to_string();
    assert!(err.contains(&is_dir.display().to_string()), "{err}");

    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = dir.path().join("read-only");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        // root ignores directory permissions; only check where they apply.
        if std::fs::write(ro.join("probe"), b"").is_err() {
            let target = ro.join("out.exr");
            let err = write_exr(&target, &img, &[]).unwrap_err().to_string();
            assert!(err.contains(&target.display().to_string()), "{err}");
            assert!(!err.contains('\n'), "one line: {err}");
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

#[test]
fn atomic_writes_replace_and_leave_no_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("render.exr");
    let png = dir.path().join("render.png");
    for i in 0..3 {
        let img = Image::filled(16, 8, [i as f32, 0.5, 1.0]);
        write_exr(&path, &img, &meta(&[("vkvcm:iterations", &i.to_string())])).unwrap();
        write_png(&png, &img, 1.0).unwrap();
        let (back, m) = read_exr(&path).unwrap();
        assert_eq!(back, img);
        assert_eq!(m[0].1, i.to_string());
    }
    assert_eq!(files_in(dir.path()), vec!["render.exr".to_string(), "render.png".to_string()]);

    // A relative path (no directory part) writes into the current directory.
    let cwd = std::env::current_dir().unwrap();
    let rel = format!("image_io_relative_{}.exr", std::process::id());
    write_exr(Path::new(&rel), &Image::new(1, 1), &[]).unwrap();
    assert!(cwd.join(&rel).is_file());
    std::fs::remove_file(cwd.join(&rel)).unwrap();

    #[cfg(unix)]
    {
        // Not the 0600 of a temporary file: the same mode as any file this process creates.
        use std::os::unix::fs::PermissionsExt;
        let plain = dir.path().join("plain");
        std::fs::write(&plain, b"").unwrap();
        let want = std::fs::metadata(&plain).unwrap().permissions().mode() & 0o777;
        assert_eq!(std::fs::metadata(&path).unwrap().permissions().mode() & 0o777, want);
        assert_eq!(std::fs::metadata(&png).unwrap().permissions().mode() & 0o777, want);
    }
}

#[test]
fn png_is_tone_mapped_srgb_and_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let img = Image::from_data(
        6,
        1,
        vec![
            [0.0, 1.0, 0.5],
            [0.25, 2.0, -1.0],
            [f32::NAN, f32::INFINITY, 0.001],
            [0.0031308, 0.18, 0.9],
            [1e-5, 0.0, 0.0],
            [0.5; 3],
        ],
    )
    .unwrap();
    let path = dir.path().join("a.png");
    write_png(&path, &img, 1.0).unwrap();
    let decoded = image::open(&path).unwrap().to_rgb8();
    assert_eq!(decoded.dimensions(), (6, 1));
    let px = |x: u32| decoded.get_pixel(x, 0).0;
    assert_eq!(px(0), [0, 255, 188]); // sRGB(0.5) = 0.7354
    assert_eq!(px(1), [137, 255, 0]); // sRGB(0.25) = 0.5371; clamp above 1 and below 0
    assert_eq!(px(2), [0, 255, 3]); // NaN -> 0; 0.001 * 12.92 * 255 = 3.3
    assert_eq!(px(3), [10, 118, 243]);
    assert_eq!(px(4), [0, 0, 0]);

    // exposure is a linear scale: 0.25 at exposure 2 looks like 0.5.
    let p2 = dir.path().join("b.png");
    write_png(&p2, &Image::filled(1, 1, [0.25; 3]), 2.0).unwrap();
    assert_eq!(image::open(&p2).unwrap().to_rgb8().get_pixel(0, 0).0, [188; 3]);

    let p3 = dir.path().join("c.png");
    write_png(&p3, &img, 1.0).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), std::fs::read(&p3).unwrap());
}
