//! `vicurve.Result`: a measurement, with what it was measured from, so
//! that `to_json()` writes the command-line tool's result file.

use crate::curves::{init_to_py, xy_array};
use crate::json::serde_to_py;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vicurve::curve::InitialCurve;
use vicurve::fit::grow::GrowReport;
use vicurve::fit::{Divergence, FitConfig, Measurement, Outcome};
use vicurve::report::{polarity_text, ResultFile};
use vicurve::start::AutoStart;

/// The result of `vicurve.measure`: the measured curve as dense samples
/// and as a B-spline, the per-stage history and how the fit ended.
///
/// Coordinates are pixels: x is the column, y the row, and the centre of
/// the pixel in row i, column j is at (x, y) = (j, i). The unit normal
/// points outward for closed curves (which run counterclockwise on
/// screen) and to the screen-right of travel for open ones.
#[pyclass(module = "vicurve", name = "Result", frozen)]
pub struct PyMeasurement {
    /// The library's result.
    pub measurement: Measurement,
    /// The starting curve (the one found, for an automatic start).
    pub init: InitialCurve,
    /// The configuration measured with.
    pub config: FitConfig,
    /// The image's name for the result file.
    pub source: String,
    /// Width, height of the image, pixels.
    pub size: (usize, usize),
    /// How the automatic start found the curve, when it did.
    pub start: Option<AutoStart>,
    /// How the curve grew from a short start (`grow=`).
    pub grow: Option<GrowReport>,
}

impl PyMeasurement {
    fn column(&self, f: impl Fn(&vicurve::fit::Sample) -> f64) -> Vec<f64> {
        self.measurement.samples.iter().map(f).collect()
    }
}

