"""Type stubs of the native module ``vicurve._vicurve`` (see ``vicurve``)."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, final, overload

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = [
    "__version__",
    "FitError",
    "Circle",
    "Segment",
    "Polyline",
    "Auto",
    "Result",
    "measure",
    "synth",
    "eval",
    "basis_values",
    "interpolate",
    "track",
    "run",
    "Tracker",
    "TrackedFrame",
]

_ImageLike = Union[npt.NDArray[Any], str, "os.PathLike[str]"]
"""A 2-D array (uint8, uint16, float32, float64) or the path of an image file."""

_ArrayLike2 = Union[npt.ArrayLike, Sequence[Sequence[float]]]

_Kind = Literal["silhouette", "contour"]
_PolarityName = Literal[
    "auto",
    "positive",
    "negative",
    "bright-inside",
    "dark-inside",
    "bright-left",
    "bright-right",
    "bright-line",
    "dark-line",
]
_InterpolationName = Literal["cubic", "bilinear", "keys", "cubic_b_spline"]
_StageElements = Union[int, str]
"""A number of elements, an element length such as ``"40px"``, or ``"auto"``."""
_Stages = Union[Sequence[Tuple[float, _StageElements]], str]
"""``[(R, elements), ...]`` or the command line's text ``"20:25,10:50"``."""
_ShapeName = Literal[
    "disc", "ellipse", "star", "sine-edge", "ring", "sine-line", "paper-disc"
]

class FitError(RuntimeError):
    """The fit diverged; ``result`` holds the partial result."""

    result: "Result"

@final
class Circle:
    """A circle of centre (cx, cy) and radius r, pixels: a closed start."""

    cx: float
    cy: float
    r: float
    def __new__(cls, cx: float, cy: float, r: float) -> "Circle": ...

@final
class Segment:
    """The segment from (x0, y0) to (x1, y1), pixels: an open start."""

    x0: float
    y0: float
    x1: float
    y1: float
    def __new__(cls, x0: float, y0: float, x1: float, y1: float) -> "Segment": ...

@final
class Polyline:
    """A polyline through N points (N x 2, x and y in pixels), open or closed."""

    closed: bool
    def __new__(cls, points: _ArrayLike2, closed: bool = False) -> "Polyline": ...
    @property
    def points(self) -> npt.NDArray[np.float64]:
        """The vertices, N x 2 float64."""

@final
class Auto:
    """The automatic start: Otsu threshold, main (or picked) region, its boundary."""

    pick: Optional[Tuple[float, float]]
    roi: Optional[Tuple[float, float, float, float]]
    def __new__(
        cls,
        pick: Optional[Tuple[float, float]] = None,
        roi: Optional[Tuple[float, float, float, float]] = None,
    ) -> "Auto": ...

_InitialCurve = Union[Circle, Segment, Polyline, Auto, str, None]

