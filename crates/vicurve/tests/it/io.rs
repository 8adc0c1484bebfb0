//! Tests of image and polyline file input-output.
//!
//! Files are written with the `image` and `tiff` crates directly (an
//! independent writer) wherever the reader is under test.

use std::io::Cursor;
use std::path::PathBuf;

use image::{DynamicImage, ImageBuffer, ImageFormat, Luma, LumaA, Rgb, Rgba};
use proptest::prelude::*;
use vicurve::io::{load_image, parse_polyline_csv, read_polyline_csv, save_image};
use vicurve::{Error, Image};

/// A fresh directory for one test, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("vicurve-io-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
    fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
    fn write(&self, file: &str, bytes: &[u8]) -> PathBuf {
        let p = self.path(file);
        std::fs::write(&p, bytes).unwrap();
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn encode(image: &DynamicImage, format: ImageFormat) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    image.write_to(&mut out, format).unwrap();
    out.into_inner()
}

/// A 7x5 test image whose 8-bit levels are all different.
fn gray8_levels() -> ImageBuffer<Luma<u8>, Vec<u8>> {
    ImageBuffer::from_fn(7, 5, |x, y| Luma([(x * 37 + y * 11 + 3) as u8]))
}

fn luma(r: f64, g: f64, b: f64) -> f64 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

fn assert_close(a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((x - y).abs() <= tol, "pixel {i}: {x} vs {y}");
    }
}

// ---------------------------------------------------------------- reading

#[test]
fn gray8_png_and_tiff_are_divided_by_255() {
    let dir = TempDir::new("gray8");
    let buffer = gray8_levels();
    let expected: Vec<f64> = buffer
        .as_raw()
        .iter()
        .map(|&v| f64::from(v) / 255.0)
        .collect();
    for (name, format) in [("a.png", ImageFormat::Png), ("a.tif", ImageFormat::Tiff)] {
        let p = dir.write(
            name,
            &encode(&DynamicImage::ImageLuma8(buffer.clone()), format),
        );
        let image = load_image(&p).unwrap();
        assert_eq!((image.width(), image.height()), (7, 5));
        assert_eq!(image.data(), &expected[..], "{name}");
        // Row-major with x = column: pixel (x=4, y=2).
        assert_eq!(image.get(4, 2), f64::from(4 * 37 + 2 * 11 + 3) / 255.0);
    }
}

/// Every one of the 256 levels (read through a table of them), bit for
/// bit.
#[test]
fn every_8_bit_level_reads_as_level_over_255() {
    let dir = TempDir::new("gray8-all");
    let buffer: ImageBuffer<Luma<u8>, Vec<u8>> =
        ImageBuffer::from_fn(16, 16, |x, y| Luma([(y * 16 + x) as u8]));
    let p = dir.write(
        "all.png",
        &encode(&DynamicImage::ImageLuma8(buffer), ImageFormat::Png),
    );
    let image = load_image(&p).unwrap();
    for (k, v) in image.data().iter().enumerate() {
        assert_eq!(v.to_bits(), (k as f64 / 255.0).to_bits(), "level {k}");
    }
}

#[test]
fn gray16_png_and_tiff_are_divided_by_65535() {
    let dir = TempDir::new("gray16");
    let buffer: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_fn(6, 4, |x, y| Luma([(x * 9001 + y * 1237 + 1) as u16]));
    let expected: Vec<f64> = buffer
        .as_raw()
        .iter()
        .map(|&v| f64::from(v) / 65535.0)
        .collect();
    for (name, format) in [("a.png", ImageFormat::Png), ("a.tiff", ImageFormat::Tiff)] {
        let p = dir.write(
            name,
            &encode(&DynamicImage::ImageLuma16(buffer.clone()), format),
        );
        assert_eq!(load_image(&p).unwrap().data(), &expected[..], "{name}");
    }
}

