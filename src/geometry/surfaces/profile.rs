//! Turned faces read along their profile (module docs of [`super`], steps 3 and 4): the
//! bands a growth finds (each a cone or a cylinder between two rings) joined into the spheres
//! and tori their rings lie on, and chains of bands with a free profile left to the jet fit.

use nalgebra::Vector3;

use super::grow::{best_fit, region_on, Kinds, RegionGraph};
use super::primitive::{Primitive, SurfaceKind};
use super::tangent;
use super::MAX_CHORD_DEVIATION_DEG;
use crate::mesh::Mesh;

type V3 = Vector3<f64>;

/// A grown surface: its primitive and its regions.
pub(super) type Grown = (Primitive, Vec<u32>);

/// The distinct vertices of `regions`, as points.
fn points(g: &RegionGraph, mesh: &Mesh, regions: &[u32]) -> Vec<V3> {
    let mut vs: Vec<u32> = regions.iter().flat_map(|&r| g.verts(r).iter().copied()).collect();
    vs.sort_unstable();
    vs.dedup();
    vs.iter().map(|&v| mesh.positions[v as usize]).collect()
}

/// The distinct heights along the axis of the points (rings), up to `tol`.
fn rings(prim: &Primitive, points: &[V3], tol: f64) -> Vec<f64> {
    let Some((o, a)) = prim.axis() else { return vec![] };
    let mut hs: Vec<f64> = points.iter().map(|p| (p - o).dot(&a)).collect();
    hs.sort_by(f64::total_cmp);
    hs.dedup_by(|x, y| (*x - *y).abs() <= 4.0 * tol);
    hs
}

fn coaxial(p: &Primitive, q: &Primitive) -> bool {
    let (Some((op, ap)), Some((oq, aq))) = (p.axis(), q.axis()) else { return false };
    ap.cross(&aq).norm() < 1e-3 && (oq - op).cross(&ap).norm() <= 1e-3 * (oq - op).norm().max(1.0)
}

/// Per surface, the surfaces next to it (sorted, unique).
fn neighbours(g: &RegionGraph, grown: &[Grown]) -> Vec<Vec<usize>> {
    let mut owner = vec![usize::MAX; g.regions.normal.len()];
    for (k, (_, rs)) in grown.iter().enumerate() {
        for &r in rs {
            owner[r as usize] = k;
        }
    }
    grown
        .iter()
        .enumerate()
        .map(|(k, (_, rs))| {
            let mut out: Vec<usize> = rs
                .iter()
                .flat_map(|&r| g.neighbours(r).iter().map(|&(s, _)| owner[s as usize]))
                .filter(|&j| j != usize::MAX && j != k)
                .collect();
            out.sort_unstable();
            out.dedup();
            out
        })
        .collect()
}

/// Step 2's end: neighbouring cylinders or cones that one primitive of their kind passes
/// through — pieces of one face that a growth from a few strips of a six-digit file split
/// (its first fit strays by more than the rounding a quarter turn on) — become one surface.
pub(super) fn merge_pieces(
    g: &RegionGraph,
    mesh: &Mesh,
    mut grown: Vec<Grown>,
    tol: f64,
) -> Vec<Grown> {
    let spread = MAX_CHORD_DEVIATION_DEG.to_radians();
    let ruled = |p: &Primitive| matches!(p.kind(), SurfaceKind::Cylinder | SurfaceKind::Cone);
    let parallel = |p: &Primitive, q: &Primitive| match (p.axis(), q.axis()) {
        (Some((_, a)), Some((_, b))) => a.cross(&b).norm() <= 5f64.to_radians().sin(),
        _ => false,
    };
    // Rounds: each surface joins at most one neighbour per round (the pairs a round merges
    // are disjoint), so a band split into n pieces takes about log₂ n rounds, not n restarts.
    loop {
        let n = grown.len();
        let nb = neighbours(g, &grown);
        let mut partner: Vec<Option<(usize, Primitive, Vec<u32>)>> = vec![None; n];
        let mut used = vec![false; n];
        for k in 0..n {
            for &j in nb[k].iter().filter(|&&j| j > k) {
                if used[k] {
                    break;
                }
                let (p, q) = (&grown[k].0, &grown[j].0);
                if used[j] || !(ruled(p) && ruled(q) && p.kind() == q.kind() && parallel(p, q)) {
                    continue;
                }
                let regions: Vec<u32> = grown[k].1.iter().chain(&grown[j].1).copied().collect();
                let pts = points(g, mesh, &regions);
                let normals: Vec<V3> =
                    regions.iter().map(|&r| g.regions.normal[r as usize]).collect();
                let lines: Vec<(V3, V3)> = regions
                    .iter()
                    .map(|&r| (g.centroid[r as usize], g.regions.normal[r as usize]))
                    .collect();
                let fit = best_fit(&pts, &normals, &lines, tol, Kinds::Ruled).filter(|f| {
                    f.kind() == p.kind()
                        && regions.iter().all(|&r| region_on(g, mesh, r, f, tol, spread))
                });
                if let Some(f) = fit {
                    partner[k] = Some((j, f, regions));
                    used[k] = true;
                    used[j] = true;
                }
            }
        }
        if partner.iter().all(Option::is_none) {
            return grown;
        }
        let mut gone = vec![false; n];
        for (k, m) in partner.into_iter().enumerate() {
            if let Some((j, prim, regions)) = m {
                grown[k] = (prim, regions);
                gone[j] = true;
            }
        }
        grown = grown.into_iter().enumerate().filter(|(k, _)| !gone[*k]).map(|(_, p)| p).collect();
    }
}

