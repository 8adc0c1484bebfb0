//! `measure --all`, `synth scene|grid` and `grid`, end to end.

use crate::common::{assert_error, ok, p, text, vicurve};

fn json(path: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The rows of a CSV file as cells, header first.
fn csv(path: &str) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

/// A scene of 50 objects, 20 specks and 5 border discs: every whole
/// object in the table, measured, near its true centre; the result file
/// holds each; the points carry an `object` column.
#[test]
fn measure_all_on_a_scene() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = (p(d, "scene.png"), p(d, "scene.json"));
    ok(&vicurve(&[
        "synth", "scene", "--out", &img, "--truth", &truth,
    ]));
    let (table, out, points) = (p(d, "objects.csv"), p(d, "all.json"), p(d, "pts.csv"));
    let run = vicurve(&[
        "measure", &img, "--all", "--model", "ellipse", "--table", &table, "--out", &out,
        "--points", &points,
    ]);
    ok(&run);
    let t = json(&truth);
    let whole: Vec<[f64; 2]> = t["items"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["role"] == "object")
        .map(|i| {
            [
                i["shape"]["cx"].as_f64().unwrap(),
                i["shape"]["cy"].as_f64().unwrap(),
            ]
        })
        .collect();
    assert_eq!(whole.len(), 50);
    let rows = csv(&table);
    let col = |n: &str| rows[0].iter().position(|c| c == n).unwrap();
    let (cx, cy, outcome) = (col("model_cx"), col("model_cy"), col("outcome"));
    assert_eq!(rows.len() - 1, whole.len(), "{}", text(&run.stderr));
    for c in &whole {
        let row = rows[1..]
            .iter()
            .find(|r| {
                let x: f64 = r[cx].parse().unwrap_or(f64::NAN);
                let y: f64 = r[cy].parse().unwrap_or(f64::NAN);
                (x - c[0]).hypot(y - c[1]) < 0.02
            })
            .unwrap_or_else(|| panic!("object at {c:?} not measured within 0.02 px"));
        assert_eq!(row[outcome], "measured");
    }
    let record = json(&out);
    assert_eq!(record["objects"].as_array().unwrap().len(), 50);
    assert_eq!(record["failed"], 0);
    assert!(record["coordinates"]
        .as_str()
        .unwrap()
        .contains("x = column"));
    let pts = csv(&points);
    assert_eq!(pts[0][0], "object");
    assert!(pts[1..].iter().any(|r| r[0] == "49"));
    // eval against the scene: object by object, each matched, none extra.
    let eval = p(d, "eval.json");
    let scored = vicurve(&["eval", &points, &truth, "--json", &eval]);
    ok(&scored);
    assert!(
        text(&scored.stdout).contains("matched: 50 object(s); missed: []; extra: []"),
        "{}",
        text(&scored.stdout)
    );
    let e = json(&eval);
    let objects = e["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 50);
    assert!(objects.iter().all(|o| o["role"] == "object"));
}

/// Two discs touching among isolated ones: the pair fails with its reason,
/// the others are measured, the exit code is 3.
#[test]
fn a_touching_pair_fails_and_the_exit_code_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = vicurve::render::scene::random_scene(400, 300, 4, 0, 0, true, 10.0, 2).unwrap();
    let image = vicurve::render::scene::render_scene(&scene).unwrap();
    let img = p(d, "pair.png");
    vicurve::io::save_image(img.as_ref(), &image, 8).unwrap();
    let table = p(d, "objects.csv");
    let run = vicurve(&[
        "measure", &img, "--all", "--model", "ellipse", "--table", &table,
    ]);
    // A line per failed object, then the error line.
    assert_eq!(run.status.code(), Some(3), "{}", text(&run.stderr));
    let stderr = text(&run.stderr);
    let last = stderr.lines().last().unwrap();
    assert!(
        last.starts_with("vicurve: error:") && last.contains("objects failed"),
        "{last}"
    );
    let rows = csv(&table);
    let outcome = rows[0].iter().position(|c| c == "outcome").unwrap();
    let failed: Vec<_> = rows[1..]
        .iter()
        .filter(|r| r[outcome] != "measured")
        .collect();
    let measured = rows.len() - 1 - failed.len();
    assert_eq!(measured, 4, "{}", text(&run.stderr));
    assert!((1..=2).contains(&failed.len()));
    for r in failed {
        assert!(
            r[outcome] == "model_misfit" || r[outcome] == "too_close",
            "{r:?}"
        );
    }
}

