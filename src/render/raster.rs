//! The triangle rasterizer: near-plane clipping, binning into row bands, and a depth-buffered
//! visibility buffer (face id and perspective-correct barycentrics per sample).
//!
//! Determinism: triangles are set up in parallel but collected in face order, binned in that
//! order, and each band is filled by one thread in that order with a strict depth test, so the
//! buffer does not depend on the thread count.

use nalgebra::Vector3;
use rayon::prelude::*;

use super::camera::Projector;
use super::displace::Displacement;

/// Rows of samples per band.
const BAND: usize = 16;

/// No face at this sample.
pub(crate) const EMPTY: u32 = u32::MAX;

/// One visibility sample.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sample {
    /// Camera depth.
    pub depth: f32,
    /// Face index, or [`EMPTY`].
    pub face: u32,
    /// Barycentric weights of the face's corners 1 and 2.
    pub b1: f32,
    /// See `b1`.
    pub b2: f32,
}

const CLEAR: Sample = Sample { depth: f32::INFINITY, face: EMPTY, b1: 0.0, b2: 0.0 };

/// The visibility buffer of `width × height` samples.
pub(crate) struct VisBuffer {
    pub width: usize,
    pub height: usize,
    pub samples: Vec<Sample>,
}

/// Rasterizer counters.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct RasterStats {
    pub triangles_in: usize,
    pub triangles_culled: usize,
    pub triangles_clipped: usize,
    pub screen_triangles: usize,
}

/// A clipped screen-space triangle.
struct ScreenTri {
    face: u32,
    xy: [[f64; 2]; 3],
    inv_z: [f64; 3],
    /// Barycentrics of the original face (corners 1 and 2) at each vertex.
    bary: [[f64; 2]; 3],
    /// Sample rows covered (inclusive start, exclusive end), columns likewise.
    rows: (usize, usize),
    cols: (usize, usize),
}

/// Rasterizes all faces into a `width × height` buffer.
///
/// With `displace`, the chords of curved recognized surfaces are drawn as sub-triangles on
/// their surfaces ([`Displacement`]); each keeps its face's id and barycentrics.
pub(crate) fn rasterize(
    cam: &Projector,
    (positions, faces): (&[Vector3<f64>], &[[u32; 3]]),
    displace: Option<&Displacement>,
    width: usize,
    height: usize,
) -> (VisBuffer, RasterStats) {
    let cam_pos: Vec<Vector3<f64>> = positions.par_iter().map(|p| cam.camera_coords(p)).collect();
    let clipped = faces
        .par_iter()
        .filter(|tri| tri.iter().any(|&i| cam_pos[i as usize].z <= cam.near))
        .count();
    // Back faces are skipped only when they can never be seen (see `closed_outside`).
    let cull = clipped == 0 && closed_outside(positions, faces, &cam.eye);
    // Screen triangles in face order (rayon's collect keeps the order), without a per-face
    // slot for the faces that give none.
    let tris: Vec<ScreenTri> = faces
        .par_iter()
        .enumerate()
        .flat_map_iter(|(f, tri)| {
            let subs = displace.and_then(|d| d.sub_triangles(positions, f, tri));
            let corner_bary = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
            let whole = [0, 1, 2].map(|k| (cam_pos[tri[k] as usize], corner_bary[k]));
            let drawn: Vec<[(Vector3<f64>, [f64; 2]); 3]> = match subs {
                None if cull && faces_away(positions, tri, &cam.eye) => vec![],
                None => vec![whole],
                Some(subs) => subs
                    .into_iter()
                    .filter(|s| !(cull && corners_away(&s.map(|c| c.0), &cam.eye)))
                    .map(|s| s.map(|(p, b)| (cam.camera_coords(&p), b)))
                    .collect(),
            };
            drawn.into_iter().flat_map(move |verts| {
                setup(cam, f as u32, verts, width, height).0.into_iter().flatten()
            })
        })
        .collect();
    let mut stats =
        RasterStats { triangles_in: faces.len(), triangles_clipped: clipped, ..Default::default() };
    let nbands = height.div_ceil(BAND);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nbands];
    let mut faces_drawn = 0;
    let mut last_face = u32::MAX;
    for (id, t) in tris.iter().enumerate() {
        if t.face != last_face {
            faces_drawn += 1;
            last_face = t.face;
        }
        for b in &mut bins[t.rows.0 / BAND..t.rows.1.div_ceil(BAND)] {
            b.push(id as u32);
        }
    }
    stats.triangles_culled = faces.len() - faces_drawn;
    stats.screen_triangles = tris.len();
    let mut samples = vec![CLEAR; width * height];
    samples.par_chunks_mut(BAND * width).zip(bins.par_iter()).enumerate().for_each(
        |(band, (chunk, bin))| {
            let row0 = band * BAND;
            for &id in bin {
                fill(&tris[id as usize], chunk, row0, width);
            }
        },
    );
    (VisBuffer { width, height, samples }, stats)
}

