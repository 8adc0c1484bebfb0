#!/usr/bin/env python3
"""Side-by-side comparison of vicurve with the edge tools users would otherwise pick.

What it does
------------
For every case below, ``vicurve synth`` renders a test image by exact pixel
coverage (8-bit PNG) together with its truth file (the exact curve). Then each
tool extracts the edge from that same image, its points are written as a CSV
(header ``x,y``, vicurve's convention), every CSV is scored with
``vicurve eval POINTS TRUTH --json``, and each tool is timed. The results go to
``results.csv`` and ``results.md`` next to this script; images, truth files,
point files and eval files go to a work directory (``work/`` by default,
ignored by git).

Coordinates
-----------
vicurve: ``x`` is the column, ``y`` the row, and the centre of the pixel in
row i, column j is at (x, y) = (j, i). Every peer's output is converted to it:

* skimage ``measure.find_contours`` returns (row, col) with pixel centres at
  integer indices, so x = col, y = row (no offset).
* OpenCV ``cv2.findContours`` returns integer (x, y) = (column, row): the
  centres of the foreground pixels on the region's border (a pixel belongs to
  the foreground when its value exceeds the Otsu threshold). These points are
  therefore not on the edge but on the centres of the last bright pixels,
  0 to about 1 px inside the bright region; they are written unchanged.
* subpixel-edges returns ``edges.x`` (column) and ``edges.y`` (row), 0-based
  with pixel centres at integers (its code builds ``meshgrid(arange(cols),
  arange(rows))`` and moves each edge pixel's centre by the fitted offset),
  i.e. vicurve's convention; written unchanged.

How each tool is called
-----------------------
* vicurve: ``vicurve measure IMAGE --init circle:CX,CY,R | segment:X0,Y0,X1,Y1
  --points P.csv --out R.json`` with default settings; the start is a circle
  whose centre is ~6-10 px off and radius ~10 px off (or a straight segment
  through the middle of the sine), as a user would draw it.
* skimage: the two plateau levels are estimated from the image (Otsu
  threshold, then the median of the pixels on each side of it); contours are
  taken at the mid level with ``find_contours(img, level)``; the longest one
  is kept (its closing duplicate point dropped).
* OpenCV: ``cv2.threshold(img, 0, 255, THRESH_BINARY | THRESH_OTSU)``, then
  ``cv2.findContours(mask, RETR_EXTERNAL, CHAIN_APPROX_NONE)``; the longest
  contour is kept. For the open sine edge, points on the image border rows and
  columns (where the contour runs along the frame) are dropped. OpenCV's main
  modules have no sub-pixel edge or contour detector (Canny and findContours
  are pixel-level; cornerSubPix / find4QuadCornerSubpix refine corners), so
  no sub-pixel OpenCV variant is run.
* subpixel-edges (Trujillo-Pino et al., partial area effect; PyPI
  ``subpixel-edges``): ``subpixel_edges(img_float_0_255, threshold, iters,
  order=2)`` with threshold = 10 % of the estimated contrast (gray levels
  0-255) and iters = 0 (noise-free images), 1 (low noise) and 2 (high noise),
  each reported as its own row. It returns every edge pixel of the image;
  points farther than 3 px from the OpenCV Otsu contour are dropped (spurious
  noise edges). Version 0.1.1 calls ``np.int``, removed in NumPy 1.24, in its
  iters >= 1 code: this script sets ``np.int = int`` (what the alias was)
  before importing it. The first call of each variant compiles with numba;
  it is excluded by a warm-up call.
* Sine edge: vicurve measures the part of the edge spanned by its start
  segment (x from 20 to W-21); all peers' points are clipped to the same
  x-range so that every tool is scored on the same part of the edge. The
  start a user would draw first, a segment from border to border
  (``segment:0,256,511,256``), is also run and reported as its own row
  (with vicurve at the time of writing it stops with "the fit diverged").

Timing
------
Peers: wall clock (``time.perf_counter``) of the extraction only, with the
image already in memory as a NumPy array (level estimation, threshold,
contour extraction, selection/filtering included), best of ``--repeats``
runs after one warm-up. vicurve: (a) the sum of the per-stage ``seconds`` in
its ``--out`` JSON (the fit only: this is the "time" column, the one to
compare with the peers) and (b) the wall clock of the whole ``vicurve measure``
process (start, PNG decoding, fit, writing CSV and JSON), each the best of
``--repeats`` runs.

Determinism
-----------
Noise seeds are fixed per case; all tools are deterministic. Only timings vary.

Usage
-----
    python run_peers.py --vicurve /path/to/vicurve [--repeats 5] [--work DIR]
                        [--cases disc-clean,star ...]
"""

