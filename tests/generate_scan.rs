//! The generated scans and sculpted parts (`generate::scan`): deterministic, closed,
//! edge-manifold, outward, one component of genus 0, of the sizes the module documents, with
//! irregular triangles (no lattice of parameters) and, for the UV-mapped head, UVs with a seam.

use grainline::generate::scan::{self, ScanOptions, SculptOptions};
use grainline::mesh::topology::Topology;
use grainline::mesh::Mesh;

fn volume(m: &Mesh) -> f64 {
    m.faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| m.positions[i as usize]);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

fn check_closed(name: &str, m: &Mesh) {
    let t = Topology::new(m).unwrap();
    assert_eq!(t.num_boundary_loops(), 0, "{name}: open");
    assert!(t.nonmanifold_vertices().is_empty(), "{name}: non-manifold vertices");
    assert_eq!(t.components().len(), 1, "{name}: components");
    assert_eq!(t.genus(), Some(0), "{name}: genus");
    assert!(volume(m) > 0.0, "{name}: inward");
    assert!(m.positions.iter().all(|p| p.iter().all(|c| c.is_finite())), "{name}");
}

/// Edge lengths' coefficient of variation: a marching mesh's triangles are irregular.
fn edge_spread(m: &Mesh) -> (f64, f64) {
    let e: Vec<f64> = m
        .faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k] as usize, f[(k + 1) % 3] as usize)))
        .map(|(a, b)| (m.positions[a] - m.positions[b]).norm())
        .collect();
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    let var = e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / e.len() as f64;
    (mean, var.sqrt() / mean)
}

#[test]
fn scans_are_deterministic_closed_and_noisy() {
    // Half size on a coarser grid: the test's few thousand vertices.
    let o = ScanOptions { cell: 2.5, scale: 0.5, ..Default::default() };
    for (name, make) in [
        ("bust", scan::bust_scan as fn(&ScanOptions) -> grainline::Result<Mesh>),
        ("rock", scan::rock_scan),
    ] {
        let (a, b) = (make(&o).unwrap(), make(&o).unwrap());
        assert_eq!(a.positions, b.positions, "{name}: not deterministic");
        assert_eq!(a.faces, b.faces, "{name}");
        check_closed(name, &a);
        assert!((1000..20000).contains(&a.num_vertices()), "{name}: {}", a.num_vertices());
        let (mean, cv) = edge_spread(&a);
        assert!(mean > 0.4 * o.cell && mean < 1.0 * o.cell, "{name}: mean edge {mean}");
        assert!(cv > 0.2, "{name}: edges too regular ({cv})");
        // Another seed moves the vertices, not the triangles.
        let c = make(&ScanOptions { seed: 2, ..o.clone() }).unwrap();
        assert_eq!(a.faces, c.faces, "{name}");
        assert_ne!(a.positions, c.positions, "{name}: the seed does nothing");
    }
}

#[test]
fn sculpts_are_closed_and_the_head_has_a_uv_seam() {
    let o = SculptOptions { cell: 2.5, scale: 0.6, ..Default::default() };
    let creature = scan::sculpt_creature(&o).unwrap();
    check_closed("creature", &creature);
    assert!(creature.uv.is_none());
    let head = scan::uv_character(&o).unwrap();
    check_closed("head", &head);
    assert_eq!(head.positions, scan::uv_character(&o).unwrap().positions);
    let uv = head.uv.as_ref().unwrap();
    assert_eq!(uv.corners.len(), head.num_faces());
    // A seam: some vertices carry a second UV (u + 1) on the faces across the wrap.
    assert!(uv.values.len() > head.num_vertices(), "no seam");
    assert!(uv.values.iter().all(|t| t.x >= 0.0 && t.x <= 2.0 && (0.0..=1.0).contains(&t.y)));
    for f in 0..head.num_faces() {
        let us = uv.face(f).map(|t| t.x);
        let span = us.iter().cloned().fold(f64::MIN, f64::max)
            - us.iter().cloned().fold(f64::MAX, f64::min);
        // Faces away from the poles span little of the longitude.
        let z = head.face_positions(f).map(|p| p.z / p.norm());
        if z.iter().all(|z| z.abs() < 0.9) {
            assert!(span < 0.1, "face {f} spans {span} of the longitude");
        }
    }
}

#[test]
fn default_parts_have_the_documented_sizes() {
    // One full-size part (the rest share the mesher): 40k–140k vertices at about 1 mm.
    let bust = scan::bust_scan(&ScanOptions::default()).unwrap();
    assert!((40_000..140_000).contains(&bust.num_vertices()), "{}", bust.num_vertices());
    let (mean, _) = edge_spread(&bust);
    assert!((0.7..1.4).contains(&mean), "mean edge {mean}");
    check_closed("bust", &bust);
}

#[test]
fn bad_options_are_refused() {
    assert!(scan::bust_scan(&ScanOptions { cell: 0.0, ..Default::default() }).is_err());
    assert!(scan::rock_scan(&ScanOptions { noise: -1.0, ..Default::default() }).is_err());
    assert!(
        scan::sculpt_creature(&SculptOptions { scale: f64::NAN, ..Default::default() }).is_err()
    );
    // A grid past the node limit.
    assert!(scan::uv_character(&SculptOptions { cell: 0.01, ..Default::default() }).is_err());
}