/// A surface whose every region lies on a neighbouring surface as large or larger is a piece
/// of it that a growth read as its own primitive (a column of a torus's trapezoids, each
/// between two parallels, fits a cylinder along the parallels within a six-digit rounding):
/// it joins the larger one, the smallest pieces first.
pub(super) fn subsume(g: &RegionGraph, mesh: &Mesh, mut grown: Vec<Grown>, tol: f64) -> Vec<Grown> {
    let spread = MAX_CHORD_DEVIATION_DEG.to_radians();
    // Rounds: in each, every piece not itself taking others in joins a neighbour that does
    // not join another (so a round's moves are independent), the smallest pieces first.
    loop {
        let n = grown.len();
        let nb = neighbours(g, &grown);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by_key(|&k| (grown[k].1.len(), k));
        let mut into: Vec<Option<usize>> = vec![None; n];
        let mut takes = vec![false; n];
        for &k in &order {
            if takes[k] {
                continue;
            }
            let rs = &grown[k].1;
            let host = nb[k].iter().copied().find(|&j| {
                into[j].is_none()
                    && grown[j].1.len() >= rs.len()
                    && rs.iter().all(|&r| region_on(g, mesh, r, &grown[j].0, tol, spread))
            });
            if let Some(j) = host {
                into[k] = Some(j);
                takes[j] = true;
            }
        }
        if into.iter().all(Option::is_none) {
            return grown;
        }
        for k in 0..n {
            if let Some(j) = into[k] {
                let piece = std::mem::take(&mut grown[k].1);
                grown[j].1.extend(piece);
            }
        }
        grown = grown
            .into_iter()
            .enumerate()
            .filter(|(k, _)| into[*k].is_none())
            .map(|(_, p)| p)
            .collect();
    }
}