#[test]
fn rgb_and_rgba_png_become_rec709_luma_of_stored_values() {
    let dir = TempDir::new("rgb");
    let rgb: ImageBuffer<Rgb<u8>, Vec<u8>> = ImageBuffer::from_fn(5, 3, |x, y| {
        Rgb([(x * 50) as u8, (y * 100 + 7) as u8, (255 - x * 20) as u8])
    });
    let expected: Vec<f64> = rgb
        .pixels()
        .map(|p| luma(p[0].into(), p[1].into(), p[2].into()) / 255.0)
        .collect();
    let p = dir.write(
        "rgb.png",
        &encode(&DynamicImage::ImageRgb8(rgb.clone()), ImageFormat::Png),
    );
    assert_close(load_image(&p).unwrap().data(), &expected, 1e-12);

    // Alpha is ignored: fully transparent pixels keep their colour's gray.
    let rgba: ImageBuffer<Rgba<u8>, Vec<u8>> = ImageBuffer::from_fn(5, 3, |x, y| {
        let c = rgb.get_pixel(x, y);
        Rgba([c[0], c[1], c[2], (x * 60) as u8])
    });
    let p = dir.write(
        "rgba.png",
        &encode(&DynamicImage::ImageRgba8(rgba), ImageFormat::Png),
    );
    assert_close(load_image(&p).unwrap().data(), &expected, 1e-12);

    // Pure primaries give exactly the weights.
    let primaries: ImageBuffer<Rgb<u8>, Vec<u8>> = ImageBuffer::from_fn(3, 1, |x, _| {
        let mut c = [0u8; 3];
        c[x as usize] = 255;
        Rgb(c)
    });
    let p = dir.write(
        "prim.png",
        &encode(&DynamicImage::ImageRgb8(primaries), ImageFormat::Png),
    );
    assert_close(
        load_image(&p).unwrap().data(),
        &[0.2126, 0.7152, 0.0722],
        1e-15,
    );
}

#[test]
fn rgb16_png_and_tiff_are_luma_divided_by_65535() {
    let dir = TempDir::new("rgb16");
    let rgb: ImageBuffer<Rgb<u16>, Vec<u16>> = ImageBuffer::from_fn(4, 4, |x, y| {
        Rgb([
            (x * 16000) as u16,
            (y * 20000 + 5) as u16,
            65535 - (x * y * 3000) as u16,
        ])
    });
    let expected: Vec<f64> = rgb
        .pixels()
        .map(|p| luma(p[0].into(), p[1].into(), p[2].into()) / 65535.0)
        .collect();
    for (name, format) in [("a.png", ImageFormat::Png), ("a.tif", ImageFormat::Tiff)] {
        let p = dir.write(
            name,
            &encode(&DynamicImage::ImageRgb16(rgb.clone()), format),
        );
        assert_close(load_image(&p).unwrap().data(), &expected, 1e-12);
    }
}

#[test]
fn gray_alpha_gives_the_gray_channel() {
    let dir = TempDir::new("la");
    let la: ImageBuffer<LumaA<u8>, Vec<u8>> = ImageBuffer::from_fn(3, 2, |x, y| {
        LumaA([(x * 80 + y) as u8, (255 - x * 100) as u8])
    });
    let p = dir.write(
        "la.png",
        &encode(&DynamicImage::ImageLumaA8(la.clone()), ImageFormat::Png),
    );
    let expected: Vec<f64> = la.pixels().map(|p| f64::from(p[0]) / 255.0).collect();
    assert_eq!(load_image(&p).unwrap().data(), &expected[..]);
}

#[test]
fn jpeg_gray_and_colour_load_close_to_the_original() {
    let dir = TempDir::new("jpeg");
    // A smooth image so that JPEG's loss stays small.
    let gray: ImageBuffer<Luma<u8>, Vec<u8>> =
        ImageBuffer::from_fn(32, 24, |x, y| Luma([(40 + 4 * x + 2 * y) as u8]));
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100)
        .encode_image(&DynamicImage::ImageLuma8(gray.clone()))
        .unwrap();
    let p = dir.write("g.jpg", &bytes);
    let image = load_image(&p).unwrap();
    assert_eq!((image.width(), image.height()), (32, 24));
    let expected: Vec<f64> = gray
        .as_raw()
        .iter()
        .map(|&v| f64::from(v) / 255.0)
        .collect();
    assert_close(image.data(), &expected, 3.0 / 255.0);

    let rgb: ImageBuffer<Rgb<u8>, Vec<u8>> = ImageBuffer::from_fn(32, 24, |x, y| {
        Rgb([(100 + 3 * x) as u8, (50 + 4 * y) as u8, 120])
    });
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100)
        .encode_image(&DynamicImage::ImageRgb8(rgb.clone()))
        .unwrap();
    let p = dir.write("c.jpeg", &bytes);
    let expected: Vec<f64> = rgb
        .pixels()
        .map(|p| luma(p[0].into(), p[1].into(), p[2].into()) / 255.0)
        .collect();
    // Chroma subsampling and YCbCr rounding: a few levels.
    assert_close(load_image(&p).unwrap().data(), &expected, 6.0 / 255.0);
}

