//! Locked directions: hard locks hold exactly, boundary-derived directions, conflicts, k = 2
//! periodicity, and the settings' validation.

use std::f64::consts::{FRAC_PI_2, PI};

use grainline::generate::{self, Grid};
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::Symmetry;
use grainline::mesh::topology::Topology;
use grainline::solve::locks::{angle_difference, circular_mean, resolve_locks};
use grainline::solve::{
    optimize, BoundaryRelation, Constraints, HighlightTerm, LockRegion, LockSpec, SolverSettings,
};
use nalgebra::Vector3;

fn setup(n: usize) -> (grainline::mesh::Mesh, Geometry, Vec<Vector3<f64>>, Vec<f64>) {
    let mesh = generate::quadric_patch([0.6, 0.1, -0.3], 1.0, Grid::new(n, n));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi: Vec<f64> = mesh
        .positions
        .iter()
        .zip(&g.frames)
        .map(|(p, f)| f.angle_of(&Vector3::new((0.5 * p.y).cos(), (0.5 * p.y).sin(), 0.0)))
        .collect();
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi.len()];
    (mesh, g, h, phi)
}

fn term<'a>(g: &'a Geometry, h: &'a [Vector3<f64>], phi: &[f64], s: Symmetry) -> HighlightTerm<'a> {
    HighlightTerm::own_targets(g, h, s, GradientForm::Angle, phi)
}

#[test]
fn hard_locks_hold_exactly_and_world_directions_project() {
    let (mesh, g, h, phi) = setup(16);
    let dir = [0.2, 1.0, 0.5];
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let t = term(&g, &h, &phi, sym);
        let settings = SolverSettings {
            whole_mesh: true,
            max_iterations: 20,
            constraints: Constraints {
                locks: vec![
                    LockSpec {
                        vertices: vec![3, 40, 100],
                        direction: Some(dir),
                        ..Default::default()
                    },
                    LockSpec {
                        region: Some(LockRegion { center: [0.3, 0.3, 0.0], radius: 0.25 }),
                        direction: Some([1.0, -1.0, 0.0]),
                        ..Default::default()
                    },
                ],
                ..Default::default()
            },
            ..Default::default()
        };
        let r = optimize(&mesh, &t, &phi, &vec![false; phi.len()], &settings).unwrap();
        assert!(r.report.hard_locked > 10);
        assert!(r.report.violations.max_lock_error < 1e-6, "{:?}", r.report.violations);
        assert!(r.report.conflicting_locks.is_empty());
        // Truth from outside: the world direction projected on the tangent plane.
        for &v in &[3usize, 40, 100] {
            let n = g.frames[v].n;
            let d = Vector3::from(dir);
            let want = (d - n * n.dot(&d)).normalize();
            let got = g.frames[v].direction(r.phi[v]);
            let err = if sym == Symmetry::Line {
                1.0 - got.dot(&want).abs()
            } else {
                1.0 - got.dot(&want)
            };
            assert!(err < 1e-12, "vertex {v}: {got} vs {want}");
        }
        let mut e = r.report.initial_energy.total();
        for it in &r.report.iterations {
            assert!(it.energies.total() <= e);
            e = it.energies.total();
        }
    }
}

#[test]
fn boundary_loop_parallel_and_perpendicular() {
    let mesh = generate::plane(1.0, Grid::new(10, 10));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let topo = Topology::new(&mesh).unwrap();
    assert_eq!(topo.num_boundary_loops(), 1);
    let lp: Vec<u32> = topo.boundary_loop(0).iter().map(|v| v.0).collect();
    for (rel, k) in [(BoundaryRelation::Parallel, 1), (BoundaryRelation::Perpendicular, 1)] {
        let specs =
            vec![LockSpec { boundary_loop: Some(0), boundary: Some(rel), ..Default::default() }];
        let locks = resolve_locks(&mesh, &g, &specs, k, 0.01, "locks").unwrap();
        assert_eq!(locks.hard.len(), lp.len());
        for &(v, a) in &locks.hard {
            let p = mesh.positions[v as usize];
            // Mid-edge vertices of the square: the boundary runs along x (bottom/top) or y.
            let on_bottom = (p.y + 1.0).abs() < 1e-12 && p.x.abs() < 0.95;
            if !on_bottom {
                continue;
            }
            let u = g.frames[v as usize].direction(a);
            // Faces on the left of the loop: along the bottom edge the loop runs towards +x,
            // and the inward normal is +y.
            let want = match rel {
                BoundaryRelation::Parallel => Vector3::x(),
                BoundaryRelation::Perpendicular => Vector3::y(),
            };
            assert!((u - want).norm() < 1e-9, "{rel:?} at {p}: {u}");
        }
    }
}

