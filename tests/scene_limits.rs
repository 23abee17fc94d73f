//! Issue 30, acceptance: a property test over the scene file's documented numeric limits
//! (docs/scene.md, "Limits", and the key tables). Each generated scene sets one key at or beyond
//! its limit, and puts a few other keys at their own limits. A scene with every value at or
//! within its limit is read; a scene with one value beyond is refused, the message naming that
//! key's dotted path (`solver.constraints.turning_radius.radius`, `edits[0].strength`, …).
//! Nothing panics. A scene is read as `grainline run` reads it: the file's checks, then its
//! outputs' paths.

use std::path::Path;

use grainline::pipeline::plan::output_path;
use grainline::scene::{LoadedScene, Scene};
use proptest::prelude::*;
use serde_json::{json, Value};

/// One documented limit: where it sits in the scene, the key the error must name, values at
/// the limit (read), and values beyond it (refused) made from a random magnitude.
struct Limit {
    /// Path of keys in the scene JSON (`[0]` as the key "0" of an array).
    path: &'static [&'static str],
    /// The key the refusal names.
    key: &'static str,
    /// Values at the limit, or inside it: read.
    at: fn() -> Vec<Value>,
    /// A value beyond the limit, from `f` in [1e-9, 1e200] and a choice `k`.
    beyond: fn(f64, usize) -> Value,
}

fn num(x: f64) -> Value {
    json!(x)
}

/// Beyond an upper bound `hi` (and, by `k`, a negative value).
fn above(hi: f64, f: f64, k: usize) -> Value {
    if k % 3 == 2 {
        num(-f.max(1e-6))
    } else {
        num(hi * (1.0 + f))
    }
}

/// The plan's lengths, each at most 1e6 scene units.
const PLAN: [(&[&str], &str); 5] = [
    (&["toolpaths", "plan", "lead_in"], "toolpaths.plan.lead_in"),
    (&["toolpaths", "plan", "lead_out"], "toolpaths.plan.lead_out"),
    (&["toolpaths", "plan", "ramp_height"], "toolpaths.plan.ramp_height"),
    (&["toolpaths", "plan", "overtravel"], "toolpaths.plan.overtravel"),
    (&["toolpaths", "plan", "contact_depth"], "toolpaths.plan.contact_depth"),
];

