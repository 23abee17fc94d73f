//! The shared test meshes (../shared/meshes, see its MANIFEST.md for where the expected counts
//! come from). Each test prints a skip message and passes when the corpus is absent.

mod common;
use common::shared_mesh;

use grainline::mesh::load::{load_obj, LoadOptions, LoadedMesh};
use grainline::mesh::report::{InspectReport, QualityReport};
use grainline::mesh::topology::Topology;
use grainline::mesh::uv_charts::UvCharts;

fn inspect(name: &str, options: LoadOptions) -> Option<(LoadedMesh, InspectReport)> {
    let path = shared_mesh(name)?;
    let loaded = load_obj(&path, &options).unwrap();
    let topo = Topology::new(&loaded.mesh).unwrap();
    let charts = loaded.mesh.uv.as_ref().map(|uv| UvCharts::new(topo.halfedges(), uv));
    let report =
        InspectReport::new(&path, &loaded, &topo, charts.as_ref(), QualityReport::new(&loaded));
    Some((loaded, report))
}

#[test]
fn spot_charts_seams_and_mirrored_chart() {
    let Some((m, r)) = inspect("spot_triangulated.obj", LoadOptions::default()) else { return };
    assert_eq!((m.mesh.num_vertices(), m.mesh.num_faces()), (2930, 5856));
    assert_eq!((r.genus, r.boundary_loops.len()), (Some(0), 0));
    let uv = r.uv.unwrap();
    assert_eq!((uv.charts, uv.seam_edges), (13, 288));
    assert_eq!(uv.mirrored_charts.len(), 1);
    assert_eq!(uv.mirrored_charts[0].faces, 176);
    assert_eq!(uv.flipped_faces, 176 + 1);
    assert_eq!(uv.faces_against_chart, 1);
}

#[test]
fn blub_quads_are_triangulated() {
    let Some((m, r)) = inspect("blub_quadrangulated.obj", LoadOptions::default()) else { return };
    assert_eq!((m.mesh.num_vertices(), m.mesh.num_faces()), (7106, 2 * 7104));
    assert_eq!(r.polygons_split, 7104);
    let uv = r.uv.unwrap();
    assert_eq!((uv.charts, uv.seam_edges), (5, 208));
    assert_eq!((r.genus, r.boundary_loops.len()), (Some(0), 0));
}

#[test]
fn bunny_holes_and_unreferenced_vertices() {
    let Some((m, r)) = inspect("stanford-bunny.obj", LoadOptions::default()) else { return };
    assert_eq!(m.report.file_vertices, 35947);
    assert_eq!(m.report.unreferenced_vertices, 1113);
    assert_eq!(m.mesh.num_faces(), 69451);
    assert_eq!(r.boundary_loops.len(), 5);
    assert_eq!(r.genus, Some(0));
}

#[test]
fn teapot_loops_before_and_after_welding() {
    let tolerant = LoadOptions::default().tolerant();
    let Some((_, r)) = inspect("teapot.obj", tolerant.clone()) else { return };
    assert_eq!(r.faces, 6320);
    assert_eq!(r.boundary_components, 10);
    let welded = LoadOptions { weld: Some(1e-6), ..tolerant };
    let (m, r) = inspect("teapot.obj", welded).unwrap();
    assert_eq!(m.report.welded_vertices, 403);
    assert_eq!(r.boundary_components, 6);
    assert_eq!(r.boundary_loops.len(), 6);
}

#[test]
fn closed_meshes_and_genus() {
    for (name, genus) in [("rocker-arm.obj", 1), ("fandisk.obj", 0), ("oloid4096_tri.obj", 0)] {
        let Some((m, r)) = inspect(name, LoadOptions::default()) else { return };
        assert_eq!(r.boundary_loops.len(), 0, "{name}");
        assert_eq!(r.genus, Some(genus), "{name}");
        assert_eq!(m.report.dropped_degenerate_faces, 0, "{name}: slivers must be kept");
    }
    let Some((m, _)) = inspect("oloid4096_tri.obj", LoadOptions::default()) else { return };
    assert_eq!(m.mesh.num_faces(), 8192);
}

#[test]
fn paper_is_a_disk() {
    let Some((_, r)) = inspect("paper-crumpled2.obj", LoadOptions::default()) else { return };
    assert_eq!((r.vertices, r.faces), (289, 512));
    assert_eq!((r.boundary_loops.len(), r.euler_characteristic, r.genus), (1, 1, Some(0)));
}