@final
class Result:
    """The result of ``measure``."""

    @property
    def points(self) -> npt.NDArray[np.float64]:
        """Samples (x, y), N x 2, at most 1 px apart."""
    @property
    def normals(self) -> npt.NDArray[np.float64]:
        """Unit normals (nx, ny) at the samples, N x 2."""
    @property
    def s(self) -> npt.NDArray[np.float64]:
        """Arc length of each sample from the curve's start, pixels (N)."""
    @property
    def sigma(self) -> npt.NDArray[np.float64]:
        """Standard deviation of each sample along the normal, pixels (N): noise and model misfit."""
    @property
    def sigma_shift(self) -> float:
        """Standard deviation of a shift of the whole curve, common to every sample, pixels (the tone reading's, also when it was too weak to undo an encoding; 0 when none)."""
    @property
    def sigma_noise(self) -> npt.NDArray[np.float64]:
        """The image noise's share of sigma, pixels (N)."""
    @property
    def misfit(self) -> npt.NDArray[np.bool_]:
        """Whether the model misfits at each sample (N); sigma covers it there."""
    @property
    def spline(self) -> Dict[str, Any]:
        """degree, closed, knots (array), control_points (K x 2 array), fit_error."""
    @property
    def history(self) -> List[Dict[str, Any]]:
        """One dict per stage, the fields of the result file's ``stages``."""
    @property
    def outcome(self) -> Literal["converged", "iteration_limit", "diverged"]: ...
    @property
    def divergence(
        self,
    ) -> Optional[
        Literal[
            "left_image",
            "no_contrast",
            "non_finite",
            "degenerate",
            "self_intersecting",
            "folded_back",
            "lost_edge",
            "off_edge",
        ]
    ]: ...
    @property
    def message(self) -> str:
        """The outcome in words."""
    @property
    def length(self) -> float:
        """Arc length of the measured curve, pixels."""
    @property
    def area(self) -> Optional[float]:
        """Enclosed area (closed curves), square pixels; None for open curves."""
    @property
    def edge_spread(self) -> Optional[Dict[str, Any]]:
        """sigma, line_width, fit_quality, pixels of the estimated blur, or None."""
    @property
    def tone(self) -> Union[str, Dict[str, float]]:
        """The tone curve the gray levels were read with: "linear", "srgb" or {"gamma": g}."""
    @property
    def tone_estimate(self) -> Optional[Dict[str, Any]]:
        """curve, gamma, shift, evidence, position_sd, pixels and (when linear light was kept) the standard encodings' alternatives of the tone estimate, or None."""
    @property
    def blur_corrected(self) -> bool: ...
    @property
    def polarity(self) -> str:
        """Which side is bright, in words."""
    @property
    def iterations(self) -> int: ...
    @property
    def skipped(self) -> List[str]: ...
    @property
    def corners_found(self) -> List[Tuple[float, float]]:
        """Corners found on a first, smooth measurement (x, y), px."""
    @property
    def initial_curve(self) -> Union[Circle, Segment, Polyline]: ...
    @property
    def auto_start(self) -> Optional[Dict[str, Any]]: ...
    @property
    def grow(self) -> Optional[Dict[str, Any]]:
        """How the curve grew (``grow=``): ``ends`` and ``steps``; None without growth."""
    @property
    def config(self) -> Dict[str, Any]: ...
    def to_json(self) -> str:
        """The JSON document ``vicurve measure --out`` writes for the same input."""

def measure(
    image: _ImageLike,
    init: _InitialCurve = None,
    *,
    kind: _Kind = "silhouette",
    stages: Optional[_Stages] = None,
    degree: int = 3,
    polarity: _PolarityName = "auto",
    interpolation: _InterpolationName = "cubic",
    tolerance: float = 1e-4,
    max_iterations: int = 200,
    blur_correction: bool = True,
    levels: str = "varying",
    breaks: Optional[Sequence[float]] = None,
    grow: Union[bool, float, None] = None,
    find_corners: bool = True,
    tone: str = "auto",
) -> Result:
    """Measure the curve in ``image`` starting from ``init``.

    ``init=None`` (or ``Auto(...)``) finds the main silhouette automatically.
    ``stages=None`` is the default schedule (20, 10, 5 and 2 px bands, the
    last choosing its elements, then a stage matched to the edge's blur).
    Raises ``FitError`` when the fit diverges, ``ValueError`` for bad
    arguments, ``FileNotFoundError`` for a missing file.
    """

def measure_all(
    image: _ImageLike,
    *,
    polarity: str = "auto",
    model: Optional[str] = None,
    min_length: Optional[float] = None,
    min_area: Optional[float] = None,
    roi: Optional[Tuple[float, float, float, float]] = None,
    include_border: bool = False,
    holes: bool = False,
    kind: str = "silhouette",
    min_strength: Optional[float] = None,
    corners: Optional[int] = None,
) -> Tuple[List[Optional[Result]], Dict[str, Any]]:
    """Every object of ``image``: one ``Result`` (or None) per object and
    the table as a dict of NumPy arrays (``vicurve.measure_all`` makes it a
    DataFrame when pandas is installed)."""

