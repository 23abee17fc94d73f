//! The acceptance corpus of issue 13 ("Edits that land"), shared by `tests/edit_fidelity.rs`
//! and `examples/bench_fidelity.rs` (which includes this file with `#[path]`).
//!
//! - **Parts**: generated millimetre parts (a kettle-like body of revolution, a gently doubly
//!   curved panel, a flat sheet seen by a near eye, and each with a 0.15 mm ripple of 8 mm
//!   wavelength) and the meshes of `../shared/meshes` that have smooth regions, scaled to a
//!   200 mm bounding-box diagonal.
//! - **Lighting** (deterministic, from the part's bounding box; nothing tuned per edit): the
//!   generated parts have a fixed eye and key light per family; a shared mesh is seen from its
//!   thinnest bounding-box axis a₃ tilted towards the middle one a₂ (eye 1.5 diagonals away), lit
//!   from a₃ + a₂, with the initial field along its longest axis a₁ (or its UVs). Then the key
//!   highlight C0 = {hᵀu = 0} runs across the part's front.
//! - **Placement** ([`place`]): C0 is chained into polylines; a *stretch* is a run of C0 facing
//!   the eye, turning by less than 30° between the chords a quarter warp radius before and after
//!   each point, and at least one warp radius away from
//!   boundaries, critical points, creases (dihedral > 45°) and the initial field's singular
//!   triangles. On the longest stretch the brush centre is the point with the largest clearance
//!   (capped at half the curve's length), preferring the middle. Bend and expand: strength 0.8,
//!   radius 6 % of the diagonal, centred there, pushing across C0. Curve: an S-curve 25 % of the
//!   diagonal long through the centre, crossing C0 at about 50°, radius 2 % of the diagonal, traced
//!   on the surface as a 3D polyline.
//! - **Measure**: `grainline::fidelity` — the figures the optimize stage reports per edit
//!   (`OptimizeStageReport::fidelity`), from the shape the edit tool recorded.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

use grainline::edit::support::closest_point_on_triangle;
use grainline::edit::Edit;
use grainline::fidelity::EditFidelity;
use grainline::generate::{curved_panel, kettle_body, Ripple};
use grainline::geometry::Geometry;
use grainline::mesh::Mesh;
use grainline::pipeline::optimize::optimize_stage;
use grainline::pipeline::{prepare, Prepared, Silent, Stages};
use grainline::scene::{LoadedScene, Scene};
use grainline::solve::SolverSettings;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Warp brush radius, share of the bounding-box diagonal.
pub const WARP_RADIUS: f64 = 0.06;
/// Warp strength.
pub const WARP_STRENGTH: f64 = 0.8;
/// Curve length, share of the diagonal.
pub const CURVE_LENGTH: f64 = 0.25;
/// Curve brush radius, share of the diagonal.
pub const CURVE_RADIUS: f64 = 0.02;

/// How fine the generated parts are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// 20k–60k vertices (the benchmark).
    Full,
    /// 5k–10k vertices (the test).
    Small,
}

/// The initial field of a case.
#[derive(Clone, Copy, Debug)]
pub enum Init {
    /// The part's UVs (`field.init: "uv"`).
    Uv,
    /// A world direction (`field.init: "world"`).
    World(V3),
}

/// One part of the corpus with its lighting.
#[derive(Clone, Debug)]
pub struct Case {
    /// Short name (the table's first column).
    pub name: String,
    /// The OBJ file.
    pub obj: PathBuf,
    /// `mesh.scale`.
    pub scale: f64,
    /// `mesh.weld`.
    pub weld: Option<f64>,
    /// `mesh.allow_nonmanifold`.
    pub nonmanifold: bool,
    /// The initial field.
    pub init: Init,
    /// The eye (scene units, after scaling).
    pub eye: V3,
    /// The point looked at.
    pub target: V3,
    /// Direction towards the key light.
    pub light: V3,
}

/// The directory of the generated OBJ files and scenes (one for every run, so nothing piles up
/// in the temporary directory).
pub fn scratch_dir() -> PathBuf {
    let d = std::env::temp_dir().join("grainline-corpus");
    let _ = std::fs::create_dir_all(&d);
    d
}