/// Step 3: runs of coaxial bands (cones and cylinders between two rings) whose rings lie on
/// one sphere (three rings or more) or one torus (four or more: a circle through three
/// profile points always exists) become that surface.
pub(super) fn join_bands(g: &RegionGraph, mesh: &Mesh, grown: Vec<Grown>, tol: f64) -> Vec<Grown> {
    let chains = chains(g, mesh, &grown, tol);
    let mut owners = tangent::Owners::new(&grown, g.regions.normal.len());
    let mut merged: Vec<Option<Grown>> = grown.into_iter().map(Some).collect();
    let mut out: Vec<Grown> = Vec::new();
    for chain in chains {
        let axis = chain.iter().find_map(|l| match l {
            Link::Band(k) => merged[*k].as_ref().and_then(|m| m.0.axis()),
            Link::Fan(_) => None,
        });
        let mut i = 0;
        while i < chain.len() {
            let mut best: Option<(usize, Primitive)> = None;
            let link_regions = |l: &Link, merged: &[Option<Grown>]| -> Vec<u32> {
                match l {
                    Link::Band(k) => merged[*k].as_ref().map_or(vec![], |m| m.1.clone()),
                    Link::Fan(f) => f.clone(),
                }
            };
            // The run's regions, grown one link at a time; a link that lies on the surface
            // the run already fits is taken without fitting again (the run stays linear in its
            // regions), any other makes the run fitted afresh.
            let mut regions: Vec<u32> = link_regions(&chain[i], &merged);
            for j in i + 1..chain.len() {
                let run = &chain[i..=j];
                let bands = run.iter().filter(|l| matches!(l, Link::Band(_))).count();
                let rings = bands + 1 + (run.len() - bands);
                let next = link_regions(&chain[j], &merged);
                let spread = MAX_CHORD_DEVIATION_DEG.to_radians();
                let on = best.as_ref().is_some_and(|(_, p)| {
                    next.iter().all(|&r| region_on(g, mesh, r, p, tol, spread))
                });
                regions.extend(next);
                if on {
                    best = best.map(|(_, p)| (j, p));
                    continue;
                }
                match profile_fit(g, mesh, &regions, tol, rings) {
                    Some(p) => best = Some((j, p)),
                    None if rings >= 4 => break,
                    None => {
                        // Three rings fix no circle; a tangent neighbour does (`tangent`).
                        let fit = whole_fit(g, mesh, &regions, tol).filter(|p| {
                            p.kind() == SurfaceKind::Torus
                                && tangent::tangent_to_a_neighbour(g, mesh, &owners, &regions, p)
                        });
                        if let Some(p) = fit {
                            best = Some((j, p));
                        }
                    }
                }
            }
            // A fan alone at the chain's end (a crown of one row): the sphere through its rim
            // and pole, when tangent to its neighbour.
            if let (None, Link::Fan(f), Some(axis)) = (&best, &chain[i], axis) {
                let prim = tangent::fan_sphere(&points(g, mesh, f), axis, tol)
                    .filter(|p| tangent::tangent_to_a_neighbour(g, mesh, &owners, f, p));
                best = prim.map(|p| (i, p));
            }
            match best {
                Some((j, prim)) => {
                    let regions: Vec<u32> = chain[i..=j]
                        .iter()
                        .flat_map(|l| match l {
                            Link::Band(k) => merged[*k].take().map_or(vec![], |m| m.1),
                            Link::Fan(f) => f.clone(),
                        })
                        .collect();
                    owners.assign(&regions, &prim);
                    out.push((prim, regions));
                    i = j + 1;
                }
                None => i += 1,
            }
        }
    }
    out.extend(merged.into_iter().flatten());
    out
}

/// Step 3's chains: coaxial bands in a row along the profile (open, or a closed loop), with the
/// pole's fan at either end as one more link.
fn chains(g: &RegionGraph, mesh: &Mesh, grown: &[Grown], tol: f64) -> Vec<Vec<Link>> {
    let n = grown.len();
    let band: Vec<bool> = grown
        .iter()
        .map(|(p, rs)| {
            let pts = points(g, mesh, rs);
            matches!(p.kind(), SurfaceKind::Cylinder | SurfaceKind::Cone)
                && rings(p, &pts, tol).len() == 2
        })
        .collect();
    let nb = neighbours(g, grown);
    let band_nb = |k: usize| -> Vec<usize> {
        nb[k].iter().copied().filter(|&j| band[j] && coaxial(&grown[k].0, &grown[j].0)).collect()
    };
    // Chains: walk from each band with at most one band neighbour, then from any band left
    // (a closed loop: a full torus's profile, a ring).
    let mut chained = vec![false; n];
    let mut chains: Vec<Vec<usize>> = Vec::new();
    let ends = (0..n).filter(|&k| band[k] && band_nb(k).len() <= 1);
    let loops = (0..n).filter(|&k| band[k]);
    for start in ends.chain(loops) {
        if chained[start] {
            continue;
        }
        let mut chain = vec![start];
        chained[start] = true;
        let mut at = start;
        while let Some(next) = band_nb(at).into_iter().find(|&j| !chained[j]) {
            chained[next] = true;
            chain.push(next);
            at = next;
        }
        chains.push(chain);
    }
    let owned = {
        let mut o = vec![false; g.regions.normal.len()];
        for (_, rs) in grown {
            for &r in rs {
                o[r as usize] = true;
            }
        }
        o
    };
    // A chain that ends at a pole continues into the fan of triangles around it: one more
    // profile point for a sphere (a crown's last band and its fan).
    chains
        .into_iter()
        .map(|chain| {
            let mut links: Vec<Link> = chain.iter().map(|&k| Link::Band(k)).collect();
            if let Some(fan) = pole_fan(g, mesh, &grown[chain[0]], &owned, tol) {
                links.insert(0, Link::Fan(fan));
            }
            let last = chain[chain.len() - 1];
            if chain.len() > 1 || matches!(links[0], Link::Band(_)) {
                if let Some(fan) = pole_fan(g, mesh, &grown[last], &owned, tol) {
                    links.push(Link::Fan(fan));
                }
            }
            links
        })
        .collect()
}