fn float_tiff<C: tiff::encoder::colortype::ColorType>(w: u32, h: u32, data: &[C::Inner]) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut out = Cursor::new(Vec::new());
    tiff::encoder::TiffEncoder::new(&mut out)
        .unwrap()
        .write_image::<C>(w, h, data)
        .unwrap();
    out.into_inner()
}

#[test]
fn float_gray_tiff_is_kept_as_is() {
    use tiff::encoder::colortype::{Gray32Float, Gray64Float};
    let dir = TempDir::new("float");
    let values32: Vec<f32> = vec![-3.25, 0.0, 1.0e3, 0.1, 7.5, -0.001];
    let p = dir.write("f32.tif", &float_tiff::<Gray32Float>(3, 2, &values32));
    let image = load_image(&p).unwrap();
    assert_eq!((image.width(), image.height()), (3, 2));
    let expected: Vec<f64> = values32.iter().map(|&v| f64::from(v)).collect();
    assert_eq!(image.data(), &expected[..]);

    let values64 = vec![1.0e-9, -2.5, 123456.789, 0.5];
    let p = dir.write("f64.tif", &float_tiff::<Gray64Float>(2, 2, &values64));
    assert_eq!(load_image(&p).unwrap().data(), &values64[..]);

    // A NaN pixel is refused, naming the file.
    let p = dir.write(
        "nan.tif",
        &float_tiff::<Gray32Float>(2, 1, &[0.5, f32::NAN]),
    );
    match load_image(&p) {
        Err(Error::NonFinite { what }) => assert!(what.contains("nan.tif"), "{what}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn float_rgb_tiff_is_luma_of_values_as_is() {
    use tiff::encoder::colortype::RGB32Float;
    let dir = TempDir::new("frgb");
    let values: Vec<f32> = vec![2.0, 0.5, -1.0, 0.0, 10.0, 0.25];
    let p = dir.write("rgb.tif", &float_tiff::<RGB32Float>(2, 1, &values));
    assert_close(
        load_image(&p).unwrap().data(),
        &[luma(2.0, 0.5, -1.0), luma(0.0, 10.0, 0.25)],
        1e-6,
    );
}

#[test]
fn format_comes_from_content_not_extension() {
    let dir = TempDir::new("magic");
    let buffer = gray8_levels();
    let p = dir.write(
        "really_a_png.tif",
        &encode(&DynamicImage::ImageLuma8(buffer), ImageFormat::Png),
    );
    assert_eq!(load_image(&p).unwrap().width(), 7);
}

// ---------------------------------------------------------------- errors

fn expect_decode(result: vicurve::Result<Image>, what: &str) {
    match result {
        Err(Error::Decode { reason, .. }) => assert!(!reason.is_empty()),
        Ok(image) => panic!(
            "{what}: expected Error::Decode, got a {}x{} image",
            image.width(),
            image.height()
        ),
        Err(other) => panic!("{what}: expected Error::Decode, got {other:?}"),
    }
}

fn expect_unsupported(result: vicurve::Result<Image>, what: &str) -> String {
    match result {
        Err(e @ Error::UnsupportedImage { .. }) => {
            let message = e.to_string();
            assert!(
                message.contains("PNG") && message.contains("TIFF") && message.contains("JPEG"),
                "{what}: the message should name the supported formats: {message}"
            );
            message
        }
        other => panic!("{what}: expected Error::UnsupportedImage, got {other:?}"),
    }
}

#[test]
fn missing_file_is_not_found_and_directory_is_io() {
    let dir = TempDir::new("missing");
    let missing = dir.path("nope.png");
    assert!(matches!(load_image(&missing), Err(Error::NotFound { path }) if path == missing));
    assert!(matches!(load_image(&dir.0), Err(Error::Io { .. })));
    assert!(matches!(
        read_polyline_csv(&missing),
        Err(Error::NotFound { .. })
    ));
    assert!(matches!(read_polyline_csv(&dir.0), Err(Error::Io { .. })));
}

#[test]
fn non_images_are_unsupported() {
    let dir = TempDir::new("unsupported");
    let text = dir.write("x.png", b"x,y\n1,2\n");
    expect_unsupported(load_image(&text), "text");
    let empty = dir.write("empty.png", b"");
    let message = expect_unsupported(load_image(&empty), "empty");
    assert!(message.contains("empty"), "{message}");
    let gif = dir.write("a.gif", b"GIF89a\x01\x00\x01\x00\x00\x00\x00;");
    let message = expect_unsupported(load_image(&gif), "gif");
    assert!(message.contains("Gif"), "{message}");
    let bmp = dir.write(
        "a.png",
        b"BM\x3a\x00\x00\x00\x00\x00\x00\x00\x36\x00\x00\x00",
    );
    expect_unsupported(load_image(&bmp), "bmp");
}

#[test]
fn truncated_files_are_decode_errors() {
    let dir = TempDir::new("truncated");
    // Noisy content so that the compressed data are not tiny.
    let buffer: ImageBuffer<Luma<u8>, Vec<u8>> =
        ImageBuffer::from_fn(64, 48, |x, y| Luma([((x * 7919 + y * 104729) % 251) as u8]));
    let image = DynamicImage::ImageLuma8(buffer);
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 90)
        .encode_image(&image)
        .unwrap();
    for (name, bytes) in [
        ("t.png", encode(&image, ImageFormat::Png)),
        ("t.tif", encode(&image, ImageFormat::Tiff)),
        ("t.jpg", jpeg),
    ] {
        assert!(load_image(&dir.write(name, &bytes)).is_ok(), "{name} whole");
        // Cutting a PNG's final IEND chunk loses no pixel, so it may load.
        let last = if name == "t.png" {
            bytes.len() - 12
        } else {
            bytes.len() - 1
        };
        for cut in [bytes.len() / 2, last, bytes.len() * 9 / 10, 20] {
            let p = dir.write(name, &bytes[..cut]);
            expect_decode(
                load_image(&p),
                &format!("{name} cut at {cut} of {}", bytes.len()),
            );
        }
    }
}

#[test]
fn jpeg_completeness_check_skips_thumbnails_and_tolerates_trailing_bytes() {
    let dir = TempDir::new("jpegthumb");
    let gray: ImageBuffer<Luma<u8>, Vec<u8>> =
        ImageBuffer::from_fn(16, 16, |x, y| Luma([(x * 10 + y) as u8]));
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 90)
        .encode_image(&DynamicImage::ImageLuma8(gray))
        .unwrap();
    // An APP1 segment holding a fake thumbnail with its own SOI..EOI, right
    // after the SOI: a naive search for the EOI marker would find it.
    let payload = b"Exif\0\0\xFF\xD8\xFF\xDA\x00\x02\x12\x34\xFF\xD9";
    let mut with_thumb = jpeg[..2].to_vec();
    with_thumb.extend_from_slice(&[0xFF, 0xE1]);
    with_thumb.extend_from_slice(&((payload.len() + 2) as u16).to_be_bytes());
    with_thumb.extend_from_slice(payload);
    with_thumb.extend_from_slice(&jpeg[2..]);
    let p = dir.write("thumb.jpg", &with_thumb);
    assert!(load_image(&p).is_ok());
    let p = dir.write("thumb_cut.jpg", &with_thumb[..with_thumb.len() - 40]);
    expect_decode(load_image(&p), "truncated with thumbnail");

    let mut trailing = jpeg.clone();
    trailing.extend_from_slice(b"\0\0some trailing bytes");
    let p = dir.write("trailing.jpg", &trailing);
    assert!(load_image(&p).is_ok());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Random bytes after each accepted magic number: an error, never a panic.
    #[test]
    fn random_bytes_give_errors_not_panics(
        magic in 0usize..5,
        body in proptest::collection::vec(any::<u8>(), 0..300),
    ) {
        let prefixes: [&[u8]; 5] = [b"\x89PNG\r\n\x1a\n", &[0xFF, 0xD8, 0xFF], b"II*\0", b"MM\0*", b""];
        let mut bytes = prefixes[magic].to_vec();
        bytes.extend_from_slice(&body);
        let dir = TempDir::new("random");
        let p = dir.write("r.img", &bytes);
        let result = load_image(&p);
        prop_assert!(result.is_err(), "{:?}", result);
    }
}

