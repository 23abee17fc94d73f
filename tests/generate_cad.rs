//! The generated CAD parts (`generate::cad`) against their analytic truth: each part's STL
//! loads through grainline's own loader as a closed, edge-manifold, consistently oriented
//! mesh of the expected genus; its volume and per-face areas match the analytic ones within
//! what the chords allow (planes bounded by straight edges exactly); every vertex lies on the
//! surfaces of all its faces; planar faces have no interior vertex and hold slivers; fillets
//! and bends meet their neighbours tangentially, every other edge is sharp.

use std::collections::{BTreeMap, BTreeSet};

use grainline::generate::cad::{self, AnalyticFace, CadPart};
use grainline::mesh::load::{load_mesh, LoadOptions};
use grainline::mesh::topology::Topology;

/// The four parts with their defaults and the genus each must have (one per through-hole).
fn parts() -> Vec<(CadPart, u32)> {
    vec![
        (cad::housing(&Default::default()).unwrap(), 2),
        (cad::plate(&Default::default()).unwrap(), 5),
        (cad::bracket(&Default::default()).unwrap(), 2),
        (cad::turned(&Default::default()).unwrap(), 0),
        (cad::knob(&Default::default()).unwrap(), 0),
    ]
}

/// Length scale of a part: its bounding box's diagonal.
fn scale(part: &CadPart) -> f64 {
    let (lo, hi) = part.mesh().bounding_box().unwrap();
    (hi - lo).norm()
}

#[test]
fn parts_weld_to_closed_oriented_manifolds_through_their_stl() {
    let dir = tempfile::tempdir().unwrap();
    for (part, genus) in parts() {
        let path = dir.path().join(format!("{}.stl", part.name));
        std::fs::write(&path, part.stl_binary()).unwrap();
        // The default options refuse non-manifold and inconsistently oriented meshes.
        let opts = LoadOptions { units: part.units, ..Default::default() };
        let loaded = load_mesh(&path, &opts).unwrap();
        let (m, r) = (&loaded.mesh, &loaded.report);
        let welded = part.mesh();
        assert_eq!(r.dropped_degenerate_faces, 0, "{}", part.name);
        assert_eq!(m.num_faces(), part.triangles.len(), "{}", part.name);
        assert_eq!(
            m.num_vertices(),
            welded.num_vertices(),
            "{}: float32 merged vertices",
            part.name
        );
        assert_eq!(m.units, part.units);
        for mesh in [m, &welded] {
            let t = Topology::new(mesh).unwrap();
            assert_eq!(t.num_boundary_loops(), 0, "{}: open", part.name);
            assert!(t.nonmanifold_vertices().is_empty(), "{}", part.name);
            assert_eq!(t.components().len(), 1, "{}", part.name);
            assert_eq!(t.genus(), Some(genus), "{}", part.name);
            assert_eq!(t.euler_characteristic(), 2 - 2 * genus as i64, "{}", part.name);
        }
        // Outward: the enclosed volume is positive.
        assert!(part.enclosed_volume() > 0.0, "{}", part.name);
    }
}

#[test]
fn enclosed_volumes_match_the_analytic_volumes_within_the_chords() {
    for (part, _) in parts() {
        let (v, exact, tol) = (part.enclosed_volume(), part.volume, part.volume_tolerance());
        eprintln!("{}: volume {v:.6} analytic {exact:.6} (tolerance {tol:.6})", part.name);
        assert!(tol > 0.0 && tol < 0.05 * exact, "{}: tolerance {tol}", part.name);
        assert!((v - exact).abs() <= tol, "{}: {v} vs {exact} ± {tol}", part.name);
    }
}

#[test]
fn every_vertex_lies_on_the_surfaces_of_its_faces() {
    for (part, _) in parts() {
        let eps = 1e-6 * scale(&part);
        // Every face a vertex's triangles lie on, per exact position.
        let mut around: BTreeMap<[u64; 3], BTreeSet<u32>> = BTreeMap::new();
        for (t, &f) in part.triangles.iter().zip(&part.face_of) {
            for p in t {
                around.entry([p.x, p.y, p.z].map(|c| (c + 0.0).to_bits())).or_default().insert(f);
            }
        }
        for (key, faces) in &around {
            let p = nalgebra::Vector3::from(key.map(f64::from_bits));
            for &f in faces {
                let d = part.faces[f as usize].distance(&p);
                assert!(d <= eps, "{}: vertex {p:?} is {d} off face {f}", part.name);
            }
        }
    }
}

#[test]
fn planar_faces_have_no_interior_vertex_and_hold_slivers() {
    for (part, _) in parts() {
        let mesh = part.mesh();
        // Faces around each welded vertex.
        let mut faces_at = vec![BTreeSet::new(); mesh.num_vertices()];
        for (t, &f) in mesh.faces.iter().zip(&part.face_of) {
            for &v in t {
                faces_at[v as usize].insert(f);
            }
        }
        for (t, &f) in mesh.faces.iter().zip(&part.face_of) {
            if let AnalyticFace::Plane { normal, .. } = part.faces[f as usize] {
                // Counter-clockwise around the face's outward normal, never degenerate.
                let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
                assert!((b - a).cross(&(c - a)).dot(&normal) > 0.0, "{}: flipped", part.name);
                for &v in t {
                    // A vertex of a flat face lies on its rim: another face touches it too.
                    assert!(faces_at[v as usize].len() > 1, "{}: interior vertex {v}", part.name);
                }
            }
        }
        let slivers = part.planar_slivers(5.0);
        let smallest = (0..part.triangles.len())
            .filter(|&t| part.faces[part.face_of[t] as usize].is_planar())
            .map(|t| part.smallest_angle_deg(t))
            .fold(f64::INFINITY, f64::min);
        eprintln!("{}: {slivers} planar slivers, smallest angle {smallest:.3}°", part.name);
        assert!(slivers > 0 && smallest < 5.0, "{}: no sliver", part.name);
    }
}

