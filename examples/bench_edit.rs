//! Benchmark of the editing tools (src/edit) on a generated height field.
//!
//! ```text
//! cargo run --release --example bench_edit [-- N]
//! ```
//!
//! An N×N-cell quadric patch (default N = 400: 161k vertices) with UVs, a world-direction field
//! and a distant light. Times `apply_edits` for each tool alone (a brush of radius 0.2 on a
//! 2 × 2 patch: about 3 % of the vertices) and for all of them in one list: min / median / max of
//! 7 in-process runs.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::time::Instant;

use grainline::edit::{
    apply_edits, Centre, CurveEdit, Edit, EditInput, EditOptions, LightEdit, Metric, MoveLightEdit,
    StencilEdit, WarpEdit,
};
use grainline::generate::{quadric_patch, Grid};
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::{half_vectors, Lighting, Symmetry, View};
use nalgebra::Vector3;

fn main() {
    let n: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(400);
    let mesh = quadric_patch([0.6, 0.2, -0.4], 1.0, Grid::new(n, n));
    let geom = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi: Vec<f64> = mesh
        .positions
        .iter()
        .zip(&geom.frames)
        .map(|(p, f)| f.angle_of(&Vector3::new(1.0, 0.3 * p.y, 0.1)))
        .collect();
    let lighting =
        Lighting::new(Vector3::new(0.3, 0.4, 1.0), View::Direction(Vector3::new(-0.2, 0.1, 1.0)))
            .unwrap();
    let normals: Vec<_> = geom.frames.iter().map(|f| f.n).collect();
    let h = half_vectors(&lighting, &mesh.positions, &normals);
    let input = EditInput {
        mesh: &mesh,
        geometry: &geom,
        phi: &phi,
        lighting: &lighting,
        h: &h,
        symmetry: Symmetry::Oriented,
        gradient_form: GradientForm::Angle,
    };
    let warp = WarpEdit {
        centre: Centre::Point([0.1, -0.2, 0.5]),
        radius: 0.2,
        metric: Metric::Geodesic,
        strength: 1.0,
        direction: None,
        weight: 1.0,
    };
    let edits = [
        ("bend", Edit::Bend(warp.clone())),
        ("expand", Edit::Expand(WarpEdit { centre: Centre::Point([-0.4, 0.3, 0.5]), ..warp })),
        (
            "stencil",
            Edit::Stencil(StencilEdit {
                centre: Centre::Point([0.5, 0.5, 0.5]),
                radius: 0.2,
                metric: Metric::Geodesic,
                blend: 0.5,
                weight: 1.0,
            }),
        ),
        (
            "light",
            Edit::Light(LightEdit {
                centre: Centre::Point([0.0, 0.0, 0.5]),
                ell: Some([1.0, 1.0, 0.0]),
                min_elevation_deg: 22.5,
            }),
        ),
        ("move_light", Edit::MoveLight(MoveLightEdit { light: [0.2, 0.5, 1.0] })),
        (
            "curve",
            Edit::Curve(CurveEdit {
                svg: None,
                uv: Some(vec![vec![[0.1, 0.2], [0.5, 0.4], [0.9, 0.3]]]),
                points: None,
                radius: 0.05,
                weight: 1.0,
                tolerance: 1e-3,
                width: None,
            }),
        ),
    ];
    println!("{} vertices, {} faces", mesh.num_vertices(), mesh.num_faces());
    let mut all: Vec<Edit> = edits.iter().map(|e| e.1.clone()).collect();
    all.retain(|e| !matches!(e, Edit::MoveLight(_)));
    let mut cases: Vec<(&str, Vec<Edit>)> =
        edits.iter().map(|(name, e)| (*name, vec![e.clone()])).collect();
    cases.push(("all but move_light", all));
    for (name, list) in cases {
        let mut times = Vec::new();
        let mut targeted = 0;
        for _ in 0..7 {
            let t = Instant::now();
            let r = apply_edits(&input, &list, &EditOptions::default()).expect("edits");
            times.push(t.elapsed().as_secs_f64() * 1e3);
            targeted = r.reports.iter().map(|r| r.vertices).sum();
        }
        times.sort_by(|a, b| a.total_cmp(b));
        println!(
            "{name:>20}: {targeted:>7} vertices targeted, {:.1} / {:.1} / {:.1} ms",
            times[0], times[3], times[6]
        );
    }
}