import argparse
import csv
import json
import os
import platform
import shutil
import subprocess
import sys
import time
import traceback
from pathlib import Path

import numpy as np

# subpixel-edges 0.1.1 uses the alias np.int (removed in NumPy 1.24) inside
# numba-compiled code; restore the alias (it was the builtin int).
if not hasattr(np, "int"):
    np.int = int  # noqa: E305

import cv2  # noqa: E402
import skimage  # noqa: E402
from skimage import filters, measure  # noqa: E402

try:
    import subpixel_edges as _spe_mod  # noqa: E402
    from subpixel_edges import subpixel_edges  # noqa: E402

    SPE_IMPORT_ERROR = None
except Exception as exc:  # recorded as a failure of that peer
    subpixel_edges = None
    _spe_mod = None
    SPE_IMPORT_ERROR = f"{type(exc).__name__}: {exc}"

HERE = Path(__file__).resolve().parent

DISC = ["disc", "--size", "400x400", "--center", "200.37,199.62", "--radius", "150",
        "--levels", "0.2,0.8", "--bits", "8"]
DISC_INIT = "circle:206,194,140"

# name, synth arguments, vicurve --init, open curve?, description
# (EXTRA_INITS: further vicurve starts run on a case, reported as their own rows)
EXTRA_INITS = {"sine-edge": ["segment:0,256,511,256"]}
CASES = [
    ("disc-clean", DISC + ["--seed", "1"], DISC_INIT, False,
     "disc r=150, centre (200.37, 199.62), 400x400, noiseless"),
    ("disc-blur1", DISC + ["--blur", "1", "--seed", "1"], DISC_INIT, False,
     "same disc, Gaussian blur 1 px"),
    ("disc-noise1", DISC + ["--noise", "0.01", "--seed", "11"], DISC_INIT, False,
     "same disc, noise 1 % of the contrast"),
    ("disc-noise5", DISC + ["--noise", "0.05", "--seed", "12"], DISC_INIT, False,
     "same disc, noise 5 %"),
    ("disc-blur2-noise2", DISC + ["--blur", "2", "--noise", "0.02", "--seed", "13"],
     DISC_INIT, False, "same disc, blur 2 px + noise 2 %"),
    ("star", ["star", "--size", "1024x1024", "--center", "512.3,511.6", "--radius", "300",
              "--amplitude", "0.2", "--lobes", "5", "--blur", "1", "--noise", "0.01",
              "--levels", "0.2,0.8", "--bits", "8", "--seed", "1"],
     "circle:522,512,300", False,
     "star r=300(1+0.2cos5t), 1024x1024, blur 1 px + noise 1 %"),
    ("sine-edge", ["sine-edge", "--size", "512x512", "--amplitude", "25", "--wavelength",
                   "256", "--y0", "256.3", "--blur", "1", "--noise", "0.01",
                   "--levels", "0.2,0.8", "--bits", "8", "--seed", "7"],
     "segment:20,256,491,256", True,
     "open edge y=256.3+25sin(2pi x/256), 512x512, blur 1 px + noise 1 %; scored on x in [20, 491]"),
]

SPE_ITERS = (0, 1, 2)
SPE_MAX_DIST = 3.0  # px from the rough (Otsu) contour


# ---------------------------------------------------------------- helpers

def run(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw)


def best_time(fn, repeats):
    """One warm-up call, then `repeats` timed calls; returns (best seconds, result)."""
    result = fn()
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def write_points(path, xy):
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x", "y"])
        for x, y in xy:
            w.writerow([f"{x:.6f}", f"{y:.6f}"])
    return len(xy)


