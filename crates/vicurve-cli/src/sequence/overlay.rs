//! The overlay of a frame of a sequence: every curve measured on it, over
//! the image (the library's runner calls [`draw`]).

use crate::output::measurement::overlay_layers;
use crate::output::overlay;
use std::path::Path;
use vicurve::sequence::run::job::OverlayKind;
use vicurve::sequence::CurveStep;
use vicurve::Image;

/// Every measured curve of `steps` over `image`, to `path`.
pub fn draw(
    kind: OverlayKind,
    path: &Path,
    image: &Image,
    steps: &[CurveStep],
) -> Result<(), String> {
    let mut layers = Vec::new();
    for r in steps {
        if let Ok(m) = &r.measured {
            let l = overlay_layers(&r.init, &r.config, m).map_err(|e| e.message())?;
            layers.extend(l);
        }
    }
    match kind {
        OverlayKind::Png => overlay::write_png(path, image, &layers, 1),
        OverlayKind::Svg => overlay::write_svg(path, image, &layers),
    }
}
