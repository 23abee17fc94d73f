//! The CAD corpus (`../shared/meshes/cad`: STL as CAD systems export them, in inches, metres
//! and millimetres) with `field.init: "world"` and no edit: on every planar face of at least
//! 5 % of a part's area, ≥ 99 % of the strokes' length runs within 1° of the world direction
//! projected onto the face, and ≥ 99 % of the face's area in the glb carries the plane's
//! normal (1°) and that direction as tangent (0.5°) at all three corners. The faces and
//! their grain are found from the STL alone (tests/support/cad_truth.rs), not by grainline.

#[path = "support/cad_truth.rs"]
mod cad_truth;
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use cad_truth::{diagonal, glb_flatness, large_planar_faces, read_stl, stroke_straightness, P};

/// A world direction aligned with no face of the corpus.
const WORLD: P = [0.2, 1.0, 0.3];

/// (file, units, the file has non-manifold edges)
const PARTS: [(&str, &str, bool); 5] = [
    ("box.STL", "in", false),
    ("angle_block.STL", "in", true),
    ("round.stl", "mm", false),
    ("octagonal_pocket.stl", "m", true),
    ("busted.STL", "mm", false),
];

/// Runs `stl` with a world grain, strokes and a glb; returns the output directory.
fn run(stl: &Path, units: &str, nonmanifold: bool, tag: &str) -> PathBuf {
    let tris = read_stl(stl);
    let d = diagonal(&tris);
    let dir =
        std::env::temp_dir().join(format!("grainline-cadcorpus-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = serde_json::json!({
        "mesh": {"path": stl, "allow_nonmanifold": nonmanifold},
        "units": units,
        "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
        "view": {"eye": [d, -2.0 * d, 1.5 * d], "target": [0, 0, 0]},
        "field": {"init": "world", "world": WORLD},
        "toolpaths": {"strokes_json": "strokes.json", "placement": {"width": d / 50.0}},
        "export": {"glb": "part.glb"}
    });
    std::fs::write(dir.join("scene.json"), serde_json::to_string(&scene).unwrap()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(dir.join("scene.json"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{tag}: {}", String::from_utf8_lossy(&out.stderr));
    dir
}

#[test]
fn every_large_flat_face_of_the_cad_corpus_is_brushed_straight_and_exported_flat() {
    let Some(first) = common::shared_mesh("cad/box.STL") else { return };
    let shared = first.parent().unwrap().to_path_buf();
    let parts = PARTS.iter().map(|&(f, u, m)| (shared.join(f), u.to_string(), m));
    check_parts(parts.collect());
}

/// The generated CAD parts (`grainline::generate::cad`: a housing with tangent fillets and a
/// pocket, a plate with five holes in inches, a bent sheet-metal bracket, a turned part), as
/// binary STL: parts the shared corpus does not hold, measured the same way.
#[test]
fn every_large_flat_face_of_the_generated_cad_parts_is_brushed_straight_and_exported_flat() {
    use grainline::generate::cad;
    let dir = std::env::temp_dir().join(format!("grainline-cadcorpus-gen-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let parts = [
        cad::housing(&Default::default()).unwrap(),
        cad::plate(&Default::default()).unwrap(),
        cad::bracket(&Default::default()).unwrap(),
        cad::turned(&Default::default()).unwrap(),
    ];
    let files = parts
        .iter()
        .map(|p| {
            let stl = dir.join(format!("{}.stl", p.name));
            std::fs::write(&stl, p.stl_binary()).unwrap();
            (stl, p.units.as_str().to_string(), false)
        })
        .collect();
    check_parts(files);
    std::fs::remove_dir_all(&dir).ok();
}

fn check_parts(parts: Vec<(PathBuf, String, bool)>) {
    let mut failures = Vec::new();
    for (stl, units, nonmanifold) in parts {
        let (file, units) =
            (stl.file_name().unwrap().to_string_lossy().to_string(), units.as_str());
        let tris = read_stl(&stl);
        let faces = large_planar_faces(&tris, 0.05);
        let total: f64 = tris
            .iter()
            .map(|t| {
                0.5 * cad_truth::norm(cad_truth::cross(
                    cad_truth::sub(t[1], t[0]),
                    cad_truth::sub(t[2], t[0]),
                ))
            })
            .sum();
        let tol = 1e-4 * diagonal(&tris);
        let dir = run(&stl, units, nonmanifold, &file);
        let straight = stroke_straightness(&dir.join("strokes.json"), &faces, WORLD, tol);
        let flat = glb_flatness(&dir.join("part.glb"), &faces, WORLD, tol);
        for (k, f) in faces.iter().enumerate() {
            let (s, g) = (straight[k].1 / straight[k].0, flat[k].1 / flat[k].0);
            let share = f.area / total;
            eprintln!(
                "{file} face {k} (n {:.3?}, {:.1} % of the area): strokes {:.1} % of {:.3} \
                 within 1°, glb {:.1} % flat",
                f.normal,
                100.0 * share,
                100.0 * s,
                straight[k].0,
                100.0 * g
            );
            if !(s >= 0.99 && g >= 0.99) {
                failures.push(format!(
                    "{file} face {k}: strokes {:.1} %, glb {:.1} %",
                    100.0 * s,
                    100.0 * g
                ));
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