def evaluate(vicurve, points, truth, out_json):
    run([vicurve, "eval", str(points), str(truth), "--json", str(out_json)])
    with open(out_json) as f:
        return json.load(f)


def clip_x(xy, xrange):
    if xrange is None or len(xy) == 0:
        return xy
    lo, hi = xrange
    keep = (xy[:, 0] >= lo) & (xy[:, 0] <= hi)
    return xy[keep]


def plateau_levels(img):
    """Background/foreground levels as a user would estimate them: Otsu
    threshold, then the median of the pixels on each side."""
    t = filters.threshold_otsu(img)
    lo = float(np.median(img[img <= t]))
    hi = float(np.median(img[img > t]))
    return lo, hi


# ---------------------------------------------------------------- peers
# Each returns an (N, 2) array of (x, y) in vicurve's convention.

def peer_skimage(img, is_open):
    f = img.astype(np.float64)
    lo, hi = plateau_levels(f)
    contours = measure.find_contours(f, 0.5 * (lo + hi))
    if not contours:
        raise RuntimeError("find_contours returned no contour")
    c = max(contours, key=len)
    if not is_open and len(c) > 1 and np.allclose(c[0], c[-1]):
        c = c[:-1]  # closed contours repeat their first point
    return np.column_stack([c[:, 1], c[:, 0]])  # (row, col) -> (x=col, y=row)


