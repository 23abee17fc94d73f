//! Issue 14, item 6: crease-aware normals. A sheet-metal bracket generated here — an L-shaped
//! plate of thickness t with a sharp 90° bend, round holes through both legs, and each plate
//! triangulated the way CAD exporters do (every hole fanned to the cell corners: slivers) —
//! against what its construction says: on every flat face the shading normal is the plane's
//! normal, on a hole wall it is the radial direction, the 90° edges are not averaged, the sharp
//! edges are counted exactly, and the preview of the bend shades like the same faces drawn
//! apart with their exact normals.

use std::collections::HashMap;
use std::f64::consts::PI;

use grainline::geometry::normals::{
    corner_normals, face_data, vertex_normals, NormalSource, DEFAULT_CREASE_ANGLE_DEG,
};
use grainline::highlight::Symmetry;
use grainline::mesh::{Mesh, VertexFaces};
use grainline::render::image::decode_pfm;
use grainline::render::{
    render, BrdfSpec, Camera, Fresnel, LightSpec, Material, RenderInput, RenderSettings, ToneMap,
};
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// What the generator knows about each face: the exact normal of a flat face, or the hole
/// axis' centre and direction of a hole-wall face (its exact normal at a point is radial).
#[derive(Clone, Copy, Debug)]
enum Truth {
    Flat(V3),
    Wall { centre: V3, axis: V3 },
}

struct Bracket {
    mesh: Mesh,
    truth: Vec<Truth>,
    /// Sharp edges by construction (see `sharp_edges`).
    sharp_edges: usize,
}

/// Parameters: cells of side `s` (one hole of radius `r` with `n` segments each), `nx` cells
/// along the horizontal leg, `nz` along the vertical one, `ny` across; thickness `t`.
struct Spec {
    s: f64,
    r: f64,
    n: usize,
    nx: usize,
    nz: usize,
    ny: usize,
    t: f64,
}

struct Builder {
    pos: Vec<V3>,
    index: HashMap<[u64; 3], u32>,
    faces: Vec<[u32; 3]>,
    truth: Vec<Truth>,
}

impl Builder {
    fn v(&mut self, p: V3) -> u32 {
        let key = [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits());
        if let Some(&i) = self.index.get(&key) {
            return i;
        }
        self.pos.push(p);
        let i = self.pos.len() as u32 - 1;
        self.index.insert(key, i);
        i
    }

    /// A triangle, turned so that its normal points along `out`.
    fn tri(&mut self, a: V3, b: V3, c: V3, out: V3, truth: Truth) {
        let (ia, mut ib, mut ic) = (self.v(a), self.v(b), self.v(c));
        if (b - a).cross(&(c - a)).dot(&out) < 0.0 {
            std::mem::swap(&mut ib, &mut ic);
        }
        self.faces.push([ia, ib, ic]);
        self.truth.push(truth);
    }

    fn quad(&mut self, q: [V3; 4], out: V3, truth: Truth) {
        self.tri(q[0], q[1], q[2], out, truth);
        self.tri(q[0], q[2], q[3], out, truth);
    }

    /// One holed cell of a plane: `at(a, b)` maps cell coordinates in [0, s]² to 3D; the hole
    /// (centre (s/2, s/2), radius r, n segments) is fanned to the four corners.
    fn cell(&mut self, sp: &Spec, at: &dyn Fn(f64, f64) -> V3, out: V3) {
        let h = 0.5 * sp.s;
        let corner = [at(sp.s, sp.s), at(0.0, sp.s), at(0.0, 0.0), at(sp.s, 0.0)];
        let p = |k: usize| {
            let phi = 2.0 * PI * (k % sp.n) as f64 / sp.n as f64;
            at(h + sp.r * phi.cos(), h + sp.r * phi.sin())
        };
        let q = sp.n / 4;
        for (c, &cp) in corner.iter().enumerate() {
            for k in c * q..(c + 1) * q {
                self.tri(cp, p(k), p(k + 1), out, Truth::Flat(out));
            }
            self.tri(cp, corner[(c + 1) % 4], p((c + 1) * q), out, Truth::Flat(out));
        }
    }

