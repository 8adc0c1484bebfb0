//! `measure`'s start: a given curve, or the automatic start's point and
//! rectangle, and growing an open start.

use crate::failure::Failure;
use vicurve::start::StartConfig;

/// How `measure` starts.
#[derive(clap::Args, Clone, Debug)]
pub struct StartArgs {
    /// Starting curve: `circle:CX,CY,R`, `segment:X0,Y0,X1,Y1` or
    /// `polyline:FILE.csv` (rows `x,y`, header allowed), in pixels (x =
    /// column, y = row, pixel centres at integers). It must cross or lie near
    /// the curve to measure. Without it (silhouettes), the main silhouette is
    /// found automatically: Otsu threshold, the region with the strongest
    /// edge (contrast times length; objects cut by the border count their
    /// visible edge), its traced boundary.
    #[arg(long)]
    pub init: Option<String>,
    /// Automatic start: the region containing this point `X,Y` (pixels);
    /// for a contour, the line through it, followed along its ridge.
    #[arg(long, value_name = "X,Y")]
    pub pick: Option<String>,
    /// Automatic start: search only this rectangle `X0,Y0,X1,Y1` (pixels).
    #[arg(long, value_name = "X0,Y0,X1,Y1")]
    pub roi: Option<String>,
    /// Grow an open start (`--init segment:...` or an open polyline) along
    /// the curve, segment by segment, until it reaches the image border,
    /// closes on itself or the edge ends; `--grow LEN` stops at LEN pixels.
    #[arg(long, value_name = "LEN", num_args = 0..=1)]
    pub grow: Option<Option<f64>>,
}

impl StartArgs {
    /// `--pick` and `--roi`, which only make sense without `--init`.
    pub fn automatic(&self) -> Result<StartConfig, Failure> {
        if self.init.is_some() && (self.pick.is_some() || self.roi.is_some()) {
            return Err(Failure::Error(
                "--pick and --roi choose an automatic start: drop --init, or drop them".into(),
            ));
        }
        let pick = match &self.pick {
            Some(t) => {
                let v = numbers("--pick", t, 2)?;
                Some([v[0], v[1]])
            }
            None => None,
        };
        let roi = match &self.roi {
            Some(t) => {
                let v = numbers("--roi", t, 4)?;
                Some([v[0], v[1], v[2], v[3]])
            }
            None => None,
        };
        Ok(StartConfig { pick, roi })
    }
}

/// `n` finite numbers separated by commas.
fn numbers(what: &str, text: &str, n: usize) -> Result<Vec<f64>, Failure> {
    let v: Result<Vec<f64>, _> = text.split(',').map(|t| t.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(Failure::Error(format!(
            "malformed {what} '{text}': expected {n} numbers separated by commas"
        ))),
    }
}