/// Writes a generated part (to a temporary name first, then renamed: tests running at the same
/// time never read a half-written file).
fn write_obj(mesh: &Mesh, name: &str) -> Result<PathBuf, String> {
    let dir = scratch_dir();
    let p = dir.join(format!("{name}-{}v.obj", mesh.num_vertices()));
    let tmp = dir.join(format!(
        "{name}-{}v.{}.{:?}.tmp",
        mesh.num_vertices(),
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::write(&tmp, grainline::mesh::write::obj_string(mesh, name))
        .and_then(|_| std::fs::rename(&tmp, &p))
        .map_err(|e| format!("{}: {e}", p.display()))?;
    Ok(p)
}

/// The generated parts: `body`, `panel`, `sheet` and their rippled variants `*-ripple`.
pub fn generated_cases(size: Size, names: Option<&[String]>) -> Result<Vec<Case>, String> {
    let wanted = |n: &str| names.is_none_or(|l| l.iter().any(|x| x == n));
    let (around, profile, nx, ny) = match size {
        Size::Full => (200, 200, 240, 180),
        Size::Small => (80, 80, 100, 75),
    };
    let mut out = Vec::new();
    for ripple in [None, Some(Ripple::CORPUS)] {
        let tail = if ripple.is_some() { "-ripple" } else { "" };
        // The body of revolution, UV field around it; eye in front, light above right.
        let name = format!("body{tail}");
        if wanted(&name) {
            let mesh = kettle_body(around, profile, ripple);
            out.push(Case {
                obj: write_obj(&mesh, &name)?,
                name,
                scale: 1.0,
                weld: None,
                nonmanifold: false,
                init: Init::Uv,
                eye: V3::new(0.0, -420.0, 170.0),
                target: V3::new(0.0, 0.0, 90.0),
                light: V3::new(0.35, -0.6, 0.7),
            });
        }
        // Panel and sheet: 200 × 150 mm, UV field along x, light from the front, eye 600 mm
        // (panel) or 300 mm (sheet) away. On the panel the grain tilts with the slope x/R;
        // seen from 300 mm that tilt cancels the view's change across the part and hᵀu has no
        // zero on it (the highlight is off the panel), from 600 mm it is at x ≈ −26 mm.
        for (base, r, eye) in [
            ("panel", (600.0, 400.0), V3::new(21.0, -300.0, 520.0)),
            ("sheet", (f64::INFINITY, f64::INFINITY), V3::new(21.0, -150.0, 260.0)),
        ] {
            let name = format!("{base}{tail}");
            if wanted(&name) {
                let mesh = curved_panel(200.0, 150.0, r.0, r.1, nx, ny, ripple);
                out.push(Case {
                    obj: write_obj(&mesh, &name)?,
                    name,
                    scale: 1.0,
                    weld: None,
                    nonmanifold: false,
                    init: Init::Uv,
                    eye,
                    target: V3::zeros(),
                    light: V3::new(0.0, -0.35, 1.0),
                });
            }
        }
    }
    Ok(out)
}

/// The shared meshes of the corpus (file, whether it has UVs, weld distance in file units,
/// non-manifold vertices accepted). The teapot's patches are welded, which leaves one
/// non-manifold vertex (its spout's tip).
pub const SHARED: [(&str, bool, Option<f64>, bool); 6] = [
    ("spot_triangulated.obj", true, None, false),
    ("blub_quadrangulated.obj", true, None, false),
    ("stanford-bunny.obj", false, None, false),
    ("fandisk.obj", false, None, false),
    ("rocker-arm.obj", false, None, false),
    ("teapot.obj", false, Some(1e-6), true),
];

/// `../shared/meshes` (or `$GRAINLINE_SHARED/meshes`), if present.
pub fn shared_dir() -> Option<PathBuf> {
    let root = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let d = root.join("meshes");
    d.exists().then_some(d)
}

/// The shared meshes' cases (scaled to a 200 mm diagonal); a message when `../shared` is absent,
/// and one per mesh that does not load.
pub fn shared_cases(names: Option<&[String]>) -> Result<Vec<Case>, String> {
    let Some(dir) = shared_dir() else {
        eprintln!("skipping the shared meshes: ../shared/meshes not found (set GRAINLINE_SHARED)");
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (file, uv, weld, nonmanifold) in SHARED {
        let name = file.split(['_', '.']).next().unwrap_or(file).to_string();
        let name = name.strip_prefix("stanford-").unwrap_or(&name).to_string();
        if !names.is_none_or(|l| l.contains(&name)) {
            continue;
        }
        let path = dir.join(file);
        let options = grainline::mesh::load::LoadOptions {
            weld,
            allow_nonmanifold: nonmanifold,
            ..Default::default()
        };
        let mesh = match grainline::mesh::load::load_obj(&path, &options) {
            Ok(m) => m.mesh,
            Err(e) => {
                eprintln!("skipping {name}: {e}");
                continue;
            }
        };
        let (lo, hi) = bbox(&mesh.positions);
        let scale = 200.0 / (hi - lo).norm();
        let (lo, hi) = (lo * scale, hi * scale);
        let (c, ext) = ((lo + hi) * 0.5, hi - lo);
        let mut axes = [0usize, 1, 2];
        axes.sort_by(|&a, &b| ext[b].total_cmp(&ext[a]).then(a.cmp(&b)));
        let unit = |k: usize| {
            let mut v = V3::zeros();
            v[k] = 1.0;
            v
        };
        let (a1, a2, a3) = (unit(axes[0]), unit(axes[1]), unit(axes[2]));
        let view = (a3 + 0.3 * a2).normalize();
        out.push(Case {
            name,
            obj: path,
            scale,
            weld,
            nonmanifold,
            init: if uv { Init::Uv } else { Init::World(a1) },
            eye: c + 300.0 * view,
            target: c,
            light: (a3 + a2).normalize(),
        });
    }
    Ok(out)
}

/// The scene of a case, without edits.
pub fn scene(case: &Case) -> Result<LoadedScene, String> {
    let json = scene_json(case);
    let path = scratch_dir().join(format!("{}.json", case.name));
    let scene = Scene::from_str(&json.to_string(), &path).map_err(|e| e.to_string())?;
    Ok(LoadedScene { base: scratch_dir(), path, scene })
}

/// The scene file of a case, without edits, as JSON (the mesh path absolute).
pub fn scene_json(case: &Case) -> serde_json::Value {
    let arr = |v: &V3| [v.x, v.y, v.z];
    let mut mesh =
        serde_json::json!({ "path": case.obj.display().to_string(), "scale": case.scale });
    if let Some(w) = case.weld {
        mesh["weld"] = w.into();
    }
    if case.nonmanifold {
        mesh["allow_nonmanifold"] = true.into();
    }
    let field = match case.init {
        Init::Uv => serde_json::json!({ "init": "uv", "symmetry": "line" }),
        Init::World(d) => {
            serde_json::json!({ "init": "world", "world": arr(&d), "symmetry": "line" })
        }
    };
    serde_json::json!({
        "mesh": mesh,
        "units": "mm",
        "lights": [{ "type": "directional", "key": true, "direction": arr(&case.light) }],
        "view": { "eye": arr(&case.eye), "target": arr(&case.target) },
        "field": field,
    })
}

/// The solver settings for an energy: `Ok(None)` when this build's scene loader does not know
/// `solver.highlight_energy` and the energy is not today's ("tensor").
///
/// `GRAINLINE_CORPUS_SOLVER` (a JSON object of further `solver` keys, the bench's `--solver`)
/// is merged in, for experiments.
pub fn solver_settings(energy: &str) -> Result<Option<(SolverSettings, bool)>, String> {
    let mut json = serde_json::json!({ "highlight_energy": energy });
    if let Ok(extra) = std::env::var("GRAINLINE_CORPUS_SOLVER") {
        let extra: serde_json::Value =
            serde_json::from_str(&extra).map_err(|e| format!("GRAINLINE_CORPUS_SOLVER: {e}"))?;
        for (k, v) in extra.as_object().into_iter().flatten() {
            json[k] = v.clone();
        }
    }
    match serde_json::from_value::<SolverSettings>(json) {
        Ok(s) => Ok(Some((s, true))),
        Err(e) if e.to_string().contains("unknown field") => {
            Ok((energy == "tensor").then(|| (SolverSettings::default(), false)))
        }
        Err(e) => Err(format!("solver.highlight_energy = {energy:?}: {e}")),
    }
}

fn bbox(p: &[V3]) -> (V3, V3) {
    let mut lo = V3::repeat(f64::INFINITY);
    let mut hi = V3::repeat(f64::NEG_INFINITY);
    for q in p {
        lo = lo.inf(q);
        hi = hi.sup(q);
    }
    (lo, hi)
}

// ---------------------------------------------------------------------------------------------
// Placement

/// Where the corpus puts a case's edits.
#[derive(Clone, Debug)]
pub struct Placement {
    /// Brush centre (on C0, on the surface).
    pub point: V3,
    /// Unit tangent of C0 there.
    pub along: V3,
    /// Unit tangent across C0 (normal × along): the warps' `direction`.
    pub across: V3,
    /// Unit surface normal there.
    pub normal: V3,
    /// The part's bounding-box diagonal.
    pub diag: f64,
    /// Distance from the centre to the nearest boundary / critical point / crease / singularity
    /// (capped at half the curve's length).
    pub clearance: f64,
    /// Length of the chosen stretch of C0.
    pub stretch: f64,
    /// Segments of C0.
    pub c0_segments: usize,
    /// The curve edit's polyline (on the surface).
    pub curve: Vec<V3>,
    /// Obstacles: boundary edges, crease edges, critical vertices, singular triangles.
    pub obstacles: [usize; 4],
}

/// Points to stay away from: boundary vertices, critical points, crease vertices (dihedral
/// angle above 45°) and the centroids of the initial field's singular triangles.
fn obstacles(mesh: &Mesh, p: &Prepared) -> (Vec<V3>, [usize; 4]) {
    let pos = &mesh.positions;
    let fn_: Vec<V3> = mesh
        .faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| pos[i as usize]);
            (b - a).cross(&(c - a)).try_normalize(0.0).unwrap_or_else(V3::zeros)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (fi, f) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push(fi);
        }
    }
    let mut bad = vec![false; pos.len()];
    let mut counts = [0usize; 4];
    let cos45 = std::f64::consts::FRAC_1_SQRT_2;
    for (&(a, b), fs) in &edges {
        let boundary = fs.len() != 2;
        if boundary || fn_[fs[0]].dot(&fn_[fs[1]]) < cos45 {
            counts[if boundary { 0 } else { 1 }] += 1;
            bad[a as usize] = true;
            bad[b as usize] = true;
        }
    }
    for (i, &c) in p.field.critical.iter().enumerate() {
        bad[i] |= c;
        counts[2] += c as usize;
    }
    let mut out: Vec<V3> = (0..pos.len()).filter(|&i| bad[i]).map(|i| pos[i]).collect();
    let k = p.field_options.symmetry.k();
    for s in grainline::solve::singularities(mesh, &p.field.geometry, &p.field.phi, k) {
        out.push(V3::from(s.position));
        counts[3] += 1;
    }
    (out, counts)
}