#[test]
fn zero_pixel_tiff_is_an_error() {
    // A hand-made little-endian TIFF whose width is 0 (the encoders refuse to
    // write one). Decoders may refuse it as malformed before we see the size;
    // either way it must be an error, not a panic nor an empty Image.
    let dir = TempDir::new("zero");
    let mut t: Vec<u8> = b"II*\0\x08\0\0\0".to_vec();
    let entries: [(u16, u16, u32); 8] = [
        (256, 4, 0),   // ImageWidth = 0
        (257, 4, 4),   // ImageLength
        (258, 3, 8),   // BitsPerSample
        (259, 3, 1),   // Compression: none
        (262, 3, 1),   // Photometric: black is zero
        (273, 4, 200), // StripOffsets
        (278, 4, 4),   // RowsPerStrip
        (279, 4, 0),   // StripByteCounts
    ];
    t.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    for (tag, kind, value) in entries {
        t.extend_from_slice(&tag.to_le_bytes());
        t.extend_from_slice(&kind.to_le_bytes());
        t.extend_from_slice(&1u32.to_le_bytes());
        t.extend_from_slice(&value.to_le_bytes());
    }
    t.extend_from_slice(&0u32.to_le_bytes());
    t.resize(210, 0);
    let p = dir.write("zero.tif", &t);
    match load_image(&p) {
        Err(Error::EmptyImage { .. } | Error::Decode { .. }) => {}
        other => panic!("expected EmptyImage or Decode, got {other:?}"),
    }
}

