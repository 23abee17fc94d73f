//! The corpus recipe on a generated scan the corpus has never seen (`generate::scan`): the
//! placement finds a stretch of the key highlight on a noisy part (its creases judged on the
//! normals the run fits, not on the marching mesher's slivers) and the bend lands.

mod corpus;

use grainline::generate::scan::{self, ScanOptions};

/// A generated part written as `NAME.obj` in a temporary directory (kept alive by the caller),
/// made a corpus case and prepared: its initial field and the placement of its edits.
fn prepared(
    mesh: &grainline::mesh::Mesh,
    name: &str,
) -> (tempfile::TempDir, corpus::Case, corpus::PreparedCase) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{name}.obj"));
    std::fs::write(&path, grainline::mesh::write::obj_string(mesh, name)).unwrap();
    let case = corpus::mesh_case(name, &path, true, None, false).unwrap();
    let p = corpus::prepare_case(&case).unwrap();
    (dir, case, p)
}

#[test]
fn a_bend_lands_on_a_noisy_scan_placed_without_hand_tuning() {
    // A small bust: half size, 1 mm grid (noise 0.08 mm at about 0.7 mm spacing).
    let mesh =
        scan::bust_scan(&ScanOptions { cell: 1.0, scale: 0.5, ..Default::default() }).unwrap();
    let (_dir, case, p) = prepared(&mesh, "bust_small");
    let noise = p.prepared.noise.expect("the run estimates the noise");
    assert!(noise.fit_radius.is_some(), "the scan is not found noisy: {noise:?}");
    let pl = p.placement.as_ref().expect("a placement on the scan");
    assert!(pl.stretch > 2.0 * corpus::WARP_RADIUS * pl.diag, "stretch {}", pl.stretch);
    let o = corpus::run_edit(&case, &p, "bend", "position").unwrap().unwrap();
    let f = o.figures.as_ref().expect("figures");
    assert!(f.landed, "{f:?}");
}

/// The part refined for an edit, as `grainline run` prepares it.
fn refined_for(p: &corpus::PreparedCase, tool: &str) -> grainline::pipeline::Prepared {
    let pl = p.placement.as_ref().expect("a placement");
    let (_, edit) = corpus::edits(pl).into_iter().find(|(n, _)| *n == tool).unwrap();
    let mut scene = p.scene.clone();
    scene.scene.edits = vec![edit];
    let mut stages = grainline::pipeline::Stages::new(&grainline::pipeline::Silent);
    grainline::pipeline::prepare(&scene, &mut stages).unwrap()
}

/// Faces of `mesh` with a corner from `first_new` on standing against their corners' normals
/// (a fold: the face's normal more than 90° from the mean of its corners'), and faces whose
/// corners' normals oppose.
fn folds(
    mesh: &grainline::mesh::Mesh,
    g: &grainline::geometry::Geometry,
    first_new: usize,
) -> (usize, usize) {
    let (mut against, mut opposed) = (0, 0);
    for t in &mesh.faces {
        let new = t.iter().any(|&v| v as usize >= first_new);
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let n = t.map(|v| g.normal(v as usize));
        let face = (b - a).cross(&(c - a));
        against += usize::from(new && face.dot(&(n[0] + n[1] + n[2])) < 0.0);
        opposed +=
            usize::from(n[0].dot(&n[1]) < 0.0 || n[1].dot(&n[2]) < 0.0 || n[0].dot(&n[2]) < 0.0);
    }
    (against, opposed)
}

#[test]
fn refining_a_scan_for_a_curve_folds_no_face_and_adds_no_singular_triangle() {
    // A small rock: half size, 1 mm grid (noise 0.06 mm). Its slivers' facets tilt every way;
    // Phong points placed with them folded the split faces over, and the new vertices'
    // normals flipped with them (the refinement must use the normals the run fits).
    let mesh =
        scan::rock_scan(&ScanOptions { cell: 1.0, scale: 0.5, ..Default::default() }).unwrap();
    let (_dir, case, p) = prepared(&mesh, "rock_small");
    let refined = refined_for(&p, "curve");
    assert!(refined.refinement.as_ref().is_some_and(|r| r.vertices_added > 1000));
    let first_new = p.prepared.mesh.num_vertices();
    let (against, opposed) = folds(&refined.mesh, &refined.field.geometry, first_new);
    assert_eq!((against, opposed), (0, 0), "folded faces, faces with opposed normals");
    let o = corpus::run_edit(&case, &p, "curve", "position").unwrap().unwrap();
    let f = o.figures.as_ref().expect("figures");
    assert!(f.singular_after <= f.singular_before, "{f:?}");
}