/// Nearest-obstacle distances, capped (a uniform grid of cell `cap`).
struct Clearance {
    cell: f64,
    grid: HashMap<[i64; 3], Vec<V3>>,
}

impl Clearance {
    fn new(points: &[V3], cap: f64) -> Self {
        let mut grid: HashMap<[i64; 3], Vec<V3>> = HashMap::new();
        for p in points {
            grid.entry(Self::key(p, cap)).or_default().push(*p);
        }
        Clearance { cell: cap, grid }
    }

    fn key(p: &V3, cell: f64) -> [i64; 3] {
        [(p.x / cell).floor() as i64, (p.y / cell).floor() as i64, (p.z / cell).floor() as i64]
    }

    fn at(&self, p: &V3) -> f64 {
        let k = Self::key(p, self.cell);
        let mut best = self.cell;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = self.grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for q in v {
                            best = best.min((q - p).norm());
                        }
                    }
                }
            }
        }
        best
    }
}

/// Chains segments into polylines by their shared end points (within `eps`).
fn chain(segments: &[[V3; 2]], eps: f64) -> Vec<Vec<V3>> {
    let key = |p: &V3| {
        [(p.x / eps).round() as i64, (p.y / eps).round() as i64, (p.z / eps).round() as i64]
    };
    let mut at: HashMap<[i64; 3], Vec<(usize, usize)>> = HashMap::new();
    for (i, s) in segments.iter().enumerate() {
        for (e, p) in s.iter().enumerate() {
            at.entry(key(p)).or_default().push((i, e));
        }
    }
    let neighbour = |i: usize, e: usize, used: &[bool]| -> Option<(usize, usize)> {
        let k = key(&segments[i][e]);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = at.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &(j, f) in v {
                            if j != i && !used[j] && (segments[j][f] - segments[i][e]).norm() <= eps
                            {
                                return Some((j, f));
                            }
                        }
                    }
                }
            }
        }
        None
    };
    let mut used = vec![false; segments.len()];
    let mut lines = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        // Walk forward from end 1, then backward from end 0.
        let mut fwd = vec![segments[start][0], segments[start][1]];
        let (mut i, mut e) = (start, 1);
        while let Some((j, f)) = neighbour(i, e, &used) {
            used[j] = true;
            fwd.push(segments[j][1 - f]);
            (i, e) = (j, 1 - f);
        }
        let mut back = Vec::new();
        let (mut i, mut e) = (start, 0);
        while let Some((j, f)) = neighbour(i, e, &used) {
            used[j] = true;
            back.push(segments[j][1 - f]);
            (i, e) = (j, 1 - f);
        }
        back.reverse();
        back.extend(fwd);
        lines.push(back);
    }
    lines
}

