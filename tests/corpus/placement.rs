//! Where the corpus puts a case's edits ([`place`]): the key highlight C0 chained into
//! polylines, the longest stretch clear of boundaries, critical points, creases and the initial
//! field's singular triangles, the brush centre at the largest clearance there, and the bend,
//! expand and S-curve built on it (the module docs of `corpus`, "Placement").

use std::collections::HashMap;

use grainline::edit::support::closest_point_on_triangle;
use grainline::edit::Edit;
use grainline::geometry::Geometry;
use grainline::mesh::Mesh;
use grainline::pipeline::Prepared;

use super::{bbox, CURVE_LENGTH, CURVE_RADIUS, V3, WARP_RADIUS, WARP_STRENGTH};

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

/// Points to stay away from: boundary vertices, critical points, crease vertices (an angle
/// above 45° between the fitted normals of two faces) and the centroids of the initial field's singular triangles.
fn obstacles(mesh: &Mesh, p: &Prepared) -> (Vec<V3>, [usize; 4]) {
    let pos = &mesh.positions;
    // The part is judged on the surface the run sees: a face's normal is the mean of its
    // corners' fitted normals. A CAD crease is a cut between two patches there (a boundary,
    // each side with its own normals), and the slivers of a scan's noise or of a mesher,
    // whose facets tilt every way, are not creases.
    let geom = &p.field.geometry;
    let fn_: Vec<V3> = mesh
        .faces
        .iter()
        .map(|f| {
            f.iter()
                .map(|&i| geom.normal(i as usize))
                .sum::<V3>()
                .try_normalize(0.0)
                .unwrap_or_else(V3::zeros)
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
             boundaries, critical points, creases and singularities ({} boundary edges, {} \
             creases, {} critical vertices, {} singular triangles)",
            segments.len(),
            r_warp,
            obstacles[0],
            obstacles[1],
            obstacles[2],
            obstacles[3]
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
