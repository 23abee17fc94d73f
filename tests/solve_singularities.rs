//! Singularity detection against fields with known indices.

use grainline::generate::{self, Grid};
use grainline::geometry::{Geometry, GeometryOptions};
use grainline::highlight::smoothest::{smoothest_field, SmoothestOptions};
use grainline::highlight::Symmetry;
use grainline::mesh::Mesh;
use grainline::solve::singularities;
use nalgebra::Vector3;

/// The face whose projection onto the xy-plane contains (x, y).
fn face_containing(mesh: &Mesh, x: f64, y: f64) -> u32 {
    (0..mesh.num_faces())
        .find(|&f| {
            let p = mesh.face_positions(f);
            let cross = |a: Vector3<f64>, b: Vector3<f64>| {
                (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)
            };
            let s = [cross(p[0], p[1]), cross(p[1], p[2]), cross(p[2], p[0])];
            s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
        })
        .unwrap() as u32
}

/// A planar field as a function of the offset from its centre.
type Field<'a> = &'a dyn Fn(f64, f64) -> Vector3<f64>;

#[test]
fn planar_index_plus_one_minus_one_and_half() {
    let mesh = generate::plane(1.0, Grid::new(11, 11));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let (cx, cy) = (0.03, -0.05);
    let centre_face = face_containing(&mesh, cx, cy);
    let field = |f: &dyn Fn(f64, f64) -> Vector3<f64>| -> Vec<f64> {
        mesh.positions
            .iter()
            .zip(&g.frames)
            .map(|(p, fr)| fr.angle_of(&f(p.x - cx, p.y - cy)))
            .collect()
    };
    let cases: [(Field, u32, f64); 4] = [
        (&|x, y| Vector3::new(x, y, 0.0), 1, 1.0),
        (&|x, y| Vector3::new(x, -y, 0.0), 1, -1.0),
        // A line field turning by half the angle: u = (cos θ/2, sin θ/2).
        (
            &|x, y| {
                let t = y.atan2(x) / 2.0;
                Vector3::new(t.cos(), t.sin(), 0.0)
            },
            2,
            0.5,
        ),
        (
            &|x, y| {
                let t = -y.atan2(x) / 2.0;
                Vector3::new(t.cos(), t.sin(), 0.0)
            },
            2,
            -0.5,
        ),
    ];
    for (f, k, index) in cases {
        let phi = field(f);
        let s = singularities(&mesh, &g, &phi, k);
        assert_eq!(s.len(), 1, "k {k} index {index}: {s:?}");
        assert_eq!(s[0].face, centre_face);
        assert_eq!(s[0].index, index);
        let p = mesh.face_positions(centre_face as usize);
        let c = (p[0] + p[1] + p[2]) / 3.0;
        assert_eq!(s[0].position, [c.x, c.y, c.z]);
    }
}

#[test]
fn indices_add_up_to_the_euler_characteristic() {
    // Poincaré–Hopf on closed surfaces: sphere χ = 2, torus χ = 0; frames are twisted at random
    // to show the result does not depend on them.
    let twisted = GeometryOptions { frame_twist_seed: Some(11), ..Default::default() };
    for (mesh, chi) in
        [(generate::icosphere(1.0, 3), 2.0), (generate::torus(2.0, 0.7, 32, 12), 0.0)]
    {
        for opts in [GeometryOptions::default(), twisted] {
            let g = Geometry::compute(&mesh, &opts);
            for sym in [Symmetry::Oriented, Symmetry::Line] {
                let f = smoothest_field(&mesh, &g, sym, &SmoothestOptions::default()).unwrap();
                let s = singularities(&mesh, &g, &f.phi, sym.k());
                let total: f64 = s.iter().map(|s| s.index).sum();
                eprintln!("χ {chi} {sym:?}: {} singular faces, total {total}", s.len());
                assert!((total - chi).abs() < 1e-9, "{sym:?}: {total} vs {chi}");
                if chi == 2.0 {
                    assert!(s.len() >= 2);
                }
            }
        }
    }
}