def synth(
    shape: _ShapeName,
    *,
    size: Tuple[int, int] = (512, 512),
    center: Optional[Tuple[float, float]] = None,
    radius: Optional[float] = None,
    axes: Optional[Tuple[float, float]] = None,
    angle: float = 20.0,
    amplitude: Optional[float] = None,
    lobes: int = 5,
    phase: float = 0.0,
    wavelength: Optional[float] = None,
    y0: Optional[float] = None,
    line: Optional[float] = None,
    profile: Optional[float] = None,
    blur: float = 0.0,
    noise: float = 0.0,
    seed: int = 1,
    bits: Optional[int] = 8,
    levels: Optional[Tuple[float, float]] = None,
    tone: str = "linear",
) -> Tuple[npt.NDArray[Any], Dict[str, Any]]:
    """Render a test image of exactly known geometry, as ``vicurve synth``.

    Returns ``(image, truth)``: a (height, width) array, uint8 for
    ``bits=8``, uint16 for ``bits=16``, float64 for ``bits=None``; and the
    truth file's content as a dict.
    """

def eval(points: _ArrayLike2, truth: Union[Dict[str, Any], str, "os.PathLike[str]"]) -> Dict[str, Any]:
    """points (count), bias, scatter, rms, max_abs (pixels) and distances (array)."""

def basis_values(
    degree: int,
    n_elements: int,
    length: float,
    closed: bool,
    s: npt.ArrayLike,
    derivative: int = 0,
) -> npt.NDArray[np.float64]:
    """len(s) x n_functions values (or derivatives) of the uniform B-spline basis."""

@overload
def interpolate(
    image: _ImageLike,
    xs: npt.ArrayLike,
    ys: npt.ArrayLike,
    kind: _InterpolationName = "cubic",
    gradient: Literal[False] = False,
) -> npt.NDArray[np.float64]: ...
@overload
def interpolate(
    image: _ImageLike,
    xs: npt.ArrayLike,
    ys: npt.ArrayLike,
    kind: _InterpolationName = "cubic",
    *,
    gradient: Literal[True],
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...

@final
class TrackedFrame:
    """One frame of ``track``: index, name, input, ok, outcome, reason,
    started_from, result (None when nothing was measured or the frame was
    resumed) and resumed (done by an earlier run in ``out_dir``)."""

    index: int
    name: str
    input: str
    ok: bool
    outcome: Literal["converged", "iteration_limit", "diverged", "failed"]
    reason: Optional[str]
    started_from: str
    result: Optional[Result]
    resumed: bool

@final
class Tracker:
    """Iterator of ``TrackedFrame``, one frame read and measured at a time."""

    def __iter__(self) -> "Tracker": ...
    def __next__(self) -> TrackedFrame: ...
    def __len__(self) -> int: ...
    def summary(self, pandas: bool = True) -> Any:
        """The frames so far: a pandas DataFrame, or a dict of NumPy arrays."""

def track(
    frames: Union[npt.NDArray[Any], Sequence[_ImageLike], str, "os.PathLike[str]"],
    init: _InitialCurve,
    *,
    kind: _Kind = "silhouette",
    stages: Optional[_Stages] = None,
    track_stages: Optional[str] = None,
    tracking: bool = True,
    degree: int = 3,
    polarity: _PolarityName = "auto",
    interpolation: _InterpolationName = "cubic",
    tolerance: float = 1e-4,
    max_iterations: int = 200,
    blur_correction: bool = True,
    levels: str = "varying",
    out_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
    force: bool = False,
    progress: bool = True,
    tone: str = "auto",
) -> Tracker:
    """Track a curve through ``frames`` (3-D array, arrays or paths, a glob,
    a multi-page TIFF), each frame started from the previous result as
    ``vicurve track`` does; with ``out_dir``, its files and its resume."""

def run(
    job: Union[str, "os.PathLike[str]"],
    *,
    force: bool = False,
    shard: Optional[str] = None,
    progress: bool = True,
    pandas: bool = True,
) -> Any:
    """Run a job file as ``vicurve run job.toml``; returns the summary (a
    pandas DataFrame, or a dict of NumPy arrays)."""