    /// The wall of a hole between two cells `at0` (one face of the plate) and `at1` (the
    /// other), whose outward normal points at the hole's axis.
    fn wall(&mut self, sp: &Spec, at0: &dyn Fn(f64, f64) -> V3, at1: &dyn Fn(f64, f64) -> V3) {
        let h = 0.5 * sp.s;
        let (c0, c1) = (at0(h, h), at1(h, h));
        let axis = (c1 - c0).normalize();
        for k in 0..sp.n {
            let phi = |k: usize| 2.0 * PI * (k % sp.n) as f64 / sp.n as f64;
            let pt = |at: &dyn Fn(f64, f64) -> V3, k: usize| {
                at(h + sp.r * phi(k).cos(), h + sp.r * phi(k).sin())
            };
            let (a, b, c, d) = (pt(at0, k), pt(at0, k + 1), pt(at1, k + 1), pt(at1, k));
            let mid = 0.5 * (a + b);
            let radial = mid - c0 - axis * axis.dot(&(mid - c0));
            self.quad([a, b, c, d], -radial, Truth::Wall { centre: c0, axis });
        }
    }
}

fn bracket(sp: &Spec) -> Bracket {
    let mut b = Builder { pos: vec![], index: HashMap::new(), faces: vec![], truth: vec![] };
    let (s, t) = (sp.s, sp.t);
    let xa = t + sp.nx as f64 * s; // end of the horizontal leg
    let zb = t + sp.nz as f64 * s; // top of the vertical leg
    let w = sp.ny as f64 * s;
    let (ex, ey, ez) = (V3::x(), V3::y(), V3::z());
    for j in 0..sp.ny {
        let (y0, y1) = (j as f64 * s, (j + 1) as f64 * s);
        // The bend strips of the outer faces: z = 0 for x in [0, t], x = 0 for z in [0, t].
        let q = [
            V3::new(0.0, y0, 0.0),
            V3::new(t, y0, 0.0),
            V3::new(t, y1, 0.0),
            V3::new(0.0, y1, 0.0),
        ];
        b.quad(q, -ez, Truth::Flat(-ez));
        let q = [
            V3::new(0.0, y0, 0.0),
            V3::new(0.0, y0, t),
            V3::new(0.0, y1, t),
            V3::new(0.0, y1, 0.0),
        ];
        b.quad(q, -ex, Truth::Flat(-ex));
        // The end walls.
        let q =
            [V3::new(xa, y0, 0.0), V3::new(xa, y1, 0.0), V3::new(xa, y1, t), V3::new(xa, y0, t)];
        b.quad(q, ex, Truth::Flat(ex));
        let q =
            [V3::new(0.0, y0, zb), V3::new(0.0, y1, zb), V3::new(t, y1, zb), V3::new(t, y0, zb)];
        b.quad(q, ez, Truth::Flat(ez));
        for i in 0..sp.nx {
            let x0 = t + i as f64 * s;
            let outer = move |a: f64, c: f64| V3::new(x0 + a, y0 + c, 0.0);
            let inner = move |a: f64, c: f64| V3::new(x0 + a, y0 + c, t);
            b.cell(sp, &outer, -ez);
            b.cell(sp, &inner, ez);
            b.wall(sp, &outer, &inner);
        }
        for i in 0..sp.nz {
            let z0 = t + i as f64 * s;
            let outer = move |a: f64, c: f64| V3::new(0.0, y0 + c, z0 + a);
            let inner = move |a: f64, c: f64| V3::new(t, y0 + c, z0 + a);
            b.cell(sp, &outer, -ex);
            b.cell(sp, &inner, ex);
            b.wall(sp, &outer, &inner);
        }
    }
    // The two side walls (y = 0 and y = w): the L-shaped section in quads.
    for (y, out) in [(0.0, -ey), (w, ey)] {
        let p = |x: f64, z: f64| V3::new(x, y, z);
        b.quad([p(0.0, 0.0), p(t, 0.0), p(t, t), p(0.0, t)], out, Truth::Flat(out));
        for i in 0..sp.nx {
            let (x0, x1) = (t + i as f64 * s, t + (i + 1) as f64 * s);
            b.quad([p(x0, 0.0), p(x1, 0.0), p(x1, t), p(x0, t)], out, Truth::Flat(out));
        }
        for i in 0..sp.nz {
            let (z0, z1) = (t + i as f64 * s, t + (i + 1) as f64 * s);
            b.quad([p(0.0, z0), p(t, z0), p(t, z1), p(0.0, z1)], out, Truth::Flat(out));
        }
    }
    let (nx, nz, ny, n) = (sp.nx, sp.nz, sp.ny, sp.n);
    // Sharp edges, all at 90°: both rims of every hole (2n each), the outer and inner bend
    // (ny segments each), the two long edges of both end walls (2·ny each), and the outline of
    // both side walls ((nx + 1) + (nz + 1) + 1 + nz + nx + 1 segments each).
    let sharp_edges = 2 * n * (nx + nz) * ny + 2 * ny + 4 * ny + 2 * (2 * nx + 2 * nz + 4);
    Bracket { mesh: Mesh::from_triangles(b.pos, b.faces), truth: b.truth, sharp_edges }
}