// ---------------------------------------------------------------- writing

#[test]
fn save_then_load_is_exact_at_8_and_16_bits() {
    let dir = TempDir::new("roundtrip");
    let image8 = Image::from_fn(9, 4, |x, y| ((x * 28 + y * 3) % 256) as f64 / 255.0);
    let image16 = Image::from_fn(9, 4, |x, y| ((x * 7001 + y * 13) % 65536) as f64 / 65535.0);
    for name in ["a.png", "a.tif", "a.TIFF", "A.PNG"] {
        let p = dir.path(name);
        save_image(&p, &image8, 8).unwrap();
        assert_eq!(load_image(&p).unwrap(), image8, "{name} 8-bit");
        save_image(&p, &image16, 16).unwrap();
        assert_eq!(load_image(&p).unwrap(), image16, "{name} 16-bit");
    }
}

#[test]
fn save_clamps_and_rounds_checked_with_an_independent_reader() {
    let dir = TempDir::new("clamp");
    let image = Image::new(5, 1, vec![-0.5, 1.7, 0.5, 0.2, 1.0]).unwrap();
    let p = dir.path("c.png");
    save_image(&p, &image, 8).unwrap();
    let read = image::open(&p).unwrap();
    let DynamicImage::ImageLuma8(b) = read else {
        panic!("not 8-bit gray: {read:?}")
    };
    // 0.5 * 255 = 127.5 rounds to 128; 0.2 * 255 = 51.
    assert_eq!(b.as_raw(), &vec![0u8, 255, 128, 51, 255]);

    let p = dir.path("c.tif");
    save_image(&p, &image, 16).unwrap();
    let read = image::open(&p).unwrap();
    let DynamicImage::ImageLuma16(b) = read else {
        panic!("not 16-bit gray: {read:?}")
    };
    assert_eq!(b.as_raw(), &vec![0u16, 65535, 32768, 13107, 65535]);
}

#[test]
fn save_errors() {
    let dir = TempDir::new("saveerr");
    let image = Image::from_fn(2, 2, |x, _| x as f64);
    assert!(matches!(
        save_image(&dir.path("a.png"), &image, 12),
        Err(Error::InvalidParameter { name: "bits", .. })
    ));
    assert!(matches!(
        save_image(&dir.path("a.jpg"), &image, 8),
        Err(Error::InvalidParameter { .. })
    ));
    assert!(matches!(
        save_image(&dir.path("noext"), &image, 8),
        Err(Error::InvalidParameter { .. })
    ));
    assert!(matches!(
        save_image(&dir.path("no/such/dir/a.png"), &image, 8),
        Err(Error::Io { .. })
    ));
}

// ---------------------------------------------------------------- CSV

fn parse(text: &str) -> vicurve::Result<Vec<[f64; 2]>> {
    parse_polyline_csv(text, "test.csv")
}

fn parse_error_line(text: &str) -> usize {
    match parse(text) {
        Err(Error::Parse { line, what, .. }) => {
            assert_eq!(what, "test.csv");
            line
        }
        other => panic!("expected a parse error for {text:?}, got {other:?}"),
    }
}

#[test]
fn csv_separators() {
    let expected = vec![[1.0, 2.5], [-3.0, 4e-3]];
    for text in [
        "1,2.5\n-3,4e-3\n",
        "1;2.5\n-3;4e-3",
        "1\t2.5\n-3\t4e-3\n",
        "1 2.5\n  -3    4e-3  \n",
        "1, 2.5\r\n-3 ,\t4e-3\r\n",
        "\u{feff}1,2.5\n-3,4e-3,\n",
    ] {
        assert_eq!(parse(text).unwrap(), expected, "{text:?}");
    }
}