/// Closest points on the mesh: faces bucketed in a uniform grid (cell: four median face radii;
/// a face in every cell its bounding box touches), searched ring by ring.
struct Surface<'a> {
    mesh: &'a Mesh,
    normals: Vec<V3>,
    cell: f64,
    grid: HashMap<[i64; 3], Vec<u32>>,
    rings: i64,
}

impl<'a> Surface<'a> {
    fn new(mesh: &'a Mesh, geometry: &Geometry) -> Self {
        let pos = &mesh.positions;
        let mut radii: Vec<f64> = mesh
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| pos[i as usize]);
                let m = (a + b + c) / 3.0;
                (a - m).norm().max((b - m).norm()).max((c - m).norm())
            })
            .collect();
        radii.sort_by(f64::total_cmp);
        let (lo, hi) = bbox(pos);
        let extent = (hi - lo).max().max(1e-300);
        let median = radii.get(radii.len() / 2).copied().unwrap_or(extent);
        let cell = (4.0 * median).max(extent / 512.0).max(1e-300);
        let key = |p: &V3| Self::key_of(p, cell);
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (fi, f) in mesh.faces.iter().enumerate() {
            let (flo, fhi) = bbox(&f.map(|i| pos[i as usize]));
            let (k0, k1) = (key(&flo), key(&fhi));
            for x in k0[0]..=k1[0] {
                for y in k0[1]..=k1[1] {
                    for z in k0[2]..=k1[2] {
                        grid.entry([x, y, z]).or_default().push(fi as u32);
                    }
                }
            }
        }
        let rings = (extent / cell).ceil() as i64 + 2;
        Surface { mesh, normals: geometry.frames.iter().map(|f| f.n).collect(), cell, grid, rings }
    }

    fn key_of(p: &V3, cell: f64) -> [i64; 3] {
        [(p.x / cell).floor() as i64, (p.y / cell).floor() as i64, (p.z / cell).floor() as i64]
    }

    /// The closest point of the mesh to `p` and the interpolated vertex normal there.
    fn project(&self, p: &V3) -> (V3, V3) {
        let pos = &self.mesh.positions;
        let k = Self::key_of(p, self.cell);
        let mut best = (f64::INFINITY, *p, V3::z());
        let test = |fi: u32, best: &mut (f64, V3, V3)| {
            let f = self.mesh.faces[fi as usize];
            let [a, b, c] = f.map(|i| pos[i as usize]);
            let (q, w) = closest_point_on_triangle(p, &a, &b, &c);
            let d = (q - p).norm();
            if d < best.0 {
                let n = f.iter().zip(w).map(|(&i, w)| self.normals[i as usize] * w).sum::<V3>();
                *best = (d, q, n.try_normalize(0.0).unwrap_or(V3::z()));
            }
        };
        for ring in 0..=self.rings {
            for dx in -ring..=ring {
                for dy in -ring..=ring {
                    for dz in -ring..=ring {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != ring {
                            continue;
                        }
                        if let Some(faces) = self.grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                            for &fi in faces {
                                test(fi, &mut best);
                            }
                        }
                    }
                }
            }
            // Every face not yet seen lies in a cell at least `ring` cells away.
            if best.0 <= ring as f64 * self.cell {
                break;
            }
        }
        (best.1, best.2)
    }
}

