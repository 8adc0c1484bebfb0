//! `vicurve synth necking --out DIR`: the worked example of sequences. A
//! tensile specimen, a bright bar on a dark ground, necks progressively
//! ([`vicurve::truth::specimen`]); each frame is painted by exact pixel
//! coverage, blurred, noisy and quantised. Written in `DIR`:
//! - `frame_000.png`, `frame_001.png`, ...;
//! - `truth.json`: the exact bar of every frame (its width at abscissa `x`
//!   is `width - neck / cosh²((x - x_neck) / neck_length)`);
//! - `job.toml`: the job that measures both edges and the width between
//!   them along the x axis, `vicurve run DIR/job.toml`, into `DIR/results`.
//!
//! The bar of a `W x H` image: axis on the row `(H - 1) / 2 + 0.3`, width
//! `H / 2`, neck from 6 % to 24 % of the width (growing as the square of
//! time), neck length `W / 8`, narrowest section at `x = (W - 1) / 2 + 0.4`.

use crate::args::synth::{check_bits, numbers, parse_size, Args};
use crate::failure::Failure;
use crate::output::write_atomic;
use serde::Serialize;
use vicurve::render::specimen::{render_specimen, SpecimenSpec};
use vicurve::truth::specimen::{necking_sequence, NeckedBar};

/// The truth file of a necking sequence.
#[derive(Serialize)]
struct SequenceTruth<'a> {
    /// What the numbers are.
    description: &'static str,
    coordinates: &'static str,
    frames: Vec<FrameTruth<'a>>,
}

#[derive(Serialize)]
struct FrameTruth<'a> {
    image: String,
    spec: &'a SpecimenSpec,
    /// The narrowest width, px.
    min_width: f64,
}

pub fn necking(a: &Args) -> Result<(), Failure> {
    let bits = check_bits(a.bits.unwrap_or(16))?;
    let (w, h) = parse_size(a.size.as_deref().unwrap_or("400x200"))?;
    if a.frames == 0 || a.frames > 100_000 {
        return Err(Failure::Error(format!(
            "--frames {} (expected 1 to 100000)",
            a.frames
        )));
    }
    let levels = numbers("levels", &a.levels, ',', 2)?;
    let width = 0.5 * h;
    let bar = NeckedBar {
        axis_y: (h - 1.0) / 2.0 + 0.3,
        width,
        neck: 0.06 * width,
        neck_length: w / 8.0,
        x_neck: (w - 1.0) / 2.0 + 0.4,
    };
    let bars = necking_sequence(&bar, 0.06 * width, 0.24 * width, a.frames)?;
    let specs: Vec<SpecimenSpec> = bars
        .iter()
        .enumerate()
        .map(|(k, b)| SpecimenSpec {
            width: w as usize,
            height: h as usize,
            bar: *b,
            background: levels[0],
            foreground: levels[1],
            blur_sigma: a.blur.unwrap_or(1.5),
            noise: a.noise.unwrap_or(0.001),
            seed: a.seed.wrapping_add(k as u64),
            bits: Some(bits),
        })
        .collect();
    let dir = &a.out;
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create the folder {}: {e}", dir.display()))?;
    let mut frames = Vec::new();
    for (k, spec) in specs.iter().enumerate() {
        let image = render_specimen(spec)?;
        let name = format!("frame_{k:03}.png");
        vicurve::io::save_image(&dir.join(&name), &image, bits)?;
        frames.push(FrameTruth {
            image: name,
            spec,
            min_width: spec.bar.min_width(),
        });
    }
    let truth = SequenceTruth {
        description: "necking specimen: a bright bar along x, symmetric about the row axis_y; full width at abscissa x: width - neck / cosh^2((x - x_neck) / neck_length)",
        coordinates: vicurve::report::CONVENTION,
        frames,
    };
    let text = serde_json::to_string_pretty(&truth).unwrap_or_default() + "\n";
    write_atomic(&dir.join("truth.json"), text.as_bytes())?;
    // Starts: segments from border to border 4 px outside each edge (the
    // fit trims them so that their bands stay inside the image).
    let top = bar.axis_y - 0.5 * width - 4.0;
    let bottom = bar.axis_y + 0.5 * width + 4.0;
    let job = format!(
        "# Measures the necking sequence written by `vicurve synth necking`:\n\
         # `vicurve run {dir}/job.toml` writes {dir}/results/.\n\
         images = \"frame_*.png\"\n\
         out_dir = \"results\"\n\
         \n\
         [[curve]]\n\
         name = \"top\"\n\
         init = \"segment:0,{top},{x1},{top}\"\n\
         \n\
         [[curve]]\n\
         name = \"bottom\"\n\
         init = \"segment:0,{bottom},{x1},{bottom}\"\n\
         \n\
         [[width]]\n\
         name = \"width\"\n\
         between = [\"top\", \"bottom\"]\n\
         axis = \"x\"\n",
        dir = dir.display(),
        x1 = w - 1.0,
    );
    write_atomic(&dir.join("job.toml"), job.as_bytes())?;
    eprintln!(
        "wrote {} frames ({}x{}, {}-bit), truth.json and job.toml in {}",
        a.frames,
        w,
        h,
        bits,
        dir.display()
    );
    Ok(())
}