/// An element of a chain of bands: a band (a grown surface) or a pole's fan of triangles.
enum Link {
    Band(usize),
    Fan(Vec<u32>),
}

/// The fan of regions no surface took around a vertex on `band`'s axis next to it (a
/// sphere's pole), if there is one of eight triangles or more.
fn pole_fan(
    g: &RegionGraph,
    mesh: &Mesh,
    (prim, regions): &Grown,
    owned: &[bool],
    tol: f64,
) -> Option<Vec<u32>> {
    let (o, a) = prim.axis()?;
    let mut fan: Vec<u32> = regions
        .iter()
        .flat_map(|&r| g.neighbours(r).iter().map(|&(s, _)| s))
        .filter(|&s| !owned[s as usize] && g.regions.faces[s as usize] == 1)
        .collect();
    fan.sort_unstable();
    fan.dedup();
    if fan.len() < 8 {
        return None;
    }
    let pole = *g.verts(fan[0]).iter().find(|v| fan.iter().all(|&r| g.verts(r).contains(v)))?;
    let p = mesh.positions[pole as usize];
    let off_axis = (p - o).cross(&a).norm();
    (off_axis <= 16.0 * tol).then_some(fan)
}

/// A sphere (three rings or more) or a torus (four or more) through the regions, each of
/// them a chord of it.
fn profile_fit(
    g: &RegionGraph,
    mesh: &Mesh,
    regions: &[u32],
    tol: f64,
    rings: usize,
) -> Option<Primitive> {
    let pts = points(g, mesh, regions);
    let normals: Vec<V3> = regions.iter().map(|&r| g.regions.normal[r as usize]).collect();
    let lines: Vec<(V3, V3)> =
        regions.iter().map(|&r| (g.centroid[r as usize], g.regions.normal[r as usize])).collect();
    let prim = best_fit(&pts, &normals, &lines, tol, Kinds::All)?;
    let enough = match prim {
        Primitive::Sphere { .. } => rings >= 3,
        Primitive::Torus { .. } => rings >= 4,
        _ => false,
    };
    let spread = MAX_CHORD_DEVIATION_DEG.to_radians();
    (enough && regions.iter().all(|&r| region_on(g, mesh, r, &prim, tol, spread))).then_some(prim)
}

/// The least turn between two coaxial surfaces that is a free profile's chord edge, not a
/// tangent junction (degrees): fitted bands agree at a tangent junction to a few hundredths of
/// a degree, and the bands of a gently curved profile exported at ten rows (a vase) turn by
/// 2° or less, below the crease test's [`super::G1_TOLERANCE_DEG`].
const MIN_PROFILE_TURN_DEG: f64 = 0.5;

/// How far a turn between two surfaces may exceed the export's step and still read as a strip
/// edge: the step is measured on fits whose normals the file's rounding tilts.
const STEP_SLACK: f64 = 1.25;

/// The export's angular step on a surface: the largest angle between two of its regions
/// that share an edge, or on a surface of revolution meshed as a turned face the angle
/// between its meridians (360° over the distinct azimuths of its vertices; a band's
/// trapezoids meet at less than that where the surface leans towards its axis), whichever
/// is larger; `None` for a surface of one region.
fn internal_step(
    g: &RegionGraph,
    mesh: &Mesh,
    (prim, regions): &Grown,
    owner: &[u32],
    k: u32,
) -> Option<f64> {
    let dihedral = regions
        .iter()
        .flat_map(|&r| g.neighbours(r).iter().filter(|(s, _)| owner[*s as usize] == k))
        .map(|&(_, angle)| angle)
        .reduce(f64::max)?;
    let azimuth = azimuth_step(prim, &points(g, mesh, regions)).unwrap_or(0.0);
    Some(dihedral.max(azimuth))
}