/// For each point of a polyline: whether it turns by more than `max_deg` between the chords to
/// the points `delta` of arc length before and after it (points nearer an end count as
/// smooth).
fn sharp_points(line: &[V3], delta: f64, max_deg: f64) -> Vec<bool> {
    let n = line.len();
    let mut s = vec![0.0; n];
    for k in 1..n {
        s[k] = s[k - 1] + (line[k] - line[k - 1]).norm();
    }
    let cos_max = max_deg.to_radians().cos();
    let (mut back, mut fwd) = (0usize, 0usize);
    (0..n)
        .map(|k| {
            while back + 1 < k && s[back + 1] <= s[k] - delta {
                back += 1;
            }
            fwd = fwd.max(k);
            while fwd < n && s[fwd] < s[k] + delta {
                fwd += 1;
            }
            if s[back] > s[k] - delta || fwd >= n {
                return false;
            }
            let (a, b) = (line[k] - line[back], line[fwd] - line[k]);
            match (a.try_normalize(1e-300), b.try_normalize(1e-300)) {
                (Some(a), Some(b)) => a.dot(&b) < cos_max,
                _ => false,
            }
        })
        .collect()
}

/// Places the edits of a case on its initial field (module documentation).
pub fn place(mesh: &Mesh, p: &Prepared, eye: &V3) -> Result<Placement, String> {
    let geom = &p.field.geometry;
    let (lo, hi) = bbox(&mesh.positions);
    let diag = (hi - lo).norm();
    let r_warp = WARP_RADIUS * diag;
    let half_curve = 0.5 * CURVE_LENGTH * diag;
    let u = geom.directions_of(&p.field.phi);
    let segments =
        grainline::fidelity::highlight_segments(mesh, &p.field.h, &u, p.field_options.symmetry);
    if segments.is_empty() {
        return Err("the initial field has no key highlight (hᵀu has no zero)".into());
    }
    let (obstacle_points, obstacles) = obstacles(mesh, p);
    let clear = Clearance::new(&obstacle_points, half_curve);
    let surface = Surface::new(mesh, geom);
    let lines = chain(&segments, 1e-7 * diag);
    // The best stretch: (length, its points, clearances).
    let mut best: Option<(f64, Vec<V3>, Vec<f64>)> = None;
    for line in &lines {
        let sharp = sharp_points(line, 0.25 * r_warp, 30.0);
        let mut run: Vec<V3> = Vec::new();
        let mut run_clear: Vec<f64> = Vec::new();
        let mut flush = |run: &mut Vec<V3>, rc: &mut Vec<f64>| {
            if run.len() >= 2 {
                let len: f64 = run.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
                if best.as_ref().is_none_or(|b| len > b.0 + 1e-9 * diag) {
                    best = Some((len, run.clone(), rc.clone()));
                }
            }
            run.clear();
            rc.clear();
        };
        for k in 0..line.len().saturating_sub(1) {
            let (a, b) = (line[k], line[k + 1]);
            let d = b - a;
            if d.norm() <= 0.0 {
                continue;
            }
            let mid = (a + b) * 0.5;
            let c = clear.at(&mid);
            let (_, n) = surface.project(&mid);
            let facing = n.dot(&(eye - mid).normalize()) > 0.3;
            let turn_ok = !sharp[k];
            if c < r_warp || !facing || !turn_ok {
                flush(&mut run, &mut run_clear);
                if c < r_warp || !facing {
                    continue;
                }
            }
            if run.is_empty() {
                run.push(a);
            }
            run.push(b);
            run_clear.push(c);
        }
        flush(&mut run, &mut run_clear);
    }
    let Some((length, pts, cl)) = best else {
        return Err(format!(
            "no stretch of the key highlight ({} segments) facing the eye and {:.1} from \
             boundaries, critical points, creases and singularities",
            segments.len(),
            r_warp
        ));
    };
    // Arc positions of the segment midpoints; score = capped clearance, minus distance from
    // the middle of the stretch.
    let mut s = 0.0;
    let mut pick = (f64::NEG_INFINITY, 0usize, 0.0);
    for k in 0..pts.len() - 1 {
        let l = (pts[k + 1] - pts[k]).norm();
        let sm = s + 0.5 * l;
        let score = cl[k].min(half_curve) / half_curve - 0.5 * (sm - 0.5 * length).abs() / length;
        if score > pick.0 {
            pick = (score, k, sm);
        }
        s += l;
    }
    let (_, k, s_mid) = pick;
    let at_arc = |target: f64| -> V3 {
        let mut s = 0.0;
        for w in pts.windows(2) {
            let l = (w[1] - w[0]).norm();
            if s + l >= target && l > 0.0 {
                return w[0] + (w[1] - w[0]) * ((target - s) / l).clamp(0.0, 1.0);
            }
            s += l;
        }
        if target <= 0.0 {
            pts[0]
        } else {
            pts[pts.len() - 1]
        }
    };
    let (point, normal) = surface.project(&((pts[k] + pts[k + 1]) * 0.5));
    let delta = 0.25 * r_warp;
    let chord = at_arc(s_mid + delta) - at_arc(s_mid - delta);
    let along = (chord - normal * normal.dot(&chord))
        .try_normalize(1e-12)
        .ok_or("the key highlight has no tangent at the brush centre")?;
    let across = normal.cross(&along);
    let curve = s_curve(&surface, &point, &across, 2.0 * half_curve);
    Ok(Placement {
        point,
        along,
        across,
        normal,
        diag,
        clearance: cl[k].min(half_curve),
        stretch: length,
        c0_segments: segments.len(),
        curve,
        obstacles,
    })
}

