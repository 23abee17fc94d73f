//! The corpus recipe on a generated scan the corpus has never seen (`generate::scan`): the
//! placement finds a stretch of the key highlight on a noisy part (its creases judged on the
//! normals the run fits, not on the marching mesher's slivers) and the bend lands.

mod corpus;

use grainline::generate::scan::{self, ScanOptions};

#[test]
fn a_bend_lands_on_a_noisy_scan_placed_without_hand_tuning() {
    // A small bust: half size, 1 mm grid (noise 0.08 mm at about 0.7 mm spacing).
    let mesh =
        scan::bust_scan(&ScanOptions { cell: 1.0, scale: 0.5, ..Default::default() }).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bust_small.obj");
    std::fs::write(&path, grainline::mesh::write::obj_string(&mesh, "bust")).unwrap();
    let case = corpus::mesh_case("bust_small", &path, true, None, false).unwrap();
    let p = corpus::prepare_case(&case).unwrap();
    let noise = p.prepared.noise.expect("the run estimates the noise");
    assert!(noise.fit_radius.is_some(), "the scan is not found noisy: {noise:?}");
    let pl = p.placement.as_ref().expect("a placement on the scan");
    assert!(pl.stretch > 2.0 * corpus::WARP_RADIUS * pl.diag, "stretch {}", pl.stretch);
    let o = corpus::run_edit(&case, &p, "bend", "position").unwrap().unwrap();
    let f = o.figures.as_ref().expect("figures");
    assert!(f.landed, "{f:?}");
}