fn limits() -> Vec<Limit> {
    let mut l = vec![
        Limit {
            path: &["mesh", "scale"],
            key: "mesh.scale",
            at: || vec![num(1e-12), num(1e12), num(1.0)],
            beyond: |f, k| match k % 3 {
                0 => num(1e12 * (1.0 + f)),
                1 => num(1e-12 / (1.0 + f)),
                _ => num(-f),
            },
        },
        Limit {
            path: &["mesh", "weld"],
            key: "mesh.weld",
            at: || vec![num(0.0), num(1e-3)],
            beyond: |f, _| num(-f),
        },
        Limit {
            path: &["solver", "smoothness"],
            key: "solver.smoothness",
            at: || vec![num(1e6), num(1e-3)],
            beyond: |f, k| above(1e6, f, k),
        },
        Limit {
            path: &["solver", "constraints", "turning_radius", "radius"],
            key: "solver.constraints.turning_radius.radius",
            at: || vec![num(1e9), num(1.0)],
            beyond: |f, k| above(1e9, f, k),
        },
        Limit {
            path: &["toolpaths", "plan", "order", "neighbours"],
            key: "toolpaths.plan.order.neighbours",
            at: || vec![json!(256), json!(1)],
            beyond: |f, _| json!(257 + (f.log10().abs() * 1000.0) as u64),
        },
        Limit {
            path: &["edits", "0", "radius"],
            key: "edits[0].radius",
            at: || vec![num(1e9), num(0.5)],
            beyond: |f, k| if k % 3 == 1 { num(0.0) } else { above(1e9, f, k) },
        },
        Limit {
            path: &["edits", "0", "strength"],
            key: "edits[0].strength",
            at: || vec![num(1.25), num(-1.25), num(0.0)],
            beyond: |f, k| num(if k % 2 == 0 { 1.25 } else { -1.25 } * (1.0 + f)),
        },
        Limit {
            path: &["render", "width"],
            key: "render.width",
            at: || vec![json!(16384), json!(1)],
            beyond: |f, k| {
                if k % 2 == 0 {
                    json!(16385 + (f.log10().abs() * 99.0) as u64)
                } else {
                    json!(0)
                }
            },
        },
        Limit {
            path: &["render", "output"],
            key: "render.output",
            at: || vec![json!(format!("{}.png", "d/".repeat(2046)))],
            beyond: |f, _| json!(format!("{}.png", "d/".repeat(2047 + (f.log10().abs()) as usize))),
        },
        Limit {
            path: &["lights"],
            key: "lights",
            at: || vec![lights(64)],
            beyond: |f, _| lights(65 + (f.log10().abs() * 3.0) as usize),
        },
        Limit {
            path: &["lights", "0", "direction"],
            key: "lights[0].direction",
            // The eye is at [0, -300, 100] looking at the origin: straight away is [0, 3, -1].
            at: || vec![json!([0.0, 3.0, -1.0 + 0.1]), json!([0.3, -0.5, 1.0])],
            beyond: |f, _| json!([0.0, 3.0 * (1.0 + f.min(1e-6)), -1.0]),
        },
        Limit {
            path: &["edits", "1", "uv"],
            key: "edits[1]",
            at: || vec![polyline(grainline::limits::MAX_CURVE_POINTS)],
            beyond: |f, _| {
                polyline(grainline::limits::MAX_CURVE_POINTS + 1 + f.log10().abs() as usize)
            },
        },
        // Issue 46: numbers in physical ranges, each naming its key.
        Limit {
            path: &["edits", "0", "weight"],
            key: "edits[0].weight",
            at: || vec![num(1e6), num(0.0)],
            beyond: |f, k| above(1e6, f, k),
        },
        Limit {
            path: &["toolpaths", "gcode_options", "safe_z"],
            key: "toolpaths.gcode_options.safe_z",
            at: || vec![num(1e6), num(-1e6), num(5.0)],
            beyond: |f, k| num(if k % 2 == 0 { 1e6 } else { -1e6 } * (1.0 + f)),
        },
        Limit {
            path: &["toolpaths", "gcode_options", "rapid_rate_mm_min"],
            key: "toolpaths.gcode_options.rapid_rate_mm_min",
            at: || vec![num(0.1), num(1e6)],
            beyond: |f, k| if k % 2 == 0 { num(0.1 / (1.0 + f)) } else { num(1e6 * (1.0 + f)) },
        },
        Limit {
            path: &["toolpaths", "placement", "width"],
            key: "toolpaths.placement.width",
            at: || vec![num(1e6), num(0.5)],
            beyond: |f, k| above(1e6, f, k),
        },
        Limit {
            path: &["toolpaths", "placement", "trace", "max_steps"],
            key: "toolpaths.placement.trace.max_steps",
            at: || vec![json!(1), json!(2_000_000)],
            beyond: |_, _| json!(0),
        },
        Limit {
            path: &["view", "target"],
            key: "view.target",
            at: || vec![json!([1e75, 0.0, 0.0]), json!([0.0, 0.0, 0.0])],
            beyond: |f, k| json!([if k % 2 == 0 { 1e75 } else { -1e75 } * (1.0 + f), 0.0, 0.0]),
        },
    ];
    for (path, key) in PLAN {
        l.push(Limit {
            path,
            key,
            at: || vec![num(1e6), num(0.0)],
            beyond: |f, k| above(1e6, f, k),
        });
    }
    l
}

fn lights(n: usize) -> Value {
    let mut v = vec![json!({"type": "directional", "direction": [0.3, -0.5, 1], "key": true})];
    for i in 1..n {
        v.push(json!({"type": "directional", "direction": [1, i as f64 * 0.01, 0.5]}));
    }
    Value::Array(v)
}