/// An S-curve of length `len` through `p`: the plane curve (s, A·sin(2πs/len)), A = len/8,
/// s ∈ [−len/2, len/2], with s along `base`, walked on the surface in steps of len/200 (each
/// step re-projected onto the surface, the base direction carried along).
fn s_curve(surface: &Surface, p: &V3, base: &V3, len: f64) -> Vec<V3> {
    let amp = len / 8.0;
    let steps = 100;
    let ds = 0.5 * len / steps as f64;
    let mut halves = Vec::new();
    for sign in [1.0, -1.0] {
        let mut pts = vec![*p];
        let (mut q, mut n) = surface.project(p);
        let mut b = *base * sign;
        for i in 0..steps {
            let s = (i as f64 + 0.5) * ds;
            // Heading of the plane curve at arc parameter s (same slope on both halves: the
            // S is point-symmetric about p).
            let slope = std::f64::consts::TAU * amp / len * (std::f64::consts::TAU * s / len).cos();
            let side = n.cross(&b);
            let heading = (b + side * (slope * sign)).normalize();
            let (nq, nn) = surface.project(&(q + heading * ds));
            if (nq - (q + heading * ds)).norm() > 0.5 * ds && (nq - q).norm() < 0.5 * ds {
                break; // walked off a boundary
            }
            q = nq;
            n = nn;
            b = (b - n * n.dot(&b)).try_normalize(1e-12).unwrap_or(b);
            pts.push(q);
        }
        halves.push(pts);
    }
    let mut out: Vec<V3> = halves[1].iter().rev().copied().collect();
    out.extend(halves[0].iter().skip(1));
    out
}