/// Dots all under the least area: nothing is measured, so the run fails
/// (exit 1) and says which options measure them; with those lowered, all
/// are measured.
#[test]
fn dots_all_too_small_are_not_a_silent_success() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let image = vicurve::Image::from_fn(60, 60, |x, y| {
        let near = [[15.3, 15.6], [44.2, 15.4], [15.1, 44.3], [44.6, 44.7]]
            .iter()
            .any(|c| (x as f64 - c[0]).hypot(y as f64 - c[1]) <= 3.5);
        if near {
            0.8
        } else {
            0.2
        }
    });
    let img = p(d, "dots.png");
    vicurve::io::save_image(img.as_ref(), &image, 8).unwrap();
    let run = vicurve(&["measure", &img, "--all"]);
    let stderr = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    let last = stderr.lines().last().unwrap();
    assert!(
        last.contains("no object measured: 4 left out as too small") && last.contains("--min-area"),
        "{last}"
    );
    let table = p(d, "objects.csv");
    let run = vicurve(&[
        "measure",
        &img,
        "--all",
        "--min-area",
        "10",
        "--min-length",
        "10",
        "--table",
        &table,
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert_eq!(csv(&table).len(), 5);
}

/// `synth grid` then `grid`: one row per circle, strains near the truth.
#[test]
fn grid_strains_from_a_synthetic_grid() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = (p(d, "grid.png"), p(d, "grid.json"));
    ok(&vicurve(&[
        "synth", "grid", "--out", &img, "--truth", &truth,
    ]));
    let table = p(d, "strains.csv");
    let fld = p(d, "fld.svg");
    ok(&vicurve(&[
        "grid",
        &img,
        "--diameter",
        "30",
        "--table",
        &table,
        "--fld",
        &fld,
    ]));
    let svg = std::fs::read_to_string(&fld).unwrap();
    assert_eq!(svg.matches("<circle ").count(), 100);
    let rows = csv(&table);
    assert_eq!(rows.len() - 1, 100);
    let col = |n: &str| rows[0].iter().position(|c| c == n).unwrap();
    let t = json(&truth);
    let items = t["items"].as_array().unwrap();
    for (r, item) in rows[1..].iter().zip(items) {
        let s = item["strain"].as_array().unwrap();
        for (name, k) in [("eps1", 0), ("eps2", 1)] {
            let v: f64 = r[col(name)].parse().unwrap();
            let sigma: f64 = r[col(&format!("sigma_{name}"))].parse().unwrap();
            let e = (v - s[k].as_f64().unwrap()).abs();
            assert!(e < 5.0 * sigma && e < 1e-3, "{name} {e} sigma {sigma}");
        }
    }
    // The scale: D0 in mm, centres in mm.
    let mm = p(d, "strains_mm.csv");
    ok(&vicurve(&[
        "grid",
        &img,
        "--diameter",
        "3",
        "--scale",
        "0.1",
        "--roi",
        "0,0,200,200",
        "--table",
        &mm,
    ]));
    assert!(csv(&mm)[0].contains(&"x_mm".to_string()));
    // The scatter as PNG: an image twice the SVG's size.
    let png = p(d, "fld.png");
    ok(&vicurve(&[
        "grid",
        &img,
        "--diameter",
        "30",
        "--roi",
        "0,0,200,200",
        "--fld",
        &png,
    ]));
    let plot = vicurve::io::load_image(png.as_ref()).unwrap();
    assert_eq!((plot.width(), plot.height()), (1120, 960));
    // The strain map: every circle, its colour's bin in the legend.
    let (map_svg, map_png) = (p(d, "map.svg"), p(d, "map.png"));
    for m in [&map_svg, &map_png] {
        ok(&vicurve(&["grid", &img, "--diameter", "30", "--map", m]));
    }
    let map = std::fs::read_to_string(&map_svg).unwrap();
    assert_eq!(map.matches("<polygon ").count(), 100);
    let bins = map.matches("fill=\"black\">eps1 ").count();
    assert!((2..=6).contains(&bins), "{bins} legend entries");
    let drawn = vicurve::io::load_image(map_png.as_ref()).unwrap();
    let grid_image = vicurve::io::load_image(img.as_ref()).unwrap();
    assert_eq!(drawn.width(), grid_image.width());
}