#[pymethods]
impl PyMeasurement {
    /// The samples (x, y), N x 2 float64, at most 1 px apart along the
    /// curve.
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        xy_array(py, &self.measurement.points())
    }

    /// The unit normals (nx, ny) at the samples, N x 2 float64.
    #[getter]
    fn normals<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let n: Vec<[f64; 2]> = self
            .measurement
            .samples
            .iter()
            .map(|s| [s.nx, s.ny])
            .collect();
        xy_array(py, &n)
    }

    /// Arc length of each sample from the start of the curve, pixels (N).
    #[getter]
    fn s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(|s| s.s).into_pyarray(py)
    }

    /// Standard deviation of each sample's position along the normal,
    /// pixels: the image noise's, combined with the model misfit's where
    /// the model misfits (N; NaN when no stage completed). A shift common
    /// to every sample is not in it: see `sigma_shift`.
    #[getter]
    fn sigma<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(|s| s.sigma).into_pyarray(py)
    }

    /// Standard deviation of a shift of the whole curve along its normals,
    /// common to every sample and not in `sigma`, pixels: what reading
    /// the tone curve from the edge leaves uncertain (also when the reading
    /// leaned to an encoding too weakly to undo it; 0 for a linear image
    /// or a tone curve given). One sample's whole uncertainty is
    /// `hypot(sigma, sigma_shift)`.
    #[getter]
    fn sigma_shift(&self) -> f64 {
        self.measurement.sigma_shift()
    }

    /// The image noise's share of `sigma`, pixels (N; NaN when no stage
    /// completed).
    #[getter]
    fn sigma_noise<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(|s| s.sigma_noise).into_pyarray(py)
    }

    /// Whether the model misfits at each sample (N booleans; `sigma`
    /// covers the misfit there).
    #[getter]
    fn misfit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        self.measurement
            .samples
            .iter()
            .map(|s| s.misfit)
            .collect::<Vec<bool>>()
            .into_pyarray(py)
    }

    /// The measured B-spline: a dict with `degree` (int), `closed` (bool),
    /// `knots` (float64 array), `control_points` (K x 2 float64 array; for
    /// a closed curve the first `degree` are repeated at the end, so that
    /// it is an ordinary B-spline on `knots[degree]..knots[-degree-1]`, as
    /// `scipy.interpolate.BSpline(knots, control_points, degree)` reads it)
    /// and `fit_error` (largest distance to the samples, pixels).
    #[getter]
    fn spline<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let data = self.measurement.curve_data();
        let d = PyDict::new(py);
        d.set_item("degree", data.degree)?;
        d.set_item("closed", data.closed)?;
        d.set_item("knots", data.knots.into_pyarray(py))?;
        d.set_item("control_points", xy_array(py, &data.control_points))?;
        d.set_item("fit_error", self.measurement.curve_fit_error)?;
        Ok(d)
    }

    /// One dict per stage run, with the fields of the result file's
    /// `stages` (half_width, profile, elements, iterations, rereferences,
    /// band_pixels, residual_rms, a, c, seconds, outcome, ...; `binning`
    /// for a coarse stage run on the binned image, `whole_object` for a
    /// small object's last stage measured against its whole image, with
    /// the `neighbours` rendered with it).
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.measurement.stages)
    }

    /// How the fit ended: "converged", "iteration_limit" or "diverged".
    #[getter]
    fn outcome(&self) -> &'static str {
        match self.measurement.outcome {
            Outcome::Converged => "converged",
            Outcome::IterationLimit => "iteration_limit",
            Outcome::Diverged { .. } => "diverged",
        }
    }

    /// Why a diverged fit stopped: "left_image", "no_contrast",
    /// "non_finite", "degenerate", "self_intersecting", "folded_back",
    /// "lost_edge" or "off_edge"; None otherwise.
    #[getter]
    fn divergence(&self) -> Option<&'static str> {
        match self.measurement.outcome {
            Outcome::Diverged { divergence } => Some(match divergence {
                Divergence::LeftImage { .. } => "left_image",
                Divergence::NoContrast => "no_contrast",
                Divergence::NonFinite => "non_finite",
                Divergence::Degenerate => "degenerate",
                Divergence::SelfIntersecting { .. } => "self_intersecting",
                Divergence::FoldedBack { .. } => "folded_back",
                Divergence::LostEdge { .. } => "lost_edge",
                Divergence::OffEdge { .. } => "off_edge",
            }),
            _ => None,
        }
    }

    /// The outcome in words (e.g. "diverged: the curve left the image near
    /// (-2.4, 119.4)").
    #[getter]
    fn message(&self) -> String {
        self.measurement.outcome.to_string()
    }

    /// Arc length of the measured curve, pixels.
    #[getter]
    fn length(&self) -> f64 {
        self.measurement.length()
    }

    /// Area enclosed by a closed measured curve, square pixels; None for
    /// open curves.
    #[getter]
    fn area(&self) -> Option<f64> {
        self.measurement.area()
    }

    /// The blur of the edge (or line) estimated on the measured curve: a
    /// dict (sigma, line_width, fit_quality, pixels) or None.
    #[getter]
    fn edge_spread<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.measurement.edge_spread)
    }

    /// The tone curve the gray levels were read with: "linear" unless the
    /// image was taken to linear light ("srgb" or {"gamma": g}).
    #[getter]
    fn tone<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.measurement.tone)
    }

    /// The tone curve estimated around the edge (`tone="auto"`,
    /// silhouettes): a dict (curve, gamma, shift, evidence, position_sd,
    /// pixels) or None.
    #[getter]
    fn tone_estimate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.measurement.tone_estimate)
    }

    /// Whether the result accounts for the blur (true boundary or centre
    /// line rather than the blurred one).
    #[getter]
    fn blur_corrected(&self) -> bool {
        self.measurement.blur_corrected
    }

    /// Which side is bright, in words (from the sign of the contrast c).
    #[getter]
    fn polarity(&self) -> String {
        let c = self.measurement.stages.last().map_or(f64::NAN, |s| s.c);
        polarity_text(self.config.kind, self.measurement.curve.is_closed(), c)
    }

    /// Total Gauss-Newton iterations over all stages.
    #[getter]
    fn iterations(&self) -> usize {
        self.measurement.iterations()
    }

    /// Stages of the default schedule that were skipped, with the reason.
    #[getter]
    fn skipped(&self) -> Vec<String> {
        self.measurement.skipped.clone()
    }

    /// Corners found on a first, smooth measurement, where the curve was
    /// measured again with breaks: `[(x, y), ...]`, pixels (empty when
    /// none; see `measure(find_corners=...)`).
    #[getter]
    fn corners_found(&self) -> Vec<(f64, f64)> {
        self.measurement
            .corners_found
            .iter()
            .map(|p| (p[0], p[1]))
            .collect()
    }

    /// The starting curve (for an automatic start, the one it found).
    #[getter]
    fn initial_curve<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        init_to_py(py, &self.init)
    }

    /// How the automatic start found the curve (a dict: threshold, bright,
    /// region_pixels, closed, curve), or None for a given start.
    #[getter]
    fn auto_start<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.start)
    }

    /// The configuration measured with, as in the result file.
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.config)
    }

    /// The result file `vicurve measure --out` writes for the same input:
    /// pretty-printed JSON with a final newline. `input.path` is the path
    /// the image was read from, or a description of the array.
    fn to_json(&self) -> String {
        let mut record = ResultFile::new(
            &self.source,
            self.size,
            &self.init,
            &self.config,
            &self.measurement,
        );
        record.grow = self.grow.as_ref();
        record.to_json()
    }

    /// How the curve grew (`grow=`): why each end stopped (`ends`) and
    /// every step; None without growth.
    #[getter]
    fn grow<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.grow)
    }

    fn __repr__(&self) -> String {
        format!(
            "<vicurve.Result {}: {} samples, length {:.4} px{}>",
            self.measurement.outcome,
            self.measurement.samples.len(),
            self.measurement.length(),
            self.measurement
                .area()
                .map(|a| format!(", area {a:.4} px^2"))
                .unwrap_or_default()
        )
    }
}
