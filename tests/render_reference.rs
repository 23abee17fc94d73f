//! Reference previews: two small scenes rendered by `grainline run` and compared with PNGs
//! committed under tests/data/reference, within a tolerance (mean |Δ| ≤ 0.5 and at most 0.1 %
//! of the channels off by more than 16 levels, so tiny floating-point differences between
//! machines pass while a changed BRDF, camera or overlay fails). The numbers behind them are
//! checked against formulas in tests/render_scene.rs and tests/render_brdf.rs. Regenerate
//! with `GRAINLINE_BLESS=1 cargo test --test render_reference` after checking the pictures.

use std::path::{Path, PathBuf};
use std::process::Command;

use grainline::generate;
use grainline::mesh::write::obj_string;

fn render(name: &str, mesh: grainline::mesh::Mesh, body: &str) -> Vec<u8> {
    let d = std::env::temp_dir().join(format!("grainline-ref-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("part.obj"), obj_string(&mesh, name)).unwrap();
    let p: PathBuf = d.join("scene.json");
    std::fs::write(&p, format!("{{\"mesh\": \"part.obj\", {body}}}")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = std::fs::read(d.join("p.png")).unwrap();
    std::fs::remove_dir_all(&d).ok();
    png
}

fn compare(name: &str, png: &[u8]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/reference")
        .join(format!("{name}.png"));
    if std::env::var_os("GRAINLINE_BLESS").is_some() {
        std::fs::write(&path, png).unwrap();
        return;
    }
    let want = std::fs::read(&path).unwrap_or_else(|_| panic!("missing {}", path.display()));
    let a = tiny_skia::Pixmap::decode_png(png).unwrap();
    let b = tiny_skia::Pixmap::decode_png(&want).unwrap();
    assert_eq!((a.width(), a.height()), (b.width(), b.height()), "{name}: size");
    let (mut sum, mut big) = (0u64, 0usize);
    for (x, y) in a.data().iter().zip(b.data()) {
        let d = (i32::from(*x) - i32::from(*y)).unsigned_abs();
        sum += u64::from(d);
        big += usize::from(d > 16);
    }
    let n = a.data().len();
    let mean = sum as f64 / n as f64;
    assert!(
        mean <= 0.5 && big * 1000 <= n,
        "{name}: mean |Δ| {mean:.3}, {big} of {n} channels off by > 16"
    );
}

const LIGHTS: &str = r#""lights": [{"type": "directional", "direction": [0.3, -0.5, 1], "irradiance": 2},
  {"type": "directional", "direction": [-0.8, -0.3, 0.4], "irradiance": 0.6}]"#;

#[test]
fn vase_with_highlight_curves() {
    let mesh =
        generate::revolve(|t| (20.0 + 5.0 * (std::f64::consts::PI * t).sin(), 40.0 * t), 48, 20);
    let png = render(
        "vase",
        mesh,
        &format!(
            r#"{LIGHTS}, "view": {{"eye": [0, -120, 60], "target": [0, 0, 20]}},
  "field": {{"init": "uv"}},
  "render": {{"width": 128, "height": 128, "output": "p.png", "effects": {{"highlight_curves": {{}}}}}}"#
        ),
    );
    compare("vase", &png);
}

#[test]
fn torus_ward_with_critical_points() {
    let mesh = generate::torus(20.0, 8.0, 48, 24);
    let png = render(
        "torus",
        mesh,
        &format!(
            r#"{LIGHTS}, "view": {{"eye": [0, -80, 60], "target": [0, 0, 0]}},
  "material": {{"brdf": {{"kind": "ward", "alpha_x": 0.05, "alpha_y": 0.3, "rho_s": 0.8}}}},
  "field": {{"init": "curvature_max"}},
  "render": {{"width": 128, "height": 96, "output": "p.png", "effects": {{"critical_points": {{}}}}}}"#
        ),
    );
    compare("torus", &png);
}