/// `synth square-grid` then `grid --pitch`: every cell in the table with
/// its lattice index, interior strains near the truth, the JSON's cells;
/// --pitch and --diameter are exclusive, one is needed.
#[test]
fn square_grid_strains_from_a_synthetic_grid() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = (p(d, "sq.png"), p(d, "sq.json"));
    ok(&vicurve(&[
        "synth",
        "square-grid",
        "--out",
        &img,
        "--truth",
        &truth,
    ]));
    let t = json(&truth);
    let pitch = t["pitch"].as_f64().unwrap().to_string();
    let (table, out) = (p(d, "cells.csv"), p(d, "cells.json"));
    let run = vicurve(&[
        "grid", &img, "--pitch", &pitch, "--table", &table, "--out", &out,
    ]);
    ok(&run);
    assert!(
        text(&run.stderr).contains("36 from central differences"),
        "{}",
        text(&run.stderr)
    );
    let rows = csv(&table);
    assert_eq!(rows.len() - 1, 64);
    let col = |n: &str| rows[0].iter().position(|c| c == n).unwrap();
    let cells = t["cells"].as_array().unwrap();
    let mut checked = 0;
    for r in &rows[1..] {
        let ij = [
            r[col("column")].parse::<i64>().unwrap(),
            r[col("row")].parse::<i64>().unwrap(),
        ];
        let c = cells
            .iter()
            .find(|c| {
                c["index"][0].as_i64() == Some(ij[0]) && c["index"][1].as_i64() == Some(ij[1])
            })
            .unwrap();
        for (name, k) in [("x", 0), ("y", 1)] {
            let v: f64 = r[col(name)].parse().unwrap();
            assert!(
                (v - c["centroid"][k].as_f64().unwrap()).abs() < 0.02,
                "{name} of {ij:?}"
            );
        }
        if r[col("central")] == "1" {
            for (name, k) in [("eps1", 0), ("eps2", 1)] {
                let v: f64 = r[col(name)].parse().unwrap();
                let e = (v - c["strain"][k].as_f64().unwrap()).abs();
                assert!(e < 3e-4, "{name} of {ij:?}: {e}");
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 36);
    let j = json(&out);
    assert_eq!(j["cells"].as_array().unwrap().len(), 64);
    assert!(j.get("circles").is_none() && j["pitch_px"].as_f64().is_some());
    assert_eq!(j["config"]["corners"].as_u64(), Some(4));
    let both = vicurve(&["grid", &img, "--pitch", "50", "--diameter", "30"]);
    assert_eq!(both.status.code(), Some(2));
    assert!(text(&both.stderr).contains("cannot be used with"));
    let neither = vicurve(&["grid", &img]);
    assert_eq!(neither.status.code(), Some(2));
    assert!(
        text(&neither.stderr).contains("--diameter <D0>|--pitch <P0>"),
        "{}",
        text(&neither.stderr)
    );
}

/// Options of --all without it, and --all with --init, are refused.
#[test]
fn all_options_are_checked() {
    let out = vicurve(&["measure", "x.png", "--table", "t.csv"]);
    assert_error(&out, 1, "go with --all");
    let out = vicurve(&["measure", "x.png", "--all", "--init", "circle:1,2,3"]);
    assert_error(&out, 1, "drop --init");
}

/// `synth grid --size` makes an image of that size (the grid spread over
/// it), and refuses one too small for the circles.
#[test]
fn synth_grid_honours_the_size() {
    let dir = tempfile::tempdir().unwrap();
    let img = p(dir.path(), "grid.png");
    ok(&vicurve(&[
        "synth", "grid", "--size", "900x800", "--out", &img,
    ]));
    let image = vicurve::io::load_image(img.as_ref()).unwrap();
    assert_eq!((image.width(), image.height()), (900, 800));
    let out = vicurve(&["synth", "grid", "--size", "300x300", "--out", &img]);
    assert_error(&out, 1, "a larger image or smaller circles");
}

/// `measure --all --svg --png`: every object's curve with its id, one
/// legend entry for all the measured ones; `--holes` adds the hole of a
/// holed disc to the table with its parent.
#[test]
fn overlays_show_every_object_with_its_id_and_holes_have_a_parent() {
    use vicurve::render::scene::{render_scene, Rendering, Role, Scene, SceneItem};
    use vicurve::truth::Shape;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let item = |cx, cy, r, role| SceneItem {
        shape: Shape::Circle { cx, cy, r },
        role,
        strain: None,
    };
    let scene = Scene {
        width: 400,
        height: 300,
        items: vec![
            item(70.3, 60.2, 20.0, Role::Object),
            item(200.6, 70.4, 18.0, Role::Object),
            item(80.2, 220.7, 22.0, Role::Object),
            item(300.4, 190.6, 50.0, Role::Object),
            item(301.3, 189.9, 18.0, Role::Hole),
        ],
        rendering: Rendering::standard(3),
        d0: None,
    };
    let image = render_scene(&scene).unwrap();
    let img = p(d, "holed.png");
    vicurve::io::save_image(img.as_ref(), &image, 8).unwrap();
    let (svg, png, table) = (p(d, "o.svg"), p(d, "o.png"), p(d, "t.csv"));
    let run = vicurve(&[
        "measure", &img, "--all", "--holes", "--svg", &svg, "--png", &png, "--table", &table,
    ]);
    ok(&run);
    let rows = csv(&table);
    assert_eq!(rows.len() - 1, 5, "{}", text(&run.stderr));
    let parent = rows[0].iter().position(|c| c == "parent").unwrap();
    let holes: Vec<_> = rows[1..].iter().filter(|r| !r[parent].is_empty()).collect();
    assert_eq!(holes.len(), 1);
    assert_eq!(holes[0][0], "4");
    let text_svg = std::fs::read_to_string(&svg).unwrap();
    for id in 0..5 {
        assert!(text_svg.contains(&format!(">{id}</text>")), "id {id}");
    }
    let legend = ">measured object (id at its centre)</text>";
    assert_eq!(text_svg.matches(legend).count(), 1);
    let overlay = vicurve::io::load_image(png.as_ref()).unwrap();
    assert_eq!((overlay.width(), overlay.height()), (400, 300));
}

/// `measure --all --kind contour`: every line of an image of two rings,
/// followed and measured, one row each.
#[test]
fn measure_all_lines() {
    use vicurve::render::{render, Method, RenderSpec};
    use vicurve::truth::Shape;
    let dir = tempfile::tempdir().unwrap();
    let ring = |cx, cy, r| {
        let spec = RenderSpec {
            width: 260,
            height: 160,
            shape: Shape::Circle { cx, cy, r },
            kind: vicurve::virtual_image::Kind::Contour,
            line_width: 3.0,
            method: Method::Coverage,
            blur_sigma: 1.0,
            noise: 0.0,
            bits: None,
            ..RenderSpec::default()
        };
        render(&spec).unwrap()
    };
    let (a, b) = (ring(70.3, 80.6, 45.0), ring(190.7, 78.2, 40.0));
    let bg = RenderSpec::default().background;
    let image = vicurve::Image::from_fn(260, 160, |x, y| a.get(x, y) + b.get(x, y) - bg);
    let img = p(dir.path(), "rings.png");
    vicurve::io::save_image(img.as_ref(), &image, 16).unwrap();
    let table = p(dir.path(), "lines.csv");
    let run = vicurve(&[
        "measure", &img, "--all", "--kind", "contour", "--table", &table,
    ]);
    ok(&run);
    assert!(text(&run.stderr).contains("2 bright line(s) found"));
    let rows = csv(&table);
    assert_eq!(rows.len() - 1, 2);
    let r = rows[0].iter().position(|c| c == "circle_r").unwrap();
    let mut radii: Vec<f64> = rows[1..]
        .iter()
        .map(|row| row[r].parse().unwrap())
        .collect();
    radii.sort_by(f64::total_cmp);
    assert!(
        (radii[0] - 40.0).abs() < 0.01 && (radii[1] - 45.0).abs() < 0.01,
        "{radii:?}"
    );
}