#[test]
fn conflicting_locks_are_reported_and_averaged() {
    // On a plane, so the projected x and y axes stay exactly perpendicular.
    let mesh = generate::plane(1.0, Grid::new(10, 10));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi: Vec<f64> = mesh.positions.iter().map(|p| 0.3 * p.x + 0.2 * p.y).collect();
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi.len()];
    // Vertex 5: x-axis vs y-axis (90° apart) and, for k = 1, opposite directions (the mean is
    // undefined: the first is kept).
    let specs = vec![
        LockSpec { vertices: vec![5, 7], direction: Some([1.0, 0.0, 0.0]), ..Default::default() },
        LockSpec { vertices: vec![5], direction: Some([0.0, 1.0, 0.0]), ..Default::default() },
        LockSpec { vertices: vec![7], direction: Some([-1.0, 0.0, 0.0]), ..Default::default() },
    ];
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let k = sym.k();
        let locks = resolve_locks(&mesh, &g, &specs, k, 0.01, "constraints.locks").unwrap();
        let c5 = locks.conflicts.iter().find(|c| c.vertex == 5).expect("vertex 5 conflicts");
        assert_eq!(c5.angles.len(), 2);
        assert!(c5.resolved.is_finite());
        // The mean of two directions 90° apart lies 45° from each (mod 2π/k).
        for a in &c5.angles {
            let d = angle_difference(c5.resolved, *a, k).abs();
            if k == 1 {
                assert!((d - PI / 4.0).abs() < 0.05, "k 1: {d}");
            } else {
                // Angle-doubled: 90° apart becomes 180° — the mean is undefined, first kept.
                assert!(d < 1e-9 || (d - FRAC_PI_2).abs() < 1e-9, "k 2: {d}");
            }
        }
        // x and −x: a conflict for k = 1 (mean undefined, first kept), the same line for k = 2.
        let c7 = locks.conflicts.iter().find(|c| c.vertex == 7);
        assert_eq!(c7.is_some(), k == 1, "k {k}");
        let t = term(&g, &h, &phi, sym);
        let settings = SolverSettings {
            whole_mesh: true,
            max_iterations: 10,
            constraints: Constraints { locks: specs.clone(), ..Default::default() },
            ..Default::default()
        };
        let r = optimize(&mesh, &t, &phi, &vec![false; phi.len()], &settings).unwrap();
        assert!(r.phi.iter().all(|p| p.is_finite()));
        assert_eq!(r.report.conflicting_locks.len(), locks.conflicts.len());
        assert!(serde_json::to_string(&r.report).unwrap().contains("conflicting_locks"));
    }
}

#[test]
fn k2_means_wrap_at_pi() {
    // 0.01 and π − 0.01 are the same line within 0.02 rad: no conflict, mean ≈ 0 (mod π), never
    // the perpendicular π/2 a raw average would give.
    let m = circular_mean(&[(0.01, 1.0), (PI - 0.01, 1.0)], 2);
    assert!(angle_difference(m, 0.0, 2).abs() < 1e-12, "{m}");
    assert!((circular_mean(&[(0.01, 1.0), (PI - 0.01, 1.0)], 1) - FRAC_PI_2).abs() < 1e-12);
    assert!(circular_mean(&[(0.0, 1.0), (PI, 1.0)], 1).is_finite());
    assert_eq!(circular_mean(&[], 2), 0.0);
}

#[test]
fn soft_locks_pull_towards_the_lock() {
    let (mesh, g, h, phi) = setup(12);
    let t = term(&g, &h, &phi, Symmetry::Oriented);
    let lock = |w| LockSpec {
        vertices: vec![50],
        direction: Some([0.0, 1.0, 0.0]),
        weight: Some(w),
        ..Default::default()
    };
    let mut errs = Vec::new();
    for w in [1.0, 1e4] {
        let settings = SolverSettings {
            whole_mesh: true,
            constraints: Constraints { locks: vec![lock(w)], ..Default::default() },
            ..Default::default()
        };
        let r = optimize(&mesh, &t, &phi, &vec![false; phi.len()], &settings).unwrap();
        assert_eq!(r.report.soft_locked, 1);
        errs.push(r.report.violations.max_lock_error);
    }
    eprintln!("soft lock error at weight 1 and 1e4: {errs:?}");
    assert!(errs[1] < errs[0] && errs[1] < 0.05, "{errs:?}");
}

#[test]
fn settings_validate_and_parse() {
    let s: SolverSettings = serde_json::from_str("{}").unwrap();
    assert_eq!(s, SolverSettings::default());
    s.validate().unwrap();
    assert!(serde_json::from_str::<SolverSettings>(r#"{"smoothnes": 1}"#).is_err());
    let s: SolverSettings = serde_json::from_str(
        r#"{"smoothness": 0, "constraints": {"turning_radius": {"radius": 2.0},
            "locks": [{"boundary_loop": 0, "boundary": "perpendicular"}]}}"#,
    )
    .unwrap();
    s.validate().unwrap();
    assert!(s.smoothing_pass());
    assert_eq!(s.constraints.turning_radius.as_ref().unwrap().weight, 10.0);
    let bad = |json: &str, key: &str| {
        let s: SolverSettings = serde_json::from_str(json).unwrap();
        let e = s.validate().unwrap_err().to_string();
        assert!(e.starts_with(key), "{e} should name {key}");
    };
    bad(r#"{"smoothness": -1}"#, "smoothness");
    bad(r#"{"max_iterations": 0}"#, "max_iterations");
    bad(r#"{"constraints": {"splay": {"max": 0}}}"#, "constraints.splay.max");
    bad(r#"{"constraints": {"locks": [{"vertices": [1]}]}}"#, "constraints.locks[0]");
    bad(
        r#"{"constraints": {"locks": [{"vertices": [1], "boundary": "parallel"}]}}"#,
        "constraints.locks[0].boundary",
    );
    bad(
        r#"{"constraints": {"locks": [{"region": {"center": [0,0,0], "radius": -1}, "direction": [1,0,0]}]}}"#,
        "constraints.locks[0].region.radius",
    );
    // Mesh-dependent errors name the key too.
    let (mesh, g, h, phi) = setup(4);
    let t = term(&g, &h, &phi, Symmetry::Oriented);
    let s: SolverSettings = serde_json::from_str(
        r#"{"constraints": {"locks": [{"vertices": [999], "direction": [1,0,0]}]}}"#,
    )
    .unwrap();
    let e = optimize(&mesh, &t, &phi, &vec![true; phi.len()], &s).unwrap_err().to_string();
    assert!(e.starts_with("constraints.locks[0].vertices[0]"), "{e}");
    let schema = schemars::schema_for!(SolverSettings);
    assert!(serde_json::to_string(&schema).unwrap().contains("turning_radius"));
}