def otsu_contour(img_u8):
    _, mask = cv2.threshold(img_u8, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    res = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    contours = res[-2]  # OpenCV 3 returns 3 values, 4/5 two
    if not contours:
        raise RuntimeError("findContours returned no contour")
    c = max(contours, key=len)
    return c[:, 0, :].astype(np.float64)  # integer (x=col, y=row) of border pixels


def peer_opencv(img_u8, is_open):
    xy = otsu_contour(img_u8)
    if is_open:
        h, w = img_u8.shape
        frame = (xy[:, 0] == 0) | (xy[:, 0] == w - 1) | (xy[:, 1] == 0) | (xy[:, 1] == h - 1)
        xy = xy[~frame]
    return xy


def peer_subpixel_edges(img_u8, iters, is_open):
    f = img_u8.astype(np.float64)
    lo, hi = plateau_levels(f)
    threshold = 0.1 * (hi - lo)
    ep = subpixel_edges(f, threshold, iters, 2)
    xy = np.column_stack([np.ravel(ep.x), np.ravel(ep.y)]).astype(np.float64)
    # keep the edge of the object: points within SPE_MAX_DIST px of the
    # rough pixel contour (Otsu + findContours)
    rough = otsu_contour(img_u8)
    h, w = img_u8.shape
    canvas = np.full((h, w), 255, np.uint8)
    canvas[rough[:, 1].astype(int), rough[:, 0].astype(int)] = 0
    dist = cv2.distanceTransform(canvas, cv2.DIST_L2, 5)
    j = np.clip(np.rint(xy[:, 0]).astype(int), 0, w - 1)
    i = np.clip(np.rint(xy[:, 1]).astype(int), 0, h - 1)
    ok = np.isfinite(xy).all(axis=1) & (dist[i, j] <= SPE_MAX_DIST)
    return xy[ok]


# ---------------------------------------------------------------- vicurve

def run_vicurve(vicurve, image, init, work, repeats):
    pts = work / "vicurve.points.csv"
    res = work / "vicurve.result.json"
    cmd = [vicurve, "measure", str(image), "--init", init, "--points", str(pts),
           "--out", str(res)]
    best_wall, best_fit = float("inf"), float("inf")
    for k in range(repeats + 1):  # first run is a warm-up (file cache)
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if p.returncode != 0:
            raise RuntimeError(f"vicurve measure exit {p.returncode}: {p.stderr.strip()}")
        with open(res) as f:
            r = json.load(f)
        fit = sum(s["seconds"] for s in r["stages"])
        if k > 0:
            best_wall, best_fit = min(best_wall, wall), min(best_fit, fit)
    return pts, best_fit, best_wall, " ".join(["vicurve"] + cmd[1:])


# ---------------------------------------------------------------- main

def fmt(v, spec=".3e"):
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    return format(v, spec)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--vicurve", default=os.environ.get("VICURVE") or shutil.which("vicurve"),
                    help="path of the vicurve binary (default: $VICURVE, then PATH)")
    ap.add_argument("--work", default=str(HERE / "work"), help="work directory")
    ap.add_argument("--repeats", type=int, default=5, help="timed runs per tool (best kept)")
    ap.add_argument("--cases", default="", help="comma-separated subset of case names")
    ap.add_argument("--out-dir", default=str(HERE), help="where results.csv/.md go")
    args = ap.parse_args()
    if not args.vicurve:
        sys.exit("vicurve binary not found: pass --vicurve PATH or set VICURVE")
    vicurve = str(Path(args.vicurve).resolve())
    work_root = Path(args.work)
    work_root.mkdir(parents=True, exist_ok=True)
    wanted = set(filter(None, args.cases.split(",")))
    cases = [c for c in CASES if not wanted or c[0] in wanted]

    # numba compilation of subpixel-edges, excluded from the timings
    jit_seconds = None
    if subpixel_edges is not None:
        t0 = time.perf_counter()
        try:
            _spe_mod.init()
            jit_seconds = time.perf_counter() - t0
        except Exception:
            pass  # the per-case calls will record the failure

    rows = []
    commands = []
    for name, synth_args, init, is_open, desc in cases:
        work = work_root / name
        work.mkdir(parents=True, exist_ok=True)
        image, truth = work / "image.png", work / "truth.json"
        synth_cmd = [vicurve, "synth"] + synth_args + ["--out", str(image), "--truth", str(truth)]
        run(synth_cmd)
        commands.append(("synth", name, " ".join(["vicurve", "synth"] + synth_args +
                                                 ["--out", f"{name}.png", "--truth", f"{name}.json"])))
        img = cv2.imread(str(image), cv2.IMREAD_UNCHANGED)
        if img is None or img.dtype != np.uint8 or img.ndim != 2:
            raise RuntimeError(f"{image}: expected an 8-bit gray PNG")
        h, w = img.shape
        xrange = None
        if is_open:
            seg = [float(v) for v in init.split(":")[1].split(",")]
            xrange = (min(seg[0], seg[2]), max(seg[0], seg[2]))
        print(f"== {name}: {desc}", flush=True)

        def record(tool, status, pts_path=None, t=None, t_what="", wall=None, note=""):
            row = dict(case=name, tool=tool, status=status, points=None, bias_px=None,
                       scatter_px=None, max_abs_px=None, time_s=t, time_what=t_what,
                       process_wall_s=wall, scatter_ratio_vs_vicurve=None, note=note)
            if status == "ok":
                e = evaluate(vicurve, pts_path, truth, work / f"{tool}.eval.json")
                row.update(points=e["count"], bias_px=e["bias"], scatter_px=e["scatter"],
                           max_abs_px=e["max_abs"])
            rows.append(row)
            print(f"   {tool:22s} {status:6s} bias {fmt(row['bias_px'], '+.3e'):>11s} "
                  f"scatter {fmt(row['scatter_px']):>10s} max {fmt(row['max_abs_px']):>10s} "
                  f"time {fmt(t, '.4f')} s {note}", flush=True)

        # vicurve
        try:
            pts, fit_s, wall_s, vcmd = run_vicurve(vicurve, image, init, work, args.repeats)
            commands.append(("measure", name, vcmd.replace(str(image), f"{name}.png")
                             .replace(str(work) + "/", "")))
            record("vicurve", "ok", pts, fit_s, "sum of per-stage seconds (fit only)", wall_s,
                   f"--init {init}")
        except Exception as exc:
            record("vicurve", "failed", note=str(exc))
        for k, alt in enumerate(EXTRA_INITS.get(name, [])):
            tool = f"vicurve(--init {alt})"
            alt_work = work / f"alt{k}"
            alt_work.mkdir(exist_ok=True)
            try:
                pts, fit_s, wall_s, _ = run_vicurve(vicurve, image, alt, alt_work, args.repeats)
                record(tool, "ok", pts, fit_s, "sum of per-stage seconds (fit only)", wall_s,
                       "alternative start")
            except Exception as exc:
                record(tool, "failed", note=str(exc))

        # skimage
        try:
            t, xy = best_time(lambda: peer_skimage(img, is_open), args.repeats)
            xy = clip_x(xy, xrange)
            p = work / "skimage.points.csv"
            write_points(p, xy)
            record("skimage-find_contours", "ok", p, t, "extraction (levels + find_contours + longest)")
        except Exception as exc:
            record("skimage-find_contours", "failed", note=f"{type(exc).__name__}: {exc}")

        # OpenCV
        try:
            t, xy = best_time(lambda: peer_opencv(img, is_open), args.repeats)
            xy = clip_x(xy, xrange)
            p = work / "opencv.points.csv"
            write_points(p, xy)
            record("opencv-otsu-findContours", "ok", p, t,
                   "extraction (Otsu + findContours + longest)",
                   note="points = centres of the border pixels of the bright region")
        except Exception as exc:
            record("opencv-otsu-findContours", "failed", note=f"{type(exc).__name__}: {exc}")

        # subpixel-edges
        for it in SPE_ITERS:
            tool = f"subpixel-edges-iters{it}"
            if subpixel_edges is None:
                record(tool, "failed", note=f"import failed: {SPE_IMPORT_ERROR}")
                continue
            try:
                t, xy = best_time(lambda: peer_subpixel_edges(img, it, is_open), args.repeats)
                xy = clip_x(xy, xrange)
                if len(xy) == 0:
                    raise RuntimeError("no edge point near the object")
                p = work / f"{tool}.points.csv"
                write_points(p, xy)
                record(tool, "ok", p, t, "extraction (subpixel_edges + 3 px filter)")
            except Exception as exc:
                tb = traceback.format_exc(limit=1).strip().splitlines()[-1]
                record(tool, "failed", note=f"{type(exc).__name__}: {exc}"[:300] or tb)

    # ratios
    vic = {r["case"]: r["scatter_px"] for r in rows if r["tool"] == "vicurve" and r["status"] == "ok"}
    for r in rows:
        v = vic.get(r["case"])
        if r["status"] == "ok" and v:
            r["scatter_ratio_vs_vicurve"] = r["scatter_px"] / v

    out_dir = Path(args.out_dir)
    fields = ["case", "tool", "status", "points", "bias_px", "scatter_px", "max_abs_px",
              "time_s", "time_what", "process_wall_s", "scatter_ratio_vs_vicurve", "note"]
    with open(out_dir / "results.csv", "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=fields)
        wr.writeheader()
        for r in rows:
            wr.writerow({k: ("" if r[k] is None else
                             (repr(r[k]) if isinstance(r[k], float) else r[k])) for k in fields})
    write_markdown(out_dir / "results.md", rows, cases, commands, args, jit_seconds)
    print(f"wrote {out_dir / 'results.csv'} and {out_dir / 'results.md'}")


def versions():
    def ver(mod):
        try:
            from importlib.metadata import version
            return version(mod)
        except Exception:
            return "?"
    cpu = platform.processor() or "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"Python {platform.python_version()}, numpy {np.__version__}, scikit-image "
            f"{skimage.__version__}, opencv-python-headless {cv2.__version__}, subpixel-edges "
            f"{ver('subpixel-edges')}, numba {ver('numba')}; CPU: {cpu}, {os.cpu_count()} "
            f"logical cores")


