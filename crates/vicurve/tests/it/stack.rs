//! Multi-page TIFF stacks read page by page ([`vicurve::io::TiffStack`]),
//! written here with the `tiff` crate's encoder (an independent writer), as
//! ImageJ writes them: one directory per page, an `ImageJ=` description on
//! the first.

use std::io::Cursor;
use std::path::PathBuf;

use tiff::encoder::colortype::{ColorType, Gray16, Gray32Float, Gray8, RGB8};
use tiff::encoder::{TiffEncoder, TiffValue};
use tiff::tags::Tag;
use vicurve::io::{load_image, page_count, TiffStack};
use vicurve::Error;

const W: u32 = 5;
const H: u32 = 3;

/// `pages` pages of `W x H` samples made by `sample(page, i)`.
fn stack<C: ColorType>(
    pages: usize,
    channels: usize,
    sample: impl Fn(usize, usize) -> C::Inner,
) -> Vec<u8>
where
    [C::Inner]: TiffValue,
{
    let mut out = Cursor::new(Vec::new());
    let mut encoder = TiffEncoder::new(&mut out).unwrap();
    let n = (W * H) as usize * channels;
    for k in 0..pages {
        let data: Vec<C::Inner> = (0..n).map(|i| sample(k, i)).collect();
        let mut image = encoder.new_image::<C>(W, H).unwrap();
        if k == 0 {
            let description = format!("ImageJ=1.54f\nimages={pages}\nslices={pages}\nloop=false\n");
            image
                .encoder()
                .write_tag(Tag::ImageDescription, description.as_str())
                .unwrap();
        }
        image.write_data(&data).unwrap();
    }
    out.into_inner()
}

fn file(name: &str, bytes: &[u8]) -> (tempfile_dir::Dir, PathBuf) {
    let dir = tempfile_dir::Dir::new(name);
    let p = dir.0.join(name);
    std::fs::write(&p, bytes).unwrap();
    (dir, p)
}

/// A folder removed when dropped.
mod tempfile_dir {
    pub struct Dir(pub std::path::PathBuf);
    impl Dir {
        pub fn new(name: &str) -> Dir {
            let d =
                std::env::temp_dir().join(format!("vicurve-stack-{}-{name}", std::process::id()));
            let _ = std::fs::remove_dir_all(&d);
            std::fs::create_dir_all(&d).unwrap();
            Dir(d)
        }
    }
    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

fn level16(k: usize, i: usize) -> u16 {
    (k * 4099 + i * 257 + 1) as u16
}

#[test]
fn pages_of_16_bit_8_bit_and_float_stacks_read_in_any_order() {
    let (_d, p16) = file("s16.tif", &stack::<Gray16>(4, 1, level16));
    let s = TiffStack::open(&p16).unwrap();
    assert_eq!(s.len(), 4);
    assert_eq!(page_count(&p16).unwrap(), 4);
    for k in [3, 0, 2, 1, 3] {
        let img = s.read_page(k).unwrap();
        assert_eq!((img.width(), img.height()), (W as usize, H as usize));
        for (i, v) in img.data().iter().enumerate() {
            assert_eq!(*v, f64::from(level16(k, i)) / 65535.0, "page {k} pixel {i}");
        }
    }
    // Page 0 is what `load_image` reads, bit for bit.
    assert_eq!(s.read_page(0).unwrap(), load_image(&p16).unwrap());

    let (_d, p8) = file("s8.tif", &stack::<Gray8>(3, 1, |k, i| (k * 50 + i) as u8));
    let s = TiffStack::open(&p8).unwrap();
    let img = s.read_page(2).unwrap();
    assert_eq!(img.data()[7], f64::from(107u8) / 255.0);

    let f = |k: usize, i: usize| k as f32 * 10.0 - i as f32 * 0.25;
    let (_d, pf) = file("sf.tif", &stack::<Gray32Float>(2, 1, f));
    let s = TiffStack::open(&pf).unwrap();
    let img = s.read_page(1).unwrap();
    for (i, v) in img.data().iter().enumerate() {
        assert_eq!(*v, f64::from(f(1, i)));
    }

    // Colour pages: the luma of the stored values, as `load_image`.
    let (_d, pc) = file(
        "rgb.tif",
        &stack::<RGB8>(2, 3, |k, i| (k * 30 + i * 3) as u8),
    );
    let s = TiffStack::open(&pc).unwrap();
    let c = s.read_page(1).unwrap();
    let expected = (0.2126 * 30.0 + 0.7152 * 33.0 + 0.0722 * 36.0) / 255.0;
    assert!((c.data()[0] - expected).abs() < 1e-15, "{}", c.data()[0]);
}

#[test]
fn odd_and_truncated_stacks_give_typed_errors() {
    let (_d, p) = file("s.tif", &stack::<Gray16>(3, 1, level16));
    let s = TiffStack::open(&p).unwrap();
    assert!(matches!(
        s.read_page(3),
        Err(Error::InvalidParameter { name: "page", .. })
    ));
    // Not a TIFF; missing.
    let (_d, png) = file("a.tif", b"\x89PNG\r\n\x1a\nrest");
    assert!(matches!(
        TiffStack::open(&png),
        Err(Error::UnsupportedImage { .. })
    ));
    let missing = p.with_file_name("none.tif");
    assert!(matches!(
        TiffStack::open(&missing),
        Err(Error::NotFound { .. })
    ));
    // A float page holding NaN: that page fails, the others read.
    let (_d, pn) = file(
        "nan.tif",
        &stack::<Gray32Float>(2, 1, |k, i| if k == 1 && i == 4 { f32::NAN } else { 0.5 }),
    );
    let s = TiffStack::open(&pn).unwrap();
    assert!(s.read_page(0).is_ok());
    match s.read_page(1) {
        Err(Error::NonFinite { what }) => assert!(what.contains("page 1"), "{what}"),
        other => panic!("{other:?}"),
    }
    // Cut anywhere: opening or reading the pages fails with a typed error
    // (the file, a page), or reads the pages whole; never a panic, never
    // a page filled in.
    let whole = std::fs::read(&p).unwrap();
    let full: Vec<_> = (0..3)
        .map(|k| TiffStack::open(&p).unwrap().read_page(k).unwrap())
        .collect();
    let cut_path = p.with_file_name("cut.tif");
    let mut cut_errors = 0;
    for cut in (8..whole.len()).step_by(7) {
        std::fs::write(&cut_path, &whole[..cut]).unwrap();
        match TiffStack::open(&cut_path) {
            Err(Error::Decode { reason, .. }) => {
                assert!(reason.contains("page"), "{cut}: {reason}");
                cut_errors += 1;
            }
            Err(e) => panic!("cut at {cut}: {e:?}"),
            Ok(s) => {
                if let Some(reason) = s.broken() {
                    assert!(reason.contains(&format!("page {}", s.len())), "{reason}");
                    assert!(matches!(s.read_page(s.len()), Err(Error::Decode { .. })));
                    cut_errors += 1;
                }
                assert!(s.len() <= full.len());
                for (k, page) in full.iter().enumerate().take(s.len()) {
                    match s.read_page(k) {
                        Ok(img) => assert_eq!(&img, page, "cut at {cut}, page {k}"),
                        Err(Error::Decode { reason, .. }) => {
                            assert!(reason.contains(&format!("page {k}")), "{reason}");
                            cut_errors += 1;
                        }
                        Err(e) => panic!("cut at {cut}, page {k}: {e:?}"),
                    }
                }
            }
        }
    }
    assert!(cut_errors > 0);
}