/// One UV polyline of `n` points.
fn polyline(n: usize) -> Value {
    let pts: Vec<Value> = (0..n).map(|i| json!([0.1 + 0.8 * i as f64 / n as f64, 0.5])).collect();
    json!([pts])
}

/// The scene every case starts from: every section the limits sit in, valid.
fn base() -> Value {
    json!({
        "mesh": {"path": "part.obj"},
        "view": {"eye": [0, -300, 100]},
        "lights": [{"type": "directional", "direction": [0.3, -0.5, 1], "key": true}],
        "edits": [
            {"tool": "bend", "centre": {"point": [0, 0, 0]}, "radius": 10, "strength": 0.5},
            {"tool": "curve", "uv": [[[0.1, 0.5], [0.9, 0.5]]], "radius": 0.05}
        ],
        "solver": {"constraints": {"turning_radius": {"radius": 50}}},
        "toolpaths": {"svg": "x.svg", "plan": {"order": {}}},
        "render": {"width": 64, "height": 48, "output": "x.png"}
    })
}

/// Sets the value at `path` (arrays indexed by their key's number).
fn set(scene: &mut Value, path: &[&str], v: Value) {
    let mut at = scene;
    for k in &path[..path.len() - 1] {
        at = match k.parse::<usize>() {
            Ok(i) => &mut at[i],
            Err(_) => &mut at[*k],
        };
    }
    let last = path[path.len() - 1];
    match last.parse::<usize>() {
        Ok(i) => at[i] = v,
        Err(_) => at[last] = v,
    }
}

/// The scene read as `grainline run` reads it: the file's checks, then its outputs' paths
/// (their length is checked when the outputs are planned).
fn read(scene: &Value) -> Result<Scene, String> {
    let path = Path::new("limits.json");
    let scene = Scene::from_str(&scene.to_string(), path).map_err(|e| e.to_string())?;
    let loaded = LoadedScene { path: path.into(), scene, base: ".".into() };
    let outputs = [
        ("render.output", loaded.scene.render.as_ref().map(|r| r.output.clone())),
        ("toolpaths.svg", loaded.scene.toolpaths.as_ref().and_then(|t| t.svg.clone())),
    ];
    for (key, p) in outputs {
        if let Some(p) = p {
            let r = output_path(&loaded, None, key, &p);
            r.map_err(|e| loaded.wrap(e).to_string())?;
        }
    }
    Ok(loaded.scene)
}

#[test]
fn every_limit_is_read_at_its_value() {
    for l in limits() {
        for v in (l.at)() {
            let mut s = base();
            set(&mut s, l.path, v.clone());
            if let Err(e) = read(&s) {
                let shown: String = v.to_string().chars().take(60).collect();
                panic!("{} = {shown}: refused at its limit: {e}", l.key);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// One key beyond its limit, up to three others at theirs: refused, naming that key.
    #[test]
    fn a_value_beyond_its_limit_is_refused_naming_its_key(
        which in 0usize..23,
        exponent in -9.0f64..200.0,
        k in 0usize..6,
        others in proptest::collection::vec((0usize..23, 0usize..3), 0..3),
    ) {
        let all = limits();
        let l = &all[which % all.len()];
        let mut s = base();
        for (o, j) in others {
            let other = &all[o % all.len()];
            // Keys sharing a prefix with the one beyond would overwrite it, or be overwritten;
            // a light's direction is beyond its limit (straight away from the eye) only for
            // the base scene's view.
            if other.path[0] == l.path[0] || (l.path[0] == "lights" && other.path[0] == "view") {
                continue;
            }
            let at = (other.at)();
            set(&mut s, other.path, at[j % at.len()].clone());
        }
        let v = (l.beyond)(10f64.powf(exponent), k);
        set(&mut s, l.path, v.clone());
        let shown: String = v.to_string().chars().take(60).collect();
        match read(&s) {
            Ok(_) => prop_assert!(false, "{} = {shown} was read", l.key),
            Err(e) => {
                prop_assert!(e.contains(l.key), "{} = {shown}: {e}", l.key);
                prop_assert!(e.len() < 600, "{} = {shown}: a long message: {e}", l.key);
            }
        }
    }
}
