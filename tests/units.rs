//! Units (issue 31, item 4): the same part in millimetres and in inches — the mesh scaled by
//! 1/25.4 and every length the scene gives divided by 25.4, every other length left to its
//! default. Defaults of length keys are physical lengths: the inch run with `safe_z: 0.5` is
//! not refused for a clearance of "1" (inch), and both programs (printed in mm, G21) have the
//! same feeds, travel height and blending tolerance and cover the same part.

use std::path::{Path, PathBuf};
use std::process::Command;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-units-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The dome example (160 × 120 mm, UVs on a grid) with its coordinates divided by `k`.
fn write_part(d: &Path, k: f64) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("examples/data/dome.obj")).unwrap();
    let out: Vec<String> = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let v: Vec<String> = rest
                    .split_whitespace()
                    .map(|x| format!("{:e}", x.parse::<f64>().unwrap() / k))
                    .collect();
                format!("v {}", v.join(" "))
            }
            None => l.to_string(),
        })
        .collect();
    std::fs::write(d.join("dome.obj"), out.join("\n")).unwrap();
}

/// A surface-following job whose given lengths are `width` and `safe_z` mm, in `units` of
/// `k` mm; everything else (clearance, feeds, tolerances, trace steps) by default.
fn run_scene(name: &str, units: &str, k: f64) -> String {
    let d = dir(name);
    write_part(&d, k);
    let scene = format!(
        r#"{{
  "mesh": "dome.obj",
  "units": "{units}",
  "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
  "view": {{"eye": [0, {ey}, {ez}], "target": [0, 0, 0]}},
  "field": {{"init": "world", "world": [1, 0.3, 0]}},
  "toolpaths": {{
    "gcode": "o.ngc",
    "placement": {{"width": {w}}},
    "plan": {{"z_mode": {{"mode": "surface_following", "max_tilt_deg": 30, "on_tilt": "error"}}}},
    "gcode_options": {{"safe_z": {sz}}}
  }}
}}"#,
        ey = -300.0 / k,
        ez = 200.0 / k,
        w = 6.0 / k,
        sz = 12.7 / k,
    );
    let sc = d.join("scene.json");
    std::fs::write(&sc, scene).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(&sc)
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    let g = std::fs::read_to_string(d.join("o.ngc")).unwrap();
    std::fs::remove_dir_all(&d).ok();
    g
}

/// The programs' bounding box of feed moves, mm.
fn feed_box(g: &str) -> [f64; 6] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for l in g.lines().filter(|l| l.starts_with("G1 X")) {
        for (i, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            let v: f64 = l.split(' ').find(|w| w.starts_with(c)).unwrap()[1..].parse().unwrap();
            b[i] = b[i].min(v);
            b[i + 3] = b[i + 3].max(v);
        }
    }
    b
}

/// The full run of one part in millimetres and in inches gives one program (issue 31, item 4).
/// The defaults are physical (the inch run with `safe_z: 0.5` clears the part by the default
/// 1 mm, feeds 1000 and 300 mm/min, blending 0.01 mm), and both programs, printed in mm, agree
/// move for move: the same words on every line, every coordinate within 0.002 mm (two units of
/// the last printed digit: the inch part's coordinates went through a decimal `{:e}` rescale),
/// the strokes ending on the dome's edge running out past it in both.
#[test]
fn inch_and_millimetre_runs_of_one_part_give_one_program() {
    let mm = run_scene("mm", "mm", 1.0);
    let inch = run_scene("in", "in", 25.4);
    assert!(inch.contains("units: mm, G21; lengths converted from in x25.4"), "{inch}");
    for g in [&mm, &inch] {
        assert!(
            g.contains("\nG0 Z12.700\n") && g.contains(" F1000.0\n") && g.contains(" F300.0\n")
        );
        assert!(g.contains("\nG64 P0.010\n"));
    }
    let passes = |g: &str| g.lines().filter(|l| l.starts_with("(pass ")).count();
    let (a, b) = (feed_box(&mm), feed_box(&inch));
    eprintln!("passes {} mm / {} in; feed box {a:?} / {b:?}", passes(&mm), passes(&inch));
    assert_eq!(passes(&mm), passes(&inch));
    let moves = |g: &str| -> Vec<String> {
        g.lines()
            .filter(|l| !l.starts_with('(') && !l.trim().is_empty())
            .map(String::from)
            .collect()
    };
    let (lm, li) = (moves(&mm), moves(&inch));
    assert_eq!(lm.len(), li.len(), "lines");
    let mut worst: f64 = 0.0;
    for (x, y) in lm.iter().zip(&li) {
        let (wx, wy): (Vec<&str>, Vec<&str>) =
            (x.split_whitespace().collect(), y.split_whitespace().collect());
        assert_eq!(wx.len(), wy.len(), "`{x}` vs `{y}`");
        for (p, q) in wx.iter().zip(&wy) {
            assert_eq!(p[..1], q[..1], "`{x}` vs `{y}`");
            let (u, v): (f64, f64) = (p[1..].parse().unwrap(), q[1..].parse().unwrap());
            worst = worst.max((u - v).abs());
            assert!((u - v).abs() <= 0.0021, "`{x}` vs `{y}`");
        }
    }
    eprintln!("{} lines alike, numbers within {worst} mm", lm.len());
    // The dome's strokes run out past its edge: the feed moves reach beyond the part's
    // 160 × 120 mm outline (one 6 mm width along the strokes).
    assert!(a[3] > 80.5 && b[3] > 80.5, "{a:?} / {b:?}");
}
