//! The band's pixels with levelset coordinates: `(s, r)` interpolated
//! from the nodes of a [`LevelsetCoords`] mesh, no pixel projected (see the
//! [module docs](super)).

use super::build::{Candidate, Foot, Pixels};
use super::levelset::LevelsetCoords;
use super::MIN_JACOBIAN;
use rayon::prelude::*;

impl Pixels<'_> {
    /// The band pixels with levelset coordinates, row by row (raster
    /// order): the pixels of the meshed domain whose interpolated `(s, r)`
    /// are in the band.
    pub(super) fn levelset_rows(&self, levelsets: &LevelsetCoords) -> Vec<Vec<Candidate>> {
        let b = levelsets.bounds();
        let x0 = b[0].ceil().max(0.0) as usize;
        let y0 = b[1].ceil().max(0.0) as usize;
        let x1 = b[2].floor().min(self.width as f64 - 1.0);
        let y1 = b[3].floor().min(self.height as f64 - 1.0);
        if x1 < x0 as f64 || y1 < y0 as f64 {
            return Vec::new();
        }
        let (x1, y1) = (x1 as usize, y1 as usize);
        (y0..=y1)
            .into_par_iter()
            .map(|y| self.levelset_row(levelsets, y, [x0, x1]))
            .collect()
    }

    /// The band pixels of row `y` between the columns `columns[0]` and
    /// `columns[1]` (included).
    fn levelset_row(
        &self,
        levelsets: &LevelsetCoords,
        y: usize,
        [x0, x1]: [usize; 2],
    ) -> Vec<Candidate> {
        let mut spans = Vec::new();
        levelsets.row_spans(y as f64, &mut spans);
        let columns = spans.iter().flat_map(|&[a, b]| {
            let a = a.ceil().max(x0 as f64) as usize;
            let b = b.floor().min(x1 as f64);
            // An empty range when the span holds no pixel column.
            a..if b >= a as f64 { b as usize + 1 } else { a }
        });
        columns
            .filter(|&x| !self.thinned_out(x, y))
            .filter_map(|x| self.levelset_pixel(levelsets, x as f64, y as f64))
            .collect()
    }

    /// The band pixel at `(x, y)`, if it is one: in the meshed domain,
    /// `|r|` under the reach, `s` inside an open curve, on the near side of
    /// the centre of curvature.
    fn levelset_pixel(&self, levelsets: &LevelsetCoords, x: f64, y: f64) -> Option<Candidate> {
        let l = self.curve.param_length();
        let (s, r) = levelsets.eval(x, y)?;
        if r.abs() >= self.reach || (!self.curve.is_closed() && (s <= 0.0 || s >= l)) {
            return None;
        }
        let f = self.curve.frame(s);
        let jacobian = 1.0 - f.curvature * r;
        if jacobian <= MIN_JACOBIAN {
            return None;
        }
        let foot = Foot {
            pos: [x, y],
            s,
            r,
            normal: f.normal,
            curvature: f.curvature,
        };
        Some(self.candidate(foot, jacobian))
    }
}