/// The three edits of a placement: bend, expand, curve.
pub fn edits(pl: &Placement) -> Vec<(&'static str, Edit)> {
    edits_json(pl)
        .into_iter()
        .map(|(name, json)| (name, serde_json::from_value(json).expect("a valid edit")))
        .collect()
}

/// The edits of a placement as scene-file JSON, by tool name.
// Built from scene JSON, so keys added later (with their defaults) need no change here.
pub fn edits_json(pl: &Placement) -> Vec<(&'static str, serde_json::Value)> {
    let arr = |v: &V3| [v.x, v.y, v.z];
    let warp = |tool: &str| {
        serde_json::json!({
            "tool": tool,
            "centre": { "point": arr(&pl.point) },
            "radius": WARP_RADIUS * pl.diag,
            "strength": WARP_STRENGTH,
            "direction": arr(&pl.across),
        })
    };
    let curve = serde_json::json!({
        "tool": "curve",
        "points": [pl.curve.iter().map(arr).collect::<Vec<_>>()],
        "radius": CURVE_RADIUS * pl.diag,
    });
    vec![("bend", warp("bend")), ("expand", warp("expand")), ("curve", curve)]
}

// ---------------------------------------------------------------------------------------------
// Running a case

/// One row of the table.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The case.
    pub case: String,
    /// bend / expand / curve.
    pub edit: String,
    /// The highlight energy asked for.
    pub energy: String,
    /// Whether the scene loader knew `solver.highlight_energy` (false: today's solver ran).
    pub energy_key: bool,
    /// Vertices of the part.
    pub vertices: usize,
    /// The figures (`None` when the edit did not run).
    pub figures: Option<EditFidelity>,
    /// Accepted iterations.
    pub iterations: usize,
    /// The iteration cap.
    pub max_iterations: usize,
    /// Why the solver stopped.
    pub stop: String,
    /// Wall seconds of the edits and the solve.
    pub seconds: f64,
    /// Wall seconds of preparing the part with the edit (load, refinement, field).
    pub prepare_seconds: f64,
    /// Vertices the refinement added inside the brush (`mesh.refine`).
    pub vertices_added: usize,
    /// Total energy of the start and after each accepted iteration.
    pub energies: Vec<f64>,
    /// Continuation stage of each accepted iteration.
    pub stages: Vec<usize>,
    /// Why the edit did not run (its error), if it did not.
    pub error: Option<String>,
}