/// Whether the face's outward side (counter-clockwise corners) faces away from the eye.
#[inline]
fn faces_away(positions: &[Vector3<f64>], tri: &[u32; 3], eye: &Vector3<f64>) -> bool {
    corners_away(&tri.map(|i| positions[i as usize]), eye)
}

/// Whether the triangle `[a, b, c]` (counter-clockwise outside) faces away from the eye.
#[inline]
fn corners_away([a, b, c]: &[Vector3<f64>; 3], eye: &Vector3<f64>) -> bool {
    (b - a).cross(&(c - a)).dot(&(a - eye)) > 0.0
}

/// The eye-independent part of [`closed_outside`]: whether the mesh is closed and consistently
/// oriented, and its edge-connected component per face. Depends on the face list and the
/// vertex count only, so it is computed once per mesh and kept (see [`topology`]).
pub(crate) struct Topology {
    faces: Vec<[u32; 3]>,
    vertices: usize,
    /// Component label (0..count) per face, `None` if the mesh is not closed and oriented.
    components: Option<(Vec<u32>, usize)>,
}

/// The last topology computed. A render of the same faces (compared in full, so a hit is
/// exact) reuses it: the check costs ~45 ms on a 268k-face mesh, the comparison < 1 ms.
static TOPOLOGY: std::sync::Mutex<Option<std::sync::Arc<Topology>>> = std::sync::Mutex::new(None);

/// The topology of `faces` on `vertices` vertices, from the cache when the faces are the same.
pub(crate) fn topology(vertices: usize, faces: &[[u32; 3]]) -> std::sync::Arc<Topology> {
    if let Ok(guard) = TOPOLOGY.lock() {
        if let Some(t) = guard.as_ref() {
            if t.vertices == vertices && t.faces[..] == *faces {
                return t.clone();
            }
        }
    }
    let t = std::sync::Arc::new(Topology {
        faces: faces.to_vec(),
        vertices,
        components: closed_components(vertices, faces),
    });
    if let Ok(mut guard) = TOPOLOGY.lock() {
        *guard = Some(t.clone());
    }
    t
}