#[test]
fn every_edit_lands_on_a_sculpted_part_meshed_with_slivers() {
    // The creature at 60 %, its skin folds kept (0.3 mm high, 4 mm long): a mesher's slivers
    // everywhere, no noise. Their 1-ring fits tilted normals over (now the ring grows), and
    // their facets read as creases.
    let o = scan::SculptOptions { scale: 0.6, ..Default::default() };
    let mesh = scan::sculpt_creature(&o).unwrap();
    let (_dir, case, p) = prepared(&mesh, "creature_small");
    let (_, opposed) = folds(&p.prepared.mesh, &p.prepared.field.geometry, usize::MAX);
    assert_eq!(opposed, 0, "faces whose corners' normals oppose");
    for tool in corpus::TOOLS {
        let o = corpus::run_edit(&case, &p, tool, "position").unwrap().unwrap();
        let f = o.figures.as_ref().unwrap_or_else(|| panic!("{tool}: {:?}", o.error));
        assert!(f.landed, "{tool}: {f:?}");
    }
}

#[test]
fn refining_where_the_half_vector_turns_keeps_a_sculpt_s_bend_and_expand_regular() {
    // The full-size creature: its skin folds turn the key light's half vector by tens of
    // degrees along one edge, and a grain designed from it (φ* = θ(h̄) + ψ*) by a right angle:
    // singular triangles the target does not ask for, unless the refinement splits those faces
    // (`mesh.refine.turn`, default 20°). At 180° (nothing asked) the bend adds some. The
    // refinement alone: untangling (`solver.untangle`, docs/math.md §10) would turn those away
    // too.
    let mesh = scan::sculpt_creature(&scan::SculptOptions::default()).unwrap();
    let (_dir, case, mut p) = prepared(&mesh, "creature");
    let mut added = Vec::new();
    for turn in [180.0, grainline::edit::resolution::DEFAULT_MAX_TURN_DEG] {
        p.scene.scene.mesh.as_mut().expect("a mesh section").0.refine.turn = turn;
        for tool in ["bend", "expand"] {
            let o = corpus::run_edit_with(&case, &p, tool, "position", &|s| s.untangle = false)
                .unwrap()
                .unwrap();
            let f = o.figures.as_ref().unwrap_or_else(|| panic!("{tool}: {:?}", o.error));
            added.push((turn, tool, f.singular_after as i64 - f.singular_before as i64));
            if turn < 180.0 {
                assert!(f.landed, "{tool}: {f:?}");
            }
        }
    }
    assert!(added[..2].iter().any(|a| a.2 > 0), "turn 180 adds none: {added:?}");
    assert!(added[2..].iter().all(|a| a.2 <= 0), "{added:?}");
}

#[test]
fn a_rough_scan_stays_one_patch_and_a_bend_lands_on_it() {
    // The small bust with 0.2 mm of noise at about 0.7 mm spacing: facet dihedrals of about
    // 35° RMS, which a 40° crease angle cut into hundreds of patches (no stretch of the key
    // highlight left to place an edit on). The noise is estimated first, and a dihedral the
    // noise can make is no crease.
    let o = ScanOptions { cell: 1.0, scale: 0.5, noise: 0.2, seed: 2 };
    let mesh = scan::bust_scan(&o).unwrap();
    let (_dir, case, p) = prepared(&mesh, "bust_rough");
    let noise = p.prepared.noise.expect("the run estimates the noise");
    // The case scales the part to the corpus's size (`mesh.scale`).
    assert!((noise.sigma / case.scale - 0.2).abs() < 0.02, "{noise:?}, scale {}", case.scale);
    let cut = p.prepared.patches.as_ref().map(|r| (r.patches, r.sharp_edges));
    assert!(cut.is_none(), "cut into (patches, sharp edges) {cut:?}");
    let o = corpus::run_edit(&case, &p, "bend", "position").unwrap().unwrap();
    let f = o.figures.as_ref().expect("figures");
    assert!(f.landed, "{f:?}");
}

#[test]
fn untangling_lands_every_edit_on_the_deep_folds_with_no_new_singular_triangle() {
    // The creature at 80 % with folds 0.5 mm high of 3 mm wavelength (docs/benchmarks.md,
    // `sculpt_creature_deep`): dozens of critical points of the key light's half vector under
    // one brush, and the designed grain of a bend, an expand or a curve turns by more than a
    // right angle within a hundred triangles or more. Untangling (docs/math.md §10: fills, then
    // bounded turns) must leave none of them and keep the key highlight where the edit asks
    // (the fidelity measure, docs/math.md §10).
    let o =
        scan::SculptOptions { cell: 0.9, wrinkle_height: 0.5, wrinkle_wavelength: 3.0, scale: 0.8 };
    let mesh = scan::sculpt_creature(&o).unwrap();
    let (_dir, case, p) = prepared(&mesh, "creature_deep");
    for tool in ["bend", "expand", "curve"] {
        let run = |untangle: bool| {
            let o = corpus::run_edit_with(&case, &p, tool, "position", &|s| s.untangle = untangle)
                .unwrap()
                .unwrap();
            o.figures.unwrap_or_else(|| panic!("{tool}: {:?}", o.error))
        };
        let (designed, untangled) = (run(false), run(true));
        let added = |f: &grainline::fidelity::EditFidelity| {
            f.singular_after.saturating_sub(f.singular_before)
        };
        assert!(added(&designed) >= 100, "{tool}: the design alone: {designed:?}");
        assert_eq!(added(&untangled), 0, "{tool}: {designed:?} {untangled:?}");
        assert!(untangled.landed, "{tool}: {untangled:?}");
    }
}
