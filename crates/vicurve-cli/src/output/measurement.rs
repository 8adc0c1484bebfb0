//! Every output of one measurement (`--out`, `--points`, `--svg`,
//! `--png`) and the summary printed when none is asked for.

use super::overlay::{write_png, write_svg, Layer, Style};
use super::{polarity_text, write_json, write_points_csv, ResultFile};
use crate::args::Outputs;
use crate::failure::Failure;
use vicurve::curve::InitialCurve;
use vicurve::fit::grow::GrowReport;
use vicurve::fit::{FitConfig, Measurement};
use vicurve::virtual_image::Profile;
use vicurve::Image;

/// A measurement and what its outputs are made from.
#[derive(Clone, Copy)]
pub struct Measured<'a> {
    /// The input's name as given (recorded in the result file).
    pub input: &'a str,
    /// The image measured.
    pub image: &'a Image,
    /// The start.
    pub init: &'a InitialCurve,
    /// The configuration it was measured with.
    pub config: &'a FitConfig,
    /// The measurement.
    pub m: &'a Measurement,
}

/// Write every requested output, with the record of a grown start
/// (`--grow`) if any; they are independent, so one failing does not
/// prevent the others (the first error is reported).
pub fn write_outputs(
    args: &Outputs,
    w: Measured,
    grown: Option<&GrowReport>,
) -> Result<(), Failure> {
    let Measured {
        input: path_text,
        image,
        init,
        config,
        m,
    } = w;
    let mut first_error: Option<String> = None;
    let mut note = |r: Result<(), String>| {
        if let Err(e) = r {
            first_error.get_or_insert(e);
        }
    };
    // The result file (its derived measures: circle and ellipse fits) and
    // the samples at once, on two cores.
    let json = || {
        args.out.as_ref().map(|p| {
            let mut record =
                ResultFile::new(path_text, (image.width(), image.height()), init, config, m);
            record.grow = grown;
            write_json(p, &record)
        })
    };
    let points = || args.points.as_ref().map(|p| write_points_csv(p, m));
    let (json, points) = rayon::join(json, points);
    json.into_iter().chain(points).for_each(&mut note);
    if args.svg.is_some() || args.png.is_some() {
        let layers = overlay_layers(init, config, m)?;
        if let Some(p) = &args.svg {
            note(write_svg(p, image, &layers));
        }
        if let Some(p) = &args.png {
            note(write_png(p, image, &layers, args.png_scale));
        }
    }
    match first_error {
        Some(e) => Err(Failure::Error(e)),
        None => Ok(()),
    }
}

/// The initial curve (dashed blue), the final band's borders (thin yellow)
/// and the measured curve (red).
pub fn overlay_layers(
    init: &InitialCurve,
    config: &FitConfig,
    m: &Measurement,
) -> Result<Vec<Layer>, Failure> {
    let closed = m.curve.is_closed();
    let init_pts = init.dense_points(1.0)?;
    let r = m.stages.last().map_or(0.0, |s| s.half_width);
    let offset = |k: f64| -> Vec<[f64; 2]> {
        m.samples
            .iter()
            .map(|s| [s.x + k * r * s.nx, s.y + k * r * s.ny])
            .collect()
    };
    let style = |color: [u8; 4], width: f32, dash: Option<[f32; 2]>| Style { color, width, dash };
    let mut layers = vec![Layer {
        label: "initial curve".into(),
        points: init_pts,
        closed: init.is_closed(),
        style: style([40, 120, 255, 255], 1.0, Some([4.0, 3.0])),
    }];
    if r > 0.0 {
        for (k, label) in [
            (-1.0, "band border (inner side)"),
            (1.0, "band border (outer side)"),
        ] {
            layers.push(Layer {
                label: format!("{label}, R = {r} px"),
                points: offset(k),
                closed,
                style: style([255, 210, 0, 200], 0.5, None),
            });
        }
    }
    layers.push(Layer {
        label: format!("measured {} ({})", config.kind, m.outcome),
        points: m.points(),
        closed,
        style: style([255, 40, 40, 255], 1.0, None),
    });
    Ok(layers)
}