/// Whether the mesh is closed and consistently oriented (every directed edge appears once and
/// its reverse once); if so, the edge-connected component of every face (labels in order of
/// first appearance) and the number of components.
fn closed_components(n: usize, faces: &[[u32; 3]]) -> Option<(Vec<u32>, usize)> {
    if faces.is_empty() || faces.iter().any(|f| f[0] == f[1] || f[1] == f[2] || f[2] == f[0]) {
        return None;
    }
    // Outgoing directed edges per vertex (compressed rows): (head, face).
    let mut start = vec![0u32; n + 1];
    for t in faces {
        for &a in t {
            start[a as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut out = vec![(0u32, 0u32); 3 * faces.len()];
    for (f, t) in faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3]);
            out[fill[a] as usize] = (b, f as u32);
            fill[a] += 1;
        }
    }
    let row = |v: u32| &out[start[v as usize] as usize..start[v as usize + 1] as usize];
    // Each directed edge once, and its reverse once: the face across it.
    let twins: Option<Vec<(u32, u32)>> = (0..n as u32)
        .into_par_iter()
        .flat_map_iter(|a| row(a).iter().map(move |&(b, f)| (a, b, f)))
        .map(|(a, b, f)| {
            let once = row(a).iter().filter(|e| e.0 == b).count() == 1;
            let mut rev = row(b).iter().filter(|e| e.0 == a);
            match (once, rev.next(), rev.next()) {
                (true, Some(&(_, g)), None) => Some((f, g)),
                _ => None,
            }
        })
        .collect();
    let twins = twins?;
    // Edge-connected components (union–find, sequential so the labels are fixed).
    let mut parent: Vec<u32> = (0..faces.len() as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for &(a, b) in &twins {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut label = vec![u32::MAX; faces.len()];
    let mut count = 0usize;
    let mut comp = vec![0u32; faces.len()];
    for (f, c) in comp.iter_mut().enumerate() {
        let r = find(&mut parent, f as u32) as usize;
        if label[r] == u32::MAX {
            label[r] = count as u32;
            count += 1;
        }
        *c = label[r];
    }
    Some((comp, count))
}

/// Whether every back face is hidden, so skipping them leaves the visibility buffer unchanged:
/// the mesh is closed and consistently oriented (every directed edge appears once and its
/// reverse once), each edge-connected component has positive signed volume (its faces wind
/// outwards) and the eye lies outside each component (winding number 0, from the solid angles
/// of Van Oosterom & Strackee 1983). For components that are embedded surfaces the first
/// surface a ray from the eye meets is then a front face. The caller also requires that no
/// face reaches the near plane (a cut would show the inside). The topology comes from
/// [`topology`] (cached per face list); the volumes and solid angles are computed per call.
pub(crate) fn closed_outside(
    positions: &[Vector3<f64>],
    faces: &[[u32; 3]],
    eye: &Vector3<f64>,
) -> bool {
    let topo = topology(positions.len(), faces);
    let Some((comp, count)) = &topo.components else {
        return false;
    };
    // Per face: 6 × signed volume of the tetrahedron (eye, a, b, c) and its solid angle.
    let per_face: Vec<(f64, f64)> = faces
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize] - eye);
            let det = a.dot(&b.cross(&c));
            let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
            let den = la * lb * lc + a.dot(&b) * lc + a.dot(&c) * lb + b.dot(&c) * la;
            (det, 2.0 * det.atan2(den))
        })
        .collect();
    // Summed in face order per component (fixed order: deterministic).
    let mut sums = vec![(0.0f64, 0.0f64); *count];
    for (&c, (vol, omega)) in comp.iter().zip(&per_face) {
        let e = &mut sums[c as usize];
        e.0 += vol;
        e.1 += omega;
    }
    sums.iter().all(|&(vol, omega)| {
        vol > 0.0 && vol.is_finite() && omega.is_finite() && omega.abs() < std::f64::consts::TAU
    })
}

/// Clips a triangle of `face` (camera coordinates and the face's barycentrics at its corners)
/// against the near plane and projects it; returns the (at most two) screen
/// triangles and whether clipping happened.
fn setup(
    cam: &Projector,
    face: u32,
    verts: [(Vector3<f64>, [f64; 2]); 3],
    width: usize,
    height: usize,
) -> ([Option<ScreenTri>; 2], bool) {
    type V = (Vector3<f64>, [f64; 2]);
    let inside = |v: &V| v.0.z > cam.near;
    let n_in = verts.iter().filter(|v| inside(v)).count();
    if n_in == 0 {
        return ([None, None], true);
    }
    let mut poly: [V; 4] = [verts[0]; 4];
    let mut len = 0;
    if n_in == 3 {
        poly[..3].copy_from_slice(&verts);
        len = 3;
    } else {
        // Sutherland–Hodgman against z = near, carrying the face barycentrics along.
        for k in 0..3 {
            let (a, b) = (&verts[k], &verts[(k + 1) % 3]);
            if inside(a) {
                poly[len] = *a;
                len += 1;
            }
            if inside(a) != inside(b) {
                let t = (cam.near - a.0.z) / (b.0.z - a.0.z);
                let p = a.0 + (b.0 - a.0) * t;
                let bc = [a.1[0] + (b.1[0] - a.1[0]) * t, a.1[1] + (b.1[1] - a.1[1]) * t];
                poly[len] = (Vector3::new(p.x, p.y, cam.near), bc);
                len += 1;
            }
        }
    }
    let mut res = [None, None];
    for k in 1..len.saturating_sub(1) {
        let vs = [poly[0], poly[k], poly[k + 1]];
        res[k - 1] = screen_tri(cam, face, &vs, width, height);
    }
    (res, n_in < 3)
}

