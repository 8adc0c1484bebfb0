//! `vicurve synth scene|grid|square-grid --out IMAGE [--truth FILE]`: many
//! objects in one image ([`vicurve::render::scene`],
//! [`vicurve::render::square_grid`]), the truth file listing every shape
//! with its role (object, speck, border) and, for a grid, its exact
//! strains.

use crate::args::synth::{check_bits, parse_size, Args, ShapeName};
use crate::failure::Failure;
use crate::output::write_json;
use vicurve::render::scene::{circle_grid, random_scene, render_scene, strained_grid, Rendering};
use vicurve::render::square_grid::square_grid;

/// `--blur`, `--blur-y`, `--noise`, `--tone`, `--shading` and `--bits`
/// (default 8) set in `r`; the bits.
fn with_options(a: &Args, r: &mut Rendering) -> Result<u8, Failure> {
    r.tone = a
        .tone
        .parse()
        .map_err(|e| Failure::Error(format!("--tone: {e}")))?;
    r.shading = a
        .shading
        .parse()
        .map_err(|e| Failure::Error(format!("--shading: {e}")))?;
    if let Some(b) = a.blur {
        r.blur_sigma = b;
    }
    r.blur_sigma_y = a.blur_y.or(r.blur_sigma_y);
    if let Some(n) = a.noise {
        r.noise = n;
    }
    let bits = check_bits(a.bits.unwrap_or(8))?;
    r.bits = Some(bits);
    Ok(bits)
}

pub fn scene(a: &Args) -> Result<(), Failure> {
    let mut scene = if a.shape == ShapeName::Grid {
        let d0 = 2.0 * a.radius.unwrap_or(15.0);
        match a.size.as_deref() {
            Some(size) => {
                let (w, h) = parse_size(size)?;
                circle_grid(w as usize, h as usize, 10, 10, d0, true, a.seed)?
            }
            None => strained_grid(10, 10, d0, (2.0 * d0).max(d0 * 1.3 + 24.0), a.seed),
        }
    } else {
        let (w, h) = parse_size(a.size.as_deref().unwrap_or("1024x768"))?;
        random_scene(w as usize, h as usize, 50, 20, 5, false, 8.0, a.seed)?
    };
    let bits = with_options(a, &mut scene.rendering)?;
    let image = render_scene(&scene)?;
    vicurve::io::save_image(&a.out, &image, bits)?;
    if let Some(t) = &a.truth {
        write_json(t, &scene)?;
    }
    eprintln!(
        "wrote {} ({}x{}, {} shapes)",
        a.out.display(),
        scene.width,
        scene.height,
        scene.items.len()
    );
    Ok(())
}

/// `synth square-grid`: a deformed square grid and its truth.
pub fn square(a: &Args) -> Result<(), Failure> {
    let (w, h) = parse_size(a.size.as_deref().unwrap_or("640x640"))?;
    let mut grid = square_grid(
        w as usize,
        h as usize,
        8,
        8,
        a.line.unwrap_or(10.0),
        true,
        a.seed,
    )?;
    let bits = with_options(a, &mut grid.rendering)?;
    let image = grid.render()?;
    vicurve::io::save_image(&a.out, &image, bits)?;
    if let Some(t) = &a.truth {
        write_json(t, &grid)?;
    }
    eprintln!(
        "wrote {} ({}x{}, {} cells, pitch {:.2} px before forming)",
        a.out.display(),
        grid.width,
        grid.height,
        grid.cells.len(),
        grid.pitch
    );
    Ok(())
}