def write_markdown(path, rows, cases, commands, args, jit_seconds):
    L = []
    L.append("# vicurve and its peers on the same images\n")
    L.append("Generated by `run_peers.py` (see its docstring for the conventions and how "
             "each tool is called). Distances are signed normal distances from each output "
             "point to the exact curve, by `vicurve eval`: bias = mean (+ = outside the "
             "closed shape / towards +y for the sine), scatter = RMS about the mean, "
             "max = largest |distance|, all in pixels. Time: peers = extraction only, image "
             "in memory, best of "
             f"{args.repeats}; vicurve = sum of its per-stage `seconds` (fit only), with the "
             "wall clock of the whole `vicurve measure` process (start, PNG decode, fit, "
             "CSV+JSON output) in parentheses. Ratio = peer scatter / vicurve scatter "
             "(> 1: vicurve scatters less).\n")
    L.append(f"Environment: {versions()}.\n")
    L.append("| case | tool | points | bias (px) | scatter (px) | max (px) | time (s) | ratio |")
    L.append("|---|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        if r["status"] != "ok":
            L.append(f"| {r['case']} | {r['tool']} | failed | | | | | {r['note']} |")
            continue
        t = fmt(r["time_s"], ".4f")
        if r["process_wall_s"] is not None:
            t += f" ({r['process_wall_s']:.3f})"
        ratio = "1" if r["tool"] == "vicurve" else fmt(r["scatter_ratio_vs_vicurve"], ".3g")
        L.append(f"| {r['case']} | {r['tool']} | {r['points']} | {r['bias_px']:+.2e} | "
                 f"{r['scatter_px']:.2e} | {r['max_abs_px']:.2e} | {t} | {ratio} |")
    L.append("")
    L.append("## Notes\n")
    L.append("- OpenCV's points are the integer centres of the bright region's border "
             "pixels (pixel precision), not edge positions: they lie 0 to ~1 px inside the "
             "bright side, hence their bias of about -0.45 px and scatter of about 0.26 px on "
             "every case. OpenCV's main modules offer no sub-pixel edge or contour detector "
             "(Canny and findContours are pixel-level; cornerSubPix refines corners), so none "
             "is run.")
    L.append("- skimage (a level crossing) and subpixel-edges (whose model is a sharp edge) "
             "find the blurred edge on blurred images, which lies about sigma^2/(2 rho) inside a convex boundary "
             "(rho: radius of curvature): 1/300 = 3.3e-3 px for the disc blurred by 1 px, "
             "4/300 = 1.3e-2 px for blur 2 px. Their raw errors are reported; vicurve models "
             "the blur and reports the true boundary.")
    L.append("- subpixel-edges: `iters` 0 is meant for noise-free images, 1 for low noise, "
             ">1 for high noise (its docstring); all three are reported on every case. "
             "Threshold = 10 % of the estimated contrast; points more than 3 px from the "
             "Otsu contour are dropped. It needed `np.int = int` (see the docstring of "
             "`run_peers.py`).")
    L.append("- Sine edge: every tool is scored on x in [20, 491], the span of vicurve's "
             "start segment; the row `vicurve(--init segment:0,256,511,256)` is the start "
             "drawn from border to border.")
    L.append("")
    L.append("## Cases\n")
    for name, _, init, _, desc in cases:
        L.append(f"- `{name}`: {desc}; vicurve starts from `{init}`.")
    L.append("")
    if jit_seconds is not None:
        L.append(f"subpixel-edges' numba compilation (its `init()`, excluded from the times): "
                 f"{jit_seconds:.1f} s.\n")
    L.append("## Reproduce\n")
    L.append("```sh")
    L.append("python3 -m venv /work/scratch/peers-venv")
    L.append("/work/scratch/peers-venv/bin/pip install -r bench/peers/requirements.txt")
    L.append("cargo build --release -p vicurve-cli")
    L.append("/work/scratch/peers-venv/bin/python bench/peers/run_peers.py "
             "--vicurve target/release/vicurve")
    L.append("```\n")
    L.append("This file was written by: `python " + " ".join(
        [Path(sys.argv[0]).name] + sys.argv[1:]) + "`.\n")
    L.append("The images and vicurve runs it makes (file names relative to the case's "
             "work directory):\n")
    L.append("```sh")
    for _, _, c in commands:
        L.append(c)
    L.append("```")
    with open(path, "w") as f:
        f.write("\n".join(L) + "\n")


if __name__ == "__main__":
    main()