/// Projects one camera-space triangle; `None` if it covers no sample centre's bounding box.
fn screen_tri(
    cam: &Projector,
    face: u32,
    vs: &[(Vector3<f64>, [f64; 2]); 3],
    width: usize,
    height: usize,
) -> Option<ScreenTri> {
    let xy = vs.map(|v| cam.cam_to_pixel(&v.0));
    if xy.iter().flatten().any(|c| !c.is_finite()) {
        return None;
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in &xy {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    // Samples with centre c + ½ in [lo, hi]: indices ceil(lo − ½) ..= floor(hi − ½).
    let span = |lo: f64, hi: f64, n: usize| {
        let a = (lo - 0.5).ceil().max(0.0);
        let b = ((hi - 0.5).floor() + 1.0).min(n as f64);
        if b > a {
            (a as usize, b as usize)
        } else {
            (0, 0)
        }
    };
    let rows = span(y0, y1, height);
    let cols = span(x0, x1, width);
    if rows.1 <= rows.0 || cols.1 <= cols.0 {
        return None;
    }
    Some(ScreenTri { face, xy, inv_z: vs.map(|v| 1.0 / v.0.z), bary: vs.map(|v| v.1), rows, cols })
}

/// Edge function: twice the signed area of (a, b, p).
#[inline]
fn edge(a: &[f64; 2], b: &[f64; 2], p: &[f64; 2]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Fills the part of `t` inside the band starting at `row0`.
fn fill(t: &ScreenTri, chunk: &mut [Sample], row0: usize, width: usize) {
    let area = edge(&t.xy[0], &t.xy[1], &t.xy[2]);
    if area.abs() < 1e-12 {
        return;
    }
    let inv_area = 1.0 / area;
    let rows_here = chunk.len() / width;
    let r0 = t.rows.0.max(row0);
    let r1 = t.rows.1.min(row0 + rows_here);
    for row in r0..r1 {
        let y = row as f64 + 0.5;
        let line = &mut chunk[(row - row0) * width..(row - row0 + 1) * width];
        for (col, s) in line.iter_mut().enumerate().take(t.cols.1).skip(t.cols.0) {
            let p = [col as f64 + 0.5, y];
            let l0 = edge(&t.xy[1], &t.xy[2], &p) * inv_area;
            let l1 = edge(&t.xy[2], &t.xy[0], &p) * inv_area;
            let l2 = 1.0 - l0 - l1;
            if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                continue;
            }
            // Perspective-correct interpolation: weights λ_k / z_k.
            let w = [l0 * t.inv_z[0], l1 * t.inv_z[1], l2 * t.inv_z[2]];
            let sw = w[0] + w[1] + w[2];
            if sw <= 0.0 {
                continue;
            }
            let depth = (1.0 / sw) as f32;
            if depth < s.depth {
                let b1 = (w[0] * t.bary[0][0] + w[1] * t.bary[1][0] + w[2] * t.bary[2][0]) / sw;
                let b2 = (w[0] * t.bary[0][1] + w[1] * t.bary[1][1] + w[2] * t.bary[2][1]) / sw;
                *s = Sample { depth, face: t.face, b1: b1 as f32, b2: b2 as f32 };
            }
        }
    }
}