pub fn print_summary(config: &FitConfig, m: &Measurement) {
    let c = m.stages.last().map_or(f64::NAN, |s| s.c);
    println!("outcome:     {}", m.outcome);
    println!(
        "iterations:  {} over {} stage(s)",
        m.iterations(),
        m.stages.len()
    );
    println!("residual:    {:.3e} (RMS gray level)", m.residual_rms());
    println!(
        "polarity:    {}",
        polarity_text(config.kind, m.curve.is_closed(), c)
    );
    println!("length:      {:.4} px", m.length());
    if let Some(a) = m.area() {
        println!("area:        {:.4} px^2", a);
    }
    print_closed_measures(m);
    let last_profile = m.stages.last().map(|s| s.profile);
    if let Some(Profile::PixelEdge { blur, anisotropy }) = last_profile
        .filter(|p| matches!(p, Profile::PixelEdge { anisotropy, .. } if !anisotropy.is_none()))
    {
        let amplitude = anisotropy.amplitude();
        println!(
            "edge blur:   {:.3} px optical along {:.1} deg (clockwise on screen from +x), {:.3} px perpendicular to it (fitted anisotropic blur: astigmatism or motion; the last stage's virtual edge is a pixel through it, so the true boundary is measured)",
            (blur * blur + amplitude).sqrt(),
            anisotropy.axis().to_degrees(),
            (blur * blur - amplitude).max(0.0).sqrt()
        );
    } else if let Some(Profile::PixelEdge { blur, .. }) = last_profile {
        println!(
            "edge blur:   {blur:.3} px optical (fitted; the last stage's virtual edge is a pixel through it, so the true boundary is measured)"
        );
    } else if let Some(Profile::PixelLine { blur, width }) = last_profile {
        println!(
            "line blur:   {blur:.3} px optical, width {width:.3} px (estimated; the last stage's virtual line is a pixel through them, so the true axis is measured)"
        );
    } else if let Some(e) = m.edge_spread {
        println!(
            "edge blur:   {:.3} px ({}; fit quality {:.3})",
            e.sigma,
            if m.blur_corrected {
                "its curvature shift removed"
            } else {
                "not corrected: the edge is not a clean blurred step"
            },
            e.fit_quality
        );
    }
    print_tone(m);
    let sig: Vec<f64> = m
        .samples
        .iter()
        .map(|s| s.sigma)
        .filter(|v| v.is_finite())
        .collect();
    if !sig.is_empty() {
        let mean = sig.iter().sum::<f64>() / sig.len() as f64;
        println!(
            "sigma:       {:.2e} px (mean uncertainty of the position, model misfit included)",
            mean
        );
    }
    let shift = m.sigma_shift();
    if shift > 0.0 {
        println!(
            "shift:       {shift:.2e} px (uncertainty common to every sample, not in their sigma: the tone reading; add it in quadrature for one sample)"
        );
    }
    if let Some(s) = m.stages.last().filter(|s| s.clipped > 0) {
        println!(
            "clipped:     {} of {} band pixels at the image's darkest or brightest level (saturated light): fitted as clipped, their light only known to lie beyond it",
            s.clipped, s.band_pixels
        );
    }
    let misfit = m.misfit_summary();
    if misfit.flagged > 0 {
        println!(
            "misfit:      {} of {} samples ({:.1} %) where the model misfits; their sigma is up to {:.1} times the noise's",
            misfit.flagged,
            m.samples.len(),
            100.0 * misfit.fraction,
            misfit.worst_inflation
        );
    }
}

/// The tone curve, when one was undone or estimated far from linear.
fn print_tone(m: &Measurement) {
    match (m.tone, m.tone_estimate) {
        (t, Some(e)) if !t.is_identity() => println!(
            "tone:        read from the edge as {t} (power law {:.3}, evidence {:.0} noise variances); measured again in linear light, about {:+.3} px along the normals; the reading leaves {:.1e} px for the whole curve (shift below; --tone CURVE if you know it)",
            e.gamma, e.evidence, e.shift, e.position_sd
        ),
        (t, _) if !t.is_identity() => println!("tone:        {t} undone before measuring"),
        (_, Some(e)) if e.position_sd > 0.0 => println!(
            "tone:        undecided: the edge's profile does not tell linear light from the usual encodings (power law read {:.2}, evidence {:.0} noise variances); measured as linear, the encodings it allows would move the edge by about {:.1e} px (shift below; --tone CURVE if you know it)",
            e.gamma, e.evidence, e.position_sd
        ),
        _ => {}
    }
}

/// The best-fit circle and ellipse of a closed curve (or why there are
/// none), for the summary.
fn print_closed_measures(m: &Measurement) {
    if !m.curve.is_closed() {
        return;
    }
    match vicurve::derived::closed_measures(m) {
        Ok(d) => {
            let (c, e) = (d.circle, d.ellipse);
            println!(
                "centroid:    ({:.4}, {:.4}) px; equivalent diameter {:.4} px",
                d.centroid[0], d.centroid[1], d.equivalent_diameter
            );
            println!(
                "circle:      centre ({:.4} +- {:.1e}, {:.4} +- {:.1e}), radius {:.4} +- {:.1e} px (rms distance {:.2e})",
                c.cx, c.sigma_cx, c.cy, c.sigma_cy, c.r, c.sigma_r, c.rms
            );
            println!(
                "ellipse:     centre ({:.4}, {:.4}), semi-axes {:.4} +- {:.1e} and {:.4} +- {:.1e} px, angle {:.3} deg +- {:.1e} (counterclockwise on screen from +x; rms distance {:.2e})",
                e.cx, e.cy, e.a, e.sigma_a, e.b, e.sigma_b, e.angle.to_degrees(), e.sigma_angle.to_degrees(), e.rms
            );
        }
        Err(err) => println!("circle:      none ({err})"),
    }
}