#[test]
fn csv_header_and_named_columns() {
    assert_eq!(
        parse("x,y\n1,2\n3,4\n").unwrap(),
        vec![[1.0, 2.0], [3.0, 4.0]]
    );
    assert_eq!(
        parse("s,x,y,nx,ny\n0,10,20,0,1\n1.5,11,21,0,1\n").unwrap(),
        vec![[10.0, 20.0], [11.0, 21.0]]
    );
    // Column order and case from the header; quotes allowed.
    assert_eq!(parse("\"Y\";\"X\"\n2;1\n").unwrap(), vec![[1.0, 2.0]]);
    // Two other names: x then y.
    assert_eq!(parse("col,row\n5,6\n").unwrap(), vec![[5.0, 6.0]]);
    // More columns, none named x and y: refused at the header's line.
    assert_eq!(parse_error_line("# c\na,b,c\n1,2,3\n"), 2);
    assert_eq!(parse_error_line("x,z\n1,2\n"), 1);
    assert_eq!(parse_error_line("s,y\n1,2\n"), 1);
    // A row shorter than the header's y column.
    assert_eq!(parse_error_line("s,x,y\n1,2,3\n4,5\n"), 3);
}

#[test]
fn csv_comments_blank_lines_and_line_numbers() {
    let text = "# a polyline\n\nx,y\n  # indented comment\n1,2\n\n3,4\n5,oops\n";
    assert_eq!(parse_error_line(text), 8);
    assert_eq!(
        parse(&text.replace("5,oops\n", "")).unwrap(),
        vec![[1.0, 2.0], [3.0, 4.0]]
    );
    // Without a header every row must have exactly two fields.
    assert_eq!(parse_error_line("1,2\n3,4,5\n"), 2);
    assert_eq!(parse_error_line("1,2\n3\n"), 2);
    assert_eq!(parse_error_line("1,2\n3,,4\n"), 2);
    // An empty field does not make a header.
    assert_eq!(parse_error_line("# c\n,2\n3,4\n"), 2);
    // A non-numeric row after the first data row is an error, not a header.
    assert_eq!(parse_error_line("1,2\nx,y\n"), 2);
}

#[test]
fn csv_without_points_is_an_error() {
    assert_eq!(parse_error_line(""), 0);
    assert_eq!(parse_error_line("# only a comment\n\n"), 0);
    assert_eq!(parse_error_line("x,y\n"), 0);
}

#[test]
fn csv_non_finite_values() {
    for text in ["1,2\nNaN,3\n", "nan,1\n", "x,y\n1,inf\n", "1,-infinity\n"] {
        match parse(text) {
            Err(Error::NonFinite { what }) => assert!(what.contains("test.csv"), "{what}"),
            other => panic!("{text:?}: {other:?}"),
        }
    }
    match parse("1,2\n\n3,NaN\n") {
        Err(Error::NonFinite { what }) => assert!(what.contains("line 3"), "{what}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn csv_file_reading_names_the_file_and_finds_bad_utf8() {
    let dir = TempDir::new("csvfile");
    let p = dir.write("p.csv", b"x,y\n1,2\n");
    assert_eq!(read_polyline_csv(&p).unwrap(), vec![[1.0, 2.0]]);
    let p = dir.write("bad.csv", b"x,y\n1,2\n3,\xff\n");
    match read_polyline_csv(&p) {
        Err(Error::Parse { what, line, .. }) => {
            assert!(what.contains("bad.csv"));
            assert_eq!(line, 3);
        }
        other => panic!("{other:?}"),
    }
}

proptest! {
    /// Any finite points written with Rust's shortest round-trip formatting
    /// and any separator are read back exactly.
    #[test]
    fn csv_round_trip(
        points in proptest::collection::vec(
            (-1e6f64..1e6, prop_oneof![Just(0.0), -1e-3f64..1e-3, -5e3f64..5e3]), 1..20),
        sep in prop_oneof![Just(","), Just(";"), Just("\t"), Just("  "), Just(" , ")],
        header in any::<bool>(),
    ) {
        let mut text = String::new();
        if header {
            text.push_str(&format!("x{sep}y\n"));
        }
        for (x, y) in &points {
            text.push_str(&format!("{x}{sep}{y}\n"));
        }
        let read = parse(&text).unwrap();
        let expected: Vec<[f64; 2]> = points.iter().map(|&(x, y)| [x, y]).collect();
        prop_assert_eq!(read, expected);
    }
}