fn spec() -> Spec {
    Spec { s: 40.0, r: 4.0, n: 64, nx: 3, nz: 2, ny: 2, t: 2.0 }
}

/// The exact shading normal of face `f` at its corner `c`.
fn exact(b: &Bracket, f: usize, c: usize) -> V3 {
    match b.truth[f] {
        Truth::Flat(n) => n,
        Truth::Wall { centre, axis } => {
            let p = b.mesh.positions[b.mesh.faces[f][c] as usize];
            let radial = p - centre - axis * axis.dot(&(p - centre));
            -radial.normalize()
        }
    }
}

#[test]
fn item6_bracket_is_a_closed_manifold_with_cad_slivers() {
    let b = bracket(&spec());
    let d = std::env::temp_dir().join(format!("grainline-crease-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("bracket.obj");
    std::fs::write(&p, grainline::mesh::write::obj_string(&b.mesh, "bracket")).unwrap();
    // The loader accepts it as it is (closed, manifold, consistently oriented: the
    // orientation of every face was chosen by its outward normal).
    let loaded =
        grainline::mesh::load::load_obj(&p, &grainline::mesh::load::LoadOptions::default())
            .unwrap();
    assert_eq!(loaded.mesh.num_faces(), b.mesh.num_faces());
    let topo = grainline::mesh::topology::Topology::new(&loaded.mesh).unwrap();
    assert_eq!(topo.num_boundary_loops(), 0);
    // Genus = number of holes: 2·(3 + 2) = 10, χ = 2 − 2g.
    assert_eq!(topo.euler_characteristic(), 2 - 2 * 10);
    // Slivers: the fan triangles at the ends of each quadrant are thin (CAD-like). The report's
    // smallest angle and sliver count against the angles computed here, corner by corner.
    let angle = |a: V3, b: V3, c: V3| {
        let (u, v) = (b - a, c - a);
        u.cross(&v).norm().atan2(u.dot(&v)).to_degrees()
    };
    let mut min = f64::INFINITY;
    let mut slivers = 0;
    for f in &loaded.mesh.faces {
        let [a, bb, c] = f.map(|v| loaded.mesh.positions[v as usize]);
        let m = angle(a, bb, c).min(angle(bb, c, a)).min(angle(c, a, bb));
        min = min.min(m);
        slivers += usize::from(m < 5.0);
    }
    let q = grainline::mesh::report::QualityReport::new(&loaded);
    assert!(min < 1.0 && slivers > 1000, "the part has slivers: {min}° and {slivers} below 5°");
    assert!((q.min_angle_deg - min).abs() < 1e-9 * min, "{q:?} vs {min}");
    assert_eq!(q.slivers, slivers);
    eprintln!(
        "bracket: {} vertices, {} faces, smallest angle {min:.4}°, {slivers} slivers < 5°, {} sharp \
         edges, {} split vertices",
        loaded.mesh.num_vertices(),
        loaded.mesh.num_faces(),
        q.crease_edges,
        q.split_vertices
    );
    assert_eq!(q.crease_edges, b.sharp_edges);
}

#[test]
fn item6_shading_normals_are_exact_on_flat_faces_and_hole_walls() {
    let b = bracket(&spec());
    let m = &b.mesh;
    let vf = VertexFaces::new(m);
    let fd = face_data(m);
    let (vn, _) = vertex_normals(m, &vf, NormalSource::AngleWeighted);
    let c = corner_normals(m, &vf, &fd, &vn, DEFAULT_CREASE_ANGLE_DEG);
    assert_eq!(c.crease_edges, b.sharp_edges);
    let mut worst = 0.0f64;
    for f in 0..m.num_faces() {
        for k in 0..3 {
            worst = worst.max((c.corners[f][k] - exact(&b, f, k)).norm());
        }
    }
    assert!(worst < 1e-9, "largest error of a corner normal: {worst:e}");
    // At the 90° bend the two sides keep their own normals: a corner on the bend edge
    // (0, y, 0) is −z on the horizontal leg and −x on the vertical one, never their mean.
    let bend: Vec<usize> = (0..m.num_vertices())
        .filter(|&v| {
            let p = m.positions[v];
            p.x == 0.0 && p.z == 0.0 && p.y > 0.0 && p.y < 80.0
        })
        .collect();
    assert_eq!(bend.len(), 1, "the bend edge has one inner vertex (y = 40)");
    let mut sides = vec![];
    for &(f, k) in vf.of(bend[0]) {
        sides.push(c.corners[f as usize][k as usize]);
    }
    assert!(sides.iter().all(|n| (n + V3::z()).norm() < 1e-12 || (n + V3::x()).norm() < 1e-12));
    assert!(sides.iter().any(|n| n.z < -0.5) && sides.iter().any(|n| n.x < -0.5));
    // The per-vertex normal — what the preview shaded with before — is the mean there, and it
    // is wrong at every hole rim: the test above fails for it.
    let mean = vn[bend[0]];
    assert!((mean - V3::new(-1.0, 0.0, -1.0).normalize()).norm() < 1e-12, "{mean:?}");
    let off = (0..m.num_faces())
        .filter(|&f| (0..3).any(|k| (vn[m.faces[f][k] as usize] - exact(&b, f, k)).norm() > 0.1))
        .count();
    assert!(off > 1000, "{off} faces would shade wrongly with vertex normals");
}

#[test]
fn item6_crease_angle_180_smooths_everything_and_0_splits_every_fold() {
    let b = bracket(&spec());
    let m = &b.mesh;
    let vf = VertexFaces::new(m);
    let fd = face_data(m);
    let (vn, _) = vertex_normals(m, &vf, NormalSource::AngleWeighted);
    let off = corner_normals(m, &vf, &fd, &vn, 180.0);
    assert_eq!((off.crease_edges, off.split_vertices), (0, 0));
    assert!(off
        .corners
        .iter()
        .enumerate()
        .all(|(f, c)| (0..3).all(|k| c[k] == vn[m.faces[f][k] as usize])));
    // At 5° the hole walls (5.625° between neighbouring segments) are faceted too: every wall
    // edge between two segments becomes sharp.
    let five = corner_normals(m, &vf, &fd, &vn, 5.0);
    let holes = 2 * (3 + 2);
    assert_eq!(five.crease_edges, b.sharp_edges + holes * 64);
}

/// The same faces as separate triangles (no shared vertex), each corner with its exact normal.
fn exploded(b: &Bracket) -> (Vec<V3>, Vec<[u32; 3]>, Vec<V3>) {
    let mut pos = vec![];
    let mut nor = vec![];
    let mut faces = vec![];
    for (f, tri) in b.mesh.faces.iter().enumerate() {
        let base = pos.len() as u32;
        for (k, &v) in tri.iter().enumerate() {
            pos.push(b.mesh.positions[v as usize]);
            nor.push(exact(b, f, k));
        }
        faces.push([base, base + 1, base + 2]);
    }
    (pos, faces, nor)
}

#[test]
fn item6_preview_across_the_bend_has_no_facet_gradient() {
    let b = bracket(&spec());
    let m = &b.mesh;
    let vf = VertexFaces::new(m);
    let fd = face_data(m);
    let (vn, _) = vertex_normals(m, &vf, NormalSource::AngleWeighted);
    let c = corner_normals(m, &vf, &fd, &vn, DEFAULT_CREASE_ANGLE_DEG);
    // Grain along the bend (y): tangent to both legs.
    let u = vec![V3::y(); m.num_vertices()];
    let material = Material {
        brdf: BrdfSpec::AshikhminShirley { nu: 200.0, nv: 20.0, rs: [0.9; 3] },
        fresnel: Fresnel::None,
        diffuse: [0.2; 3],
    };
    let lights = [LightSpec::Directional {
        direction: [-1.0, -0.3, -0.6],
        irradiance: 1.0,
        colour: [1.0; 3],
        key: true,
    }];
    // Looking at the outer side of the bend from below and outside; the middle row crosses it.
    let cam = Camera {
        eye: V3::new(-120.0, 40.0, -90.0),
        target: V3::new(0.0, 40.0, 0.0),
        // Up along the bend, so the image rows run across it.
        up: V3::y(),
        fov_deg: 40.0,
    };
    let (w, h) = (160usize, 120usize);
    let settings = RenderSettings {
        width: w as u32,
        height: h as u32,
        supersample: 1,
        tone_map: ToneMap::None,
        linear: Some("out.pfm".into()),
        ..Default::default()
    };
    let shot = |input: &RenderInput| {
        let out = render(input, &material, &lights, &cam, &settings).unwrap();
        decode_pfm(out.linear.as_ref().unwrap()).unwrap().2
    };
    let mut input = RenderInput::new(&m.positions, &m.faces, &vn, &u, Symmetry::Line);
    input.corner_normals = Some(&c.corners);
    let creased = shot(&input);
    let (ep, ef, en) = exploded(&b);
    let eu = vec![V3::y(); ep.len()];
    let truth = shot(&RenderInput::new(&ep, &ef, &en, &eu, Symmetry::Line));
    let averaged = shot(&RenderInput::new(&m.positions, &m.faces, &vn, &u, Symmetry::Line));
    let row = h / 2;
    let diff =
        |a: &[[f32; 3]], i: usize| (a[i][0] - truth[i][0]).abs() / truth[i][0].abs().max(1e-3);
    let covered: Vec<usize> = (0..w).map(|x| row * w + x).filter(|&i| truth[i][0] > 0.0).collect();
    assert!(covered.len() > w / 2, "the row crosses the part");
    let worst = covered.iter().map(|&i| diff(&creased, i)).fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "creased preview vs the exact faces: {worst}");
    // With averaged normals the strip next to the bend shades differently (the facet).
    let facet = covered.iter().map(|&i| diff(&averaged, i)).fold(0.0f32, f32::max);
    assert!(facet > 0.05, "averaged normals differ by {facet} only");
    // And the whole image agrees, not only the row.
    let all =
        (0..w * h).filter(|&i| truth[i][0] > 0.0).map(|i| diff(&creased, i)).fold(0.0f32, f32::max);
    assert!(all < 1e-4, "{all}");
    eprintln!(
        "bend row: {} covered pixels; creased vs exact faces {worst:e} (whole image {all:e}); \
         averaged normals {facet:.3} (relative)",
        covered.len()
    );
}

/// The bracket as a binary STL, written field by field (three vertices per triangle).
fn stl_bytes(m: &Mesh) -> Vec<u8> {
    let mut b = b"solid bracket".to_vec();
    b.resize(80, b' ');
    b.extend_from_slice(&(m.num_faces() as u32).to_le_bytes());
    for f in &m.faces {
        b.extend_from_slice(&[0u8; 12]);
        for &v in f {
            for c in m.positions[v as usize].iter() {
                b.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

#[test]
fn item6_a_scene_renders_an_stl_part_with_its_crease_angle() {
    let d = std::env::temp_dir().join(format!("grainline-crease-scene-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("bracket.stl"), stl_bytes(&bracket(&spec()).mesh)).unwrap();
    let scene = |angle: &str, png: &str| {
        let s = format!(
            r#"{{
  "mesh": {{"path": "bracket.stl"{angle}}},
  "lights": [{{"type": "directional", "direction": [-1, -0.3, -0.6]}}],
  "view": {{"eye": [-120, 40, -90], "target": [0, 40, 0], "up": [0, 1, 0], "fov_deg": 40}},
  "render": {{"width": 80, "height": 60, "output": "{png}"}}
}}"#
        );
        let p = d.join(format!("{png}.json"));
        std::fs::write(&p, s).unwrap();
        p
    };
    let run = |p: &std::path::Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_grainline"))
            .args(["--quiet", "run"])
            .arg(p)
            .output()
            .unwrap()
    };
    for (angle, png) in [("", "default.png"), (r#", "crease_angle": 180"#, "smooth.png")] {
        let o = run(&scene(angle, png));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let (a, b) = (
        std::fs::read(d.join("default.png")).unwrap(),
        std::fs::read(d.join("smooth.png")).unwrap(),
    );
    assert_ne!(a, b, "the crease angle reaches the preview");
    // Out of range: refused when the scene is read, under its key path.
    let o = run(&scene(r#", "crease_angle": 200"#, "bad.png"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("mesh.crease_angle") && e.contains("[0, 180]"),
        "{e}"
    );
}