impl Outcome {
    /// The energy never rose (within a continuation stage; 1e-12 relative slack).
    pub fn energy_monotone(&self) -> bool {
        let mut prev = self.energies.first().copied().unwrap_or(0.0);
        for (k, &e) in self.energies.iter().enumerate().skip(1) {
            let same_stage = k < 2 || self.stages[k - 1] == self.stages[k - 2];
            if same_stage && e > prev * (1.0 + 1e-12) + 1e-300 {
                return false;
            }
            prev = e;
        }
        true
    }
}

/// A case prepared once: the scene, the initial field and the placement.
pub struct PreparedCase {
    /// The scene without edits.
    pub scene: LoadedScene,
    /// The initial field.
    pub prepared: Prepared,
    /// Where the edits go.
    pub placement: Result<Placement, String>,
}

/// Loads a case, computes its initial field and places its edits.
pub fn prepare_case(case: &Case) -> Result<PreparedCase, String> {
    let scene = scene(case)?;
    let mut stages = Stages::new(&Silent);
    let prepared = prepare(&scene, &mut stages).map_err(|e| format!("{}: {e}", case.name))?;
    let placement = place(&prepared.mesh, &prepared, &case.eye);
    Ok(PreparedCase { scene, prepared, placement })
}

/// Runs one edit of a prepared case with one energy; `None` when the energy is not available.
pub fn run_edit(
    case: &Case,
    p: &PreparedCase,
    tool: &str,
    energy: &str,
) -> Result<Option<Outcome>, String> {
    let Some((settings, key)) = solver_settings(energy)? else { return Ok(None) };
    let pl = p.placement.as_ref().map_err(|e| format!("{}: {e}", case.name))?;
    let (_, edit) = edits(pl).into_iter().find(|(n, _)| *n == tool).ok_or("unknown tool")?;
    let mut scene = p.scene.clone();
    scene.scene.edits = vec![edit];
    scene.scene.solver = settings;
    // The part is prepared again with the edit in the scene, as `grainline run` does: the
    // mesh is refined inside the brush where its triangles are too coarse (`mesh.refine`).
    let t = Instant::now();
    let refined = prepare(&scene, &mut Stages::new(&Silent)).map_err(|e| e.to_string())?;
    let prepare_seconds = t.elapsed().as_secs_f64();
    let mesh = &refined.mesh;
    let mut out = Outcome {
        case: case.name.clone(),
        edit: tool.into(),
        energy: energy.into(),
        energy_key: key,
        vertices: mesh.num_vertices(),
        figures: None,
        iterations: 0,
        max_iterations: scene.scene.solver.max_iterations,
        stop: String::new(),
        seconds: 0.0,
        prepare_seconds,
        vertices_added: refined.refinement.as_ref().map_or(0, |r| r.vertices_added),
        energies: Vec::new(),
        stages: Vec::new(),
        error: None,
    };
    let mut stages = Stages::new(&Silent);
    let t = Instant::now();
    let o = match optimize_stage(&scene, &refined, &mut stages) {
        Ok(o) => o,
        Err(e) => {
            out.error = Some(e.to_string());
            return Ok(Some(out));
        }
    };
    out.seconds = t.elapsed().as_secs_f64();
    let r = &o.report.solver;
    out.iterations = r.iterations.len();
    out.stop = format!("{:?}", r.stop);
    out.energies = std::iter::once(r.initial_energy.total())
        .chain(r.iterations.iter().map(|i| i.energies.total()))
        .collect();
    out.stages = r.iterations.iter().map(|i| i.stage).collect();
    out.figures = o.report.fidelity.first().cloned();
    if out.figures.is_none() {
        out.error = Some("the optimize report has no fidelity for the edit".into());
    }
    Ok(Some(out))
}

/// The tools of the corpus, in table order.
pub const TOOLS: [&str; 3] = ["bend", "expand", "curve"];
