//! Holes inside objects: with `holes`, measured as objects of the opposite
//! polarity, numbered after the objects with their parent; without it, the
//! objects alone, their bands kept off the holes' edges.

use vicurve::objects::{measure_all, AllConfig, AllResult};
use vicurve::render::scene::{render_scene, Rendering, Role, Scene, SceneItem};
use vicurve::truth::Shape;

/// A disc with an off-centre round hole, an ellipse with an elliptic hole,
/// a disc without one; blur 1 px, noise 1 %, 8 bits.
fn holed_scene() -> Scene {
    let item = |shape, role| SceneItem {
        shape,
        role,
        strain: None,
    };
    let circle = |cx, cy, r| Shape::Circle { cx, cy, r };
    let ellipse = |cx, cy, a, b, angle| Shape::Ellipse {
        cx,
        cy,
        a,
        b,
        angle,
    };
    Scene {
        width: 400,
        height: 300,
        items: vec![
            item(circle(100.3, 110.2, 40.0), Role::Object),
            item(circle(103.4, 107.8, 15.0), Role::Hole),
            item(ellipse(280.4, 140.7, 50.0, 34.0, 0.3), Role::Object),
            item(ellipse(279.1, 141.9, 22.0, 12.5, -0.2), Role::Hole),
            item(circle(180.6, 240.3, 20.0), Role::Object),
        ],
        rendering: Rendering::standard(7),
        d0: None,
    }
}

/// The object whose best-fit ellipse is nearest `shape` (centre and axes),
/// and its centre and axes errors against it (px).
fn errors(all: &AllResult, shape: &Shape) -> (usize, f64, f64) {
    let (cx, cy, a, b) = match *shape {
        Shape::Circle { cx, cy, r } => (cx, cy, r, r),
        Shape::Ellipse { cx, cy, a, b, .. } => (cx, cy, a, b),
        _ => unreachable!("circles and ellipses only"),
    };
    all.objects
        .iter()
        .enumerate()
        .filter_map(|(k, o)| {
            let e = o.closed.as_ref()?.ellipse;
            let axes = (e.a.max(e.b) - a).abs().max((e.a.min(e.b) - b).abs());
            Some((k, (e.cx - cx).hypot(e.cy - cy), axes))
        })
        .min_by(|p, q| (p.1 + p.2).total_cmp(&(q.1 + q.2)))
        .unwrap_or_else(|| panic!("nothing measured"))
}

#[test]
fn holes_are_measured_as_objects_of_the_other_polarity() {
    let scene = holed_scene();
    let image = render_scene(&scene).unwrap();
    let config = AllConfig {
        holes: true,
        ..AllConfig::default()
    };
    let all = measure_all(&image, &config).unwrap();
    assert_eq!(all.objects.len(), 5, "{:?}", all.found);
    assert_eq!(all.found.holes, 2);
    assert_eq!(
        all.failed(),
        0,
        "{:?}",
        all.objects.iter().map(|o| &o.failure).collect::<Vec<_>>()
    );
    let mut worst = (0.0f64, 0.0f64);
    for (n, item) in scene.items.iter().enumerate() {
        let (k, centre, axes) = errors(&all, &item.shape);
        let o = &all.objects[k];
        eprintln!(
            "{:?} {n}: id {} centre {centre:.2e} axes {axes:.2e}",
            item.role, o.id
        );
        worst = (worst.0.max(centre), worst.1.max(axes));
        match item.role {
            // The holes come after the three objects, each with its object.
            Role::Hole => {
                assert!(o.id >= 3);
                let parent = o.region.parent.expect("a hole has a parent");
                let (p, _, _) = errors(&all, &scene.items[n - 1].shape);
                assert_eq!(parent, all.objects[p].id);
            }
            _ => assert!(o.id < 3 && o.region.parent.is_none()),
        }
    }
    eprintln!(
        "holes: worst centre error {:.2e} px, axes {:.2e} px",
        worst.0, worst.1
    );
    assert!(worst.0 < 0.02 && worst.1 < 0.02, "{worst:?}");
}

#[test]
fn without_holes_the_objects_alone_are_measured() {
    let image = render_scene(&holed_scene()).unwrap();
    let all = measure_all(&image, &AllConfig::default()).unwrap();
    assert_eq!(all.objects.len(), 3);
    assert_eq!(all.failed(), 0);
    // The disc's band is kept off its hole: the gap is the ring's width.
    let (k, _, _) = errors(&all, &holed_scene().items[0].shape);
    let ring = all.objects[k].region.gap;
    assert!((18.0..23.0).contains(&ring), "{ring}");
}