#[test]
fn triangle_areas_per_face_match_the_analytic_areas() {
    for (part, _) in parts() {
        let areas = part.face_areas();
        for (f, face) in part.faces.iter().enumerate() {
            let (got, want, tol) = (areas[f], face.area(), part.tolerances[f].area);
            assert!(got > 0.0, "{}: face {f} has no triangle", part.name);
            let err = (got - want).abs();
            assert!(
                err <= tol + 1e-9 * want,
                "{}: face {f} {face:?}: {got} vs {want} ± {tol}",
                part.name
            );
        }
        // Planes bounded by straight edges only are covered exactly (the turned part's planes
        // are all bounded by circles).
        let exact = part.tolerances.iter().filter(|t| t.area == 0.0).count();
        assert!(
            exact > 0 || part.name == "turned" || part.name == "knob",
            "{}: no face bounded by straight edges",
            part.name
        );
    }
}

/// For each pair of faces meeting at a vertex, `|n_f · n_g|` there (1: tangent, 0: 90°).
fn contacts(part: &CadPart) -> Vec<(u32, u32, f64)> {
    let mesh = part.mesh();
    let mut faces_at = vec![BTreeSet::new(); mesh.num_vertices()];
    for (t, &f) in mesh.faces.iter().zip(&part.face_of) {
        for &v in t {
            faces_at[v as usize].insert(f);
        }
    }
    let mut out = Vec::new();
    for (v, faces) in faces_at.iter().enumerate() {
        let p = mesh.positions[v];
        let faces: Vec<u32> = faces.iter().copied().collect();
        for (i, &f) in faces.iter().enumerate() {
            for &g in &faces[i + 1..] {
                let (nf, ng) =
                    (part.faces[f as usize].normal_at(&p), part.faces[g as usize].normal_at(&p));
                out.push((f, g, nf.dot(&ng).abs()));
            }
        }
    }
    out
}

#[test]
fn fillets_and_bends_are_tangent_and_the_other_edges_sharp() {
    for (part, _) in parts() {
        let c = contacts(&part);
        let curved = |f: u32| !part.faces[f as usize].is_planar();
        for &(f, g, dot) in &c {
            let tangent = dot > 1.0 - 1e-9;
            let chamfer =
                [f, g].iter().any(|&k| matches!(part.faces[k as usize], AnalyticFace::Cone { .. }));
            if chamfer && part.name == "knob" {
                // The shallow chamfer meets the skirt at 26.57° and the shoulder at 63.43°.
                let ok =
                    [2.0 / 5f64.sqrt(), 1.0 / 5f64.sqrt()].iter().any(|c| (dot - c).abs() < 1e-9);
                assert!(ok, "{}: chamfer at {dot}", part.name);
            } else if chamfer {
                // The 45° chamfer meets the shank and the top at 45°.
                assert!((dot - 0.5f64.sqrt()).abs() < 1e-9, "{}: chamfer at {dot}", part.name);
            } else {
                assert!(
                    tangent || dot < 1e-9,
                    "{}: faces {f}, {g} meet at |cos| = {dot}",
                    part.name
                );
            }
        }
        let tangent_pairs =
            c.iter().filter(|&&(f, g, d)| d > 1.0 - 1e-9 && (curved(f) || curved(g))).count();
        eprintln!("{}: {tangent_pairs} tangent plane–curve contacts", part.name);
        let expected = match part.name.as_str() {
            // 4 outer and 4 pocket fillets, 2 walls each, 2 rims each.
            "housing" => 32,
            "plate" => 0,
            // Bend inner and outer to both flanges at y = 0 and W; slot ends to the slot sides.
            "bracket" => 8 + 8,
            // The fillet's two rings, to the shoulder and to the shank.
            "turned" => 2 * 30,
            // The round's two rings, to the boss and to the crown.
            "knob" => 2 * 30,
            _ => unreachable!(),
        };
        assert_eq!(tangent_pairs, expected, "{}", part.name);
    }
}

#[test]
fn bad_options_are_refused() {
    let h = cad::HousingOptions { corner_radius: 45.0, ..Default::default() };
    assert!(cad::housing(&h).is_err());
    let p = cad::PlateOptions { holes: vec![[0.1, 1.0, 0.5]], ..Default::default() };
    assert!(cad::plate(&p).is_err());
    let b = cad::BracketOptions { thickness: f64::NAN, ..Default::default() };
    assert!(cad::bracket(&b).is_err());
    let t = cad::TurnedOptions { step_deg: 0.0, ..Default::default() };
    assert!(cad::turned(&t).is_err());
    let k = cad::KnobOptions { boss_radius: 19.5, ..Default::default() };
    assert!(cad::knob(&k).is_err());
}

#[test]
fn the_stl_is_binary_float32_with_unit_facet_normals_and_deterministic() {
    for (part, _) in parts() {
        let stl = part.stl_binary();
        assert_eq!(stl, part.stl_binary());
        let n = u32::from_le_bytes(stl[80..84].try_into().unwrap()) as usize;
        assert_eq!(n, part.triangles.len());
        assert_eq!(stl.len(), 84 + 50 * n);
        assert!(!stl.starts_with(b"solid"));
        for t in 0..n {
            let f =
                |k: usize| f32::from_le_bytes(stl[84 + 50 * t + 4 * k..][..4].try_into().unwrap());
            let len = (f(0) * f(0) + f(1) * f(1) + f(2) * f(2)).sqrt();
            assert!((len - 1.0).abs() < 1e-5, "{}: triangle {t}", part.name);
        }
    }
}