/// 2π over the number of distinct azimuths of the points about the primitive's axis (rings
/// of a turned face share their azimuths), or `None` for fewer than eight.
fn azimuth_step(prim: &Primitive, points: &[V3]) -> Option<f64> {
    let (o, a) = prim.axis()?;
    let f = crate::geometry::frames::Frame::from_normal(a);
    let mut az: Vec<f64> = points
        .iter()
        .filter_map(|p| {
            let v = p - o;
            let (x, y) = (v.dot(&f.t), v.dot(&f.b));
            (x.hypot(y) > 1e-9 * (x.abs() + y.abs() + v.dot(&a).abs())).then(|| y.atan2(x))
        })
        .collect();
    az.sort_by(f64::total_cmp);
    az.dedup_by(|x, y| (*x - *y).abs() <= 1e-6);
    (az.len() >= 8).then(|| std::f64::consts::TAU / az.len() as f64)
}

/// Adjacent curved surfaces of one kind, tangent to each other, with radii within 5 % and
/// axes within 5° (or centres within 5 % of the radius): no CAD part is built so, but a
/// free-form face whose strips each fit a circle is (a dome's rows of quads, each a
/// cylinder within the file's rounding). Both are a free form.
pub(super) fn twins(g: &RegionGraph, mesh: &Mesh, grown: Vec<Grown>, tol: f64) -> Vec<Grown> {
    let n = grown.len();
    let nb = neighbours(g, &grown);
    let alike = |p: &Primitive, q: &Primitive| {
        if p.kind() != q.kind() {
            return false;
        }
        let close = |a: f64, b: f64| (a - b).abs() <= 0.05 * a.abs().max(b.abs());
        let axes = match (p.axis(), q.axis()) {
            (Some((_, a)), Some((_, b))) => a.cross(&b).norm() <= 5f64.to_radians().sin(),
            _ => true,
        };
        match (*p, *q) {
            (Primitive::Cone { half_angle: a, .. }, Primitive::Cone { half_angle: b, .. }) => {
                axes && close(a, b)
            }
            (
                Primitive::Sphere { center: c, radius: a },
                Primitive::Sphere { center: d, radius: b },
            ) => close(a, b) && (V3::from(c) - V3::from(d)).norm() <= 0.05 * a,
            (
                Primitive::Torus { major: a, minor: r, .. },
                Primitive::Torus { major: b, minor: t, .. },
            ) => axes && close(a, b) && close(r, t),
            _ => axes && close(p.radius(), q.radius()),
        }
    };
    let mut parent: Vec<usize> = (0..n).collect();
    let mut twin = vec![false; n];
    for k in 0..n {
        for &j in &nb[k] {
            if alike(&grown[k].0, &grown[j].0) {
                twin[k] = true;
                twin[j] = true;
                let (a, b) = (root(&mut parent, k), root(&mut parent, j));
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    // A cluster of twins that one torus or sphere passes through is that surface: the
    // columns of a torus's trapezoids at 2° chords, each a prism that fits a cylinder within
    // six digits. (A cluster of cylinders that one cone fits is no CAD face's.)
    let mut clusters: Vec<Vec<usize>> = vec![Vec::new(); n];
    for k in (0..n).filter(|&k| twin[k]) {
        clusters[root(&mut parent, k)].push(k);
    }
    let mut out: Vec<Grown> = Vec::new();
    for members in clusters.iter().filter(|c| c.len() >= 2) {
        let regions: Vec<u32> = members.iter().flat_map(|&k| grown[k].1.iter().copied()).collect();
        let fit = whole_fit(g, mesh, &regions, tol)
            .filter(|p| matches!(p.kind(), SurfaceKind::Torus | SurfaceKind::Sphere));
        if let Some(prim) = fit {
            out.push((prim, regions));
        }
    }
    out.extend(grown.into_iter().enumerate().filter(|(k, _)| !twin[*k]).map(|(_, p)| p));
    out
}

/// Union-find's root of `x`, halving the path.
fn root(p: &mut [usize], mut x: usize) -> usize {
    while p[x] != x {
        p[x] = p[p[x]];
        x = p[x];
    }
    x
}

/// The one primitive of any kind through all of `regions`, each a chord of it.
fn whole_fit(g: &RegionGraph, mesh: &Mesh, regions: &[u32], tol: f64) -> Option<Primitive> {
    let pts = points(g, mesh, regions);
    let normals: Vec<V3> = regions.iter().map(|&r| g.regions.normal[r as usize]).collect();
    let lines: Vec<(V3, V3)> =
        regions.iter().map(|&r| (g.centroid[r as usize], g.regions.normal[r as usize])).collect();
    let prim = best_fit(&pts, &normals, &lines, tol, Kinds::All)?;
    let spread = MAX_CHORD_DEVIATION_DEG.to_radians();
    regions.iter().all(|&r| region_on(g, mesh, r, &prim, tol, spread)).then_some(prim)
}

/// Step 4: coaxial surfaces of revolution that meet at an angle neither tangent nor beyond
/// the export's angular step are a free profile: a chain of three or more of them, and in a
/// chain of two each single band (a cone or a cylinder between two rings).
pub(super) fn free_profiles(
    g: &RegionGraph,
    mesh: &Mesh,
    grown: Vec<Grown>,
    tol: f64,
) -> Vec<Grown> {
    let n = grown.len();
    let mut owner = vec![u32::MAX; g.regions.normal.len()];
    for (k, (_, rs)) in grown.iter().enumerate() {
        for &r in rs {
            owner[r as usize] = k as u32;
        }
    }
    let step: Vec<Option<f64>> =
        (0..n).map(|k| internal_step(g, mesh, &grown[k], &owner, k as u32)).collect();
    let mut parent: Vec<usize> = (0..n).collect();
    let g1 = MIN_PROFILE_TURN_DEG.to_radians();
    let mut tangent: Vec<(usize, usize)> = Vec::new();
    for (k, (pk, rs)) in grown.iter().enumerate() {
        let Some(step_k) = step[k] else { continue };
        for &r in rs {
            for &(s, _) in g.neighbours(r) {
                let j = owner[s as usize] as usize;
                if j >= n || j == k {
                    continue;
                }
                let pj = &grown[j].0;
                let Some(step_j) = step[j] else { continue };
                if !coaxial(pk, pj) {
                    continue;
                }
                // The profile's turn between them: the angle between their normals at a vertex
                // the two regions share.
                let Some(&v) = g.verts(r).iter().find(|v| g.verts(s).binary_search(v).is_ok())
                else {
                    continue;
                };
                let at = mesh.positions[v as usize];
                let turn = pk.normal_at(&at).dot(&pj.normal_at(&at)).clamp(-1.0, 1.0).acos();
                if turn <= g1 {
                    tangent.push((k, j));
                } else if turn <= STEP_SLACK * step_k.max(step_j) {
                    let (a, b) = (root(&mut parent, k), root(&mut parent, j));
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut size = vec![0usize; n];
    for k in 0..n {
        size[root(&mut parent, k)] += 1;
    }
    // A single band (two rings) fixes no profile of its own: next to a face it meets at less
    // than a step, it is a chord of that face's continuation, not a cone.
    let single: Vec<bool> =
        grown.iter().map(|(p, rs)| rings(p, &points(g, mesh, rs), tol).len() == 2).collect();
    // Two single bands alone, though, are two ruled faces meeting at a crease (a skirt and its
    // chamfer exported at 30°): no turn of a profile repeats to call them a free one.
    let mut singles = vec![0usize; n];
    for k in 0..n {
        singles[root(&mut parent, k)] += single[k] as usize;
    }
    let pair_of_singles: Vec<bool> = (0..n).map(|k| size[k] == 2 && singles[k] == 2).collect();
    let mut dropped: Vec<bool> = (0..n)
        .map(|k| {
            let s = size[root(&mut parent, k)];
            !(s == 1 || (s == 2 && (!single[k] || pair_of_singles[root(&mut parent, k)])))
        })
        .collect();
    // A single band that continues a free profile tangentially is its end (a vase's first
    // row, whose turn to the next is below a profile's least).
    let mut changed = true;
    while changed {
        changed = false;
        for &(k, j) in &tangent {
            if single[k] && !dropped[k] && dropped[j] {
                dropped[k] = true;
                changed = true;
            }
        }
    }
    grown.into_iter().enumerate().filter(|(k, _)| !dropped[*k]).map(|(_, p)| p).collect()
}
