//! Spacing measured on the part whatever the UV layout (issue 14, item 1), clean ends and
//! full coverage (item 2), and strokes on every chart (item 3).
//!
//! Every surface is generated here from its closed form, laid out twice (an isometric or
//! least-distorted layout and a strongly non-isometric one, same 3D triangles), and the
//! strokes are measured with code of this file only: UV points are mapped back onto the
//! analytic surface with the inverse of the layout, and distances are taken in the unrolled
//! plane (cylinder, panel) or along great circles (sphere), never with the crate's own
//! spacing code.

mod common;

use std::f64::consts::PI;

use grainline_toolpaths::*;

const D_SEP: f64 = 3.0;

/// A surface for the test: 3D points of the analytic surface for UV points of a layout.
struct Case {
    name: &'static str,
    mesh: FieldMesh,
    /// UV of the layout → a point of the analytic surface in "world" coordinates: the
    /// unrolled plane `(a, z, 0)` for developable surfaces, 3D for the sphere.
    world: Box<dyn Fn(Vec2) -> Vec3>,
    /// Sphere radius when distances are great-circle arcs; `None`: planar distances.
    sphere: Option<f64>,
    /// Coverage sample points (world) with area weights and their distance to the edge.
    samples: Vec<(Vec3, f64, f64)>,
}

fn sub3(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot3(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Distance on the surface from the chord length `c` (sphere: arc of a great circle).
fn arc(c: f64, sphere: Option<f64>) -> f64 {
    match sphere {
        Some(r) => 2.0 * r * (c / (2.0 * r)).min(1.0).asin(),
        None => c,
    }
}

fn seg_dist(p: Vec3, a: Vec3, b: Vec3) -> f64 {
    let ab = sub3(b, a);
    let l2 = dot3(ab, ab);
    let t = if l2 > 0.0 { (dot3(sub3(p, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    let q = [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]];
    dot3(sub3(p, q), sub3(p, q)).sqrt()
}

/// Strokes as world polylines (pieces at seams are not used here), with the fill flag.
/// The polylines the brush follows on the part (run-outs past the edges included: only
/// samples inside the part are measured, so only the brushed band inside counts).
fn world_strokes(case: &Case, pl: &Placement) -> Vec<(Vec<Vec3>, bool)> {
    let line = |s: &Stroke| s.brushed_uv().into_iter().map(|p| (case.world)(p)).collect();
    pl.strokes.iter().map(|s| (line(s), s.fill)).collect()
}

/// A coarse bucket grid over segment bounding boxes for nearest queries (test-side code).
struct Segs {
    segs: Vec<(Vec3, Vec3, usize)>,
    cell: f64,
    map: std::collections::HashMap<[i64; 3], Vec<usize>>,
}

impl Segs {
    fn new(lines: &[(Vec<Vec3>, bool)], keep: impl Fn(bool) -> bool, cell: f64) -> Segs {
        let mut segs = Vec::new();
        for (i, (l, fill)) in lines.iter().enumerate() {
            if keep(*fill) {
                for w in l.windows(2) {
                    segs.push((w[0], w[1], i));
                }
            }
        }
        let mut map: std::collections::HashMap<[i64; 3], Vec<usize>> = Default::default();
        for (k, (a, b, _)) in segs.iter().enumerate() {
            let lo = [0, 1, 2].map(|j| (a[j].min(b[j]) / cell).floor() as i64);
            let hi = [0, 1, 2].map(|j| (a[j].max(b[j]) / cell).floor() as i64);
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        map.entry([x, y, z]).or_default().push(k);
                    }
                }
            }
        }
        Segs { segs, cell, map }
    }

    /// Chord distance from `p` to the nearest segment not of stroke `skip`, up to `r`.
    fn nearest(&self, p: Vec3, skip: usize, r: f64) -> f64 {
        let k = (r / self.cell).ceil() as i64;
        let c = p.map(|x| (x / self.cell).floor() as i64);
        let mut best = r;
        for x in c[0] - k..=c[0] + k {
            for y in c[1] - k..=c[1] + k {
                for z in c[2] - k..=c[2] + k {
                    if let Some(v) = self.map.get(&[x, y, z]) {
                        for &s in v {
                            let (a, b, i) = self.segs[s];
                            if i != skip {
                                best = best.min(seg_dist(p, a, b));
                            }
                        }
                    }
                }
            }
        }
        best
    }
}

/// Figures measured independently: coverage (all, away from the edges), the share of
/// neighbour spacings within ±10 % of d_sep (evenly spaced strokes among themselves,
/// weighted by length), stroke count.
#[derive(Debug, Clone, Copy)]
struct Figures {
    coverage: f64,
    coverage_inner: f64,
    share: f64,
    strokes: usize,
    fills: usize,
}

fn measure(case: &Case, pl: &Placement) -> Figures {
    let lines = world_strokes(case, pl);
    let all = Segs::new(&lines, |_| true, D_SEP);
    let main = Segs::new(&lines, |f| !f, D_SEP);
    let (mut cov, mut tot, mut cov_in, mut tot_in) = (0.0, 0.0, 0.0, 0.0);
    for &(p, w, edge) in &case.samples {
        let d = arc(all.nearest(p, usize::MAX, D_SEP), case.sphere);
        let ok = if d <= 0.5 * D_SEP { w } else { 0.0 };
        cov += ok;
        tot += w;
        if edge > D_SEP {
            cov_in += ok;
            tot_in += w;
        }
    }
    let (mut ok_len, mut len) = (0.0, 0.0);
    for (i, (l, fill)) in lines.iter().enumerate() {
        if *fill {
            continue;
        }
        for k in 0..l.len() {
            let half = |j: usize| 0.5 * dot3(sub3(l[k], l[j]), sub3(l[k], l[j])).sqrt();
            let w = if k > 0 { half(k - 1) } else { 0.0 }
                + if k + 1 < l.len() { half(k + 1) } else { 0.0 };
            let d = arc(main.nearest(l[k], i, 2.0 * D_SEP), case.sphere);
            len += w;
            if (d - D_SEP).abs() <= 0.1 * D_SEP {
                ok_len += w;
            }
        }
    }
    Figures {
        coverage: cov / tot,
        coverage_inner: cov_in / tot_in,
        share: ok_len / len,
        strokes: pl.strokes.len(),
        fills: pl.fill_strokes,
    }
}

/// A grid of `nx × ny` quads over `[x0, x1] × [y0, y1]` of a parameter plane, two triangles
/// each (alternating diagonals).
fn param_grid(x: [f64; 2], y: [f64; 2], nx: usize, ny: usize) -> (Vec<Vec2>, Vec<[u32; 3]>) {
    let (uv, tris) = common::rect_mesh(x[1] - x[0], y[1] - y[0], nx, ny);
    (uv.into_iter().map(|p| [p[0] + x[0], p[1] + y[0]]).collect(), tris)
}

/// Half-cylinder, radius 20, height 60, grain a helix at 20° (surface coordinates `a` =
/// arc length, `z` = height). Warped layout: `u = a`, `v = H ((z + z0)² − z0²) / ((H +
/// z0)² − z0²)`, a power of the (offset) height: the surface length per UV unit along `v`
/// changes 13-fold from bottom to top.
fn half_cylinder(warped: bool) -> Case {
    const R: f64 = 20.0;
    const H: f64 = 60.0;
    const Z0: f64 = 5.0;
    let k = H / ((H + Z0).powi(2) - Z0 * Z0);
    let v_of = move |z: f64| k * ((z + Z0).powi(2) - Z0 * Z0);
    let dv_dz = move |z: f64| 2.0 * k * (z + Z0);
    // Below v = 0 (run-outs past the bottom edge) the layout is continued linearly.
    let z_of = move |v: f64| if v >= 0.0 { (v / k + Z0 * Z0).sqrt() - Z0 } else { v / dv_dz(0.0) };
    let (az, tris) = param_grid([0.0, PI * R], [0.0, H], 96, 90);
    let pos: Vec<Vec3> = az
        .iter()
        .map(|p| {
            let t = p[0] / R;
            [R * t.cos(), R * t.sin(), p[1]]
        })
        .collect();
    let nrm: Vec<Vec3> = pos.iter().map(|p| [p[0] / R, p[1] / R, 0.0]).collect();
    let g = 20f64.to_radians();
    let (uv, dirs): (Vec<Vec2>, Vec<Vec2>) = az
        .iter()
        .map(|p| {
            if warped {
                ([p[0], v_of(p[1])], [g.cos(), g.sin() * dv_dz(p[1])])
            } else {
                (*p, [g.cos(), g.sin()])
            }
        })
        .unzip();
    let mesh = FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Line)
        .with_lift(pos, Some(nrm));
    let world: Box<dyn Fn(Vec2) -> Vec3> = if warped {
        Box::new(move |p: Vec2| [p[0], z_of(p[1]), 0.0])
    } else {
        Box::new(|p: Vec2| [p[0], p[1], 0.0])
    };
    let w = PI * R;
    let samples = planar_samples(w, H, |x, y| x.min(w - x).min(y).min(H - y));
    Case {
        name: if warped { "cylinder warped" } else { "cylinder" },
        mesh,
        world,
        sphere: None,
        samples,
    }
}

/// Sample points on a `w × h` rectangle of the unrolled plane, pitch d_sep / 6.
fn planar_samples(w: f64, h: f64, edge: impl Fn(f64, f64) -> f64) -> Vec<(Vec3, f64, f64)> {
    let pitch = D_SEP / 6.0;
    let (nx, ny) = ((w / pitch) as usize, (h / pitch) as usize);
    let mut out = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = ((i as f64 + 0.5) * w / nx as f64, (j as f64 + 0.5) * h / ny as f64);
            out.push(([x, y, 0.0], 1.0, edge(x, y)));
        }
    }
    out
}

/// Sphere band, radius 30, longitude ±45°, latitude ±60°, grain along the circles about
/// the axis through longitude 90° (parallel curves: their geodesic spacing is constant).
/// Layouts: latitude–longitude `(R lon, R lat)` (parallels stretched by 1 / cos lat, up to
/// 2:1) or the sinusoidal `(R lon cos lat, R lat)` (true lengths along every parallel).
fn sphere_band(latlong: bool) -> Case {
    const R: f64 = 30.0;
    let (lon_max, lat_max) = (45f64.to_radians(), 60f64.to_radians());
    let (ll, tris) = param_grid([-lon_max, lon_max], [-lat_max, lat_max], 60, 80);
    let x_of =
        |lon: f64, lat: f64| [R * lat.cos() * lon.cos(), R * lat.cos() * lon.sin(), R * lat.sin()];
    let pos: Vec<Vec3> = ll.iter().map(|p| x_of(p[0], p[1])).collect();
    let nrm: Vec<Vec3> = pos.iter().map(|p| p.map(|c| c / R)).collect();
    let (uv, dirs): (Vec<Vec2>, Vec<Vec2>) = ll
        .iter()
        .zip(&pos)
        .map(|(p, x)| {
            let (lon, lat) = (p[0], p[1]);
            // Tangent of the circles about a = (0, 1, 0): a × x = (x_z, 0, −x_x).
            let t = [x[2], 0.0, -x[0]];
            let x_lon = [-R * lat.cos() * lon.sin(), R * lat.cos() * lon.cos(), 0.0];
            let x_lat = [-R * lat.sin() * lon.cos(), -R * lat.sin() * lon.sin(), R * lat.cos()];
            let dlon = dot3(t, x_lon) / dot3(x_lon, x_lon);
            let dlat = dot3(t, x_lat) / dot3(x_lat, x_lat);
            if latlong {
                ([R * lon, R * lat], [R * dlon, R * dlat])
            } else {
                (
                    [R * lon * lat.cos(), R * lat],
                    [R * lat.cos() * dlon - R * lon * lat.sin() * dlat, R * dlat],
                )
            }
        })
        .unzip();
    let mesh = FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Line)
        .with_lift(pos, Some(nrm));
    let world: Box<dyn Fn(Vec2) -> Vec3> = if latlong {
        Box::new(move |p: Vec2| x_of(p[0] / R, p[1] / R))
    } else {
        Box::new(move |p: Vec2| {
            let lat = p[1] / R;
            x_of(p[0] / (R * lat.cos()), lat)
        })
    };
    // Samples uniform in (lon, lat), weighted by the area element cos lat.
    let (nx, ny) = (180, 240);
    let mut samples = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let lon = -lon_max + (i as f64 + 0.5) * 2.0 * lon_max / nx as f64;
            let lat = -lat_max + (j as f64 + 0.5) * 2.0 * lat_max / ny as f64;
            let to_lat = R * (lat_max - lat.abs());
            let to_lon = R * (lat.cos() * (lon_max - lon.abs()).sin()).asin();
            samples.push((x_of(lon, lat), lat.cos(), to_lat.min(to_lon)));
        }
    }
    Case {
        name: if latlong { "sphere lat-long" } else { "sphere sinusoidal" },
        mesh,
        world,
        sphere: Some(R),
        samples,
    }
}

/// Flat 60 × 40 panel, grain at 30°. Warped layout: `u = x`, `v = y (1 + c (x/W)² (y/H)²)`,
/// `c = 2/3`: `∂v/∂y` grows from 1 to 3 towards the corner (W, H), with shear `∂v/∂x` up to
/// 0.9 there.
fn panel(warped: bool) -> Case {
    const W: f64 = 60.0;
    const H: f64 = 40.0;
    const C: f64 = 2.0 / 3.0;
    let (xy, tris) = param_grid([0.0, W], [0.0, H], 90, 60);
    let pos: Vec<Vec3> = xy.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let nrm = vec![[0.0, 0.0, 1.0]; pos.len()];
    let g = 30f64.to_radians();
    let t = [g.cos(), g.sin()];
    let (uv, dirs): (Vec<Vec2>, Vec<Vec2>) = xy
        .iter()
        .map(|p| {
            let (x, y) = (p[0], p[1]);
            if warped {
                let q = C * (x / W).powi(2) / (H * H);
                let v = y * (1.0 + q * y * y);
                let dv_dx = 2.0 * C * x * y.powi(3) / (W * W * H * H);
                let dv_dy = 1.0 + 3.0 * q * y * y;
                ([x, v], [t[0], dv_dx * t[0] + dv_dy * t[1]])
            } else {
                (*p, t)
            }
        })
        .unzip();
    let mesh = FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Line)
        .with_lift(pos, Some(nrm));
    let world: Box<dyn Fn(Vec2) -> Vec3> = if warped {
        Box::new(|p: Vec2| {
            // Solve y + q y³ = v by Newton from y = v (monotone, converges quickly).
            let q = C * (p[0] / W).powi(2) / (H * H);
            let mut y = p[1];
            for _ in 0..50 {
                y -= (y + q * y.powi(3) - p[1]) / (1.0 + 3.0 * q * y * y);
            }
            [p[0], y, 0.0]
        })
    } else {
        Box::new(|p: Vec2| [p[0], p[1], 0.0])
    };
    let samples = planar_samples(W, H, |x, y| x.min(W - x).min(y).min(H - y));
    Case { name: if warped { "panel warped" } else { "panel" }, mesh, world, sphere: None, samples }
}

fn run(case: &Case) -> Figures {
    let dom = Domain::new(case.mesh.clone()).unwrap();
    let pl = place_strokes(&dom, &PlacementOptions::new(D_SEP, 0.0)).unwrap();
    let f = measure(case, &pl);
    eprintln!(
        "{:<18} strokes {:>3} (fill {:>2}, dropped {:>2})  coverage {:.2}% (inner {:.2}%)  \
         spacing within ±10%: {:.2}%",
        case.name,
        f.strokes,
        f.fills,
        pl.dropped_short,
        100.0 * f.coverage,
        100.0 * f.coverage_inner,
        100.0 * f.share
    );
    f
}

fn check_pair(iso: Case, warped: Case) {
    let a = run(&iso);
    let b = run(&warped);
    for (c, f) in [(&iso, a), (&warped, b)] {
        assert!(f.coverage >= 0.98, "{}: coverage {:.4}", c.name, f.coverage);
        assert!(f.coverage_inner >= 0.99, "{}: inner coverage {:.4}", c.name, f.coverage_inner);
        assert!(f.share >= 0.95, "{}: spacing share {:.4}", c.name, f.share);
    }
    assert!((a.coverage - b.coverage).abs() <= 0.01, "coverage {a:?} vs {b:?}");
    assert!((a.coverage_inner - b.coverage_inner).abs() <= 0.01, "inner {a:?} vs {b:?}");
    assert!((a.share - b.share).abs() <= 0.01, "share {a:?} vs {b:?}");
}

#[test]
fn half_cylinder_power_law_layout_matches_isometric() {
    check_pair(half_cylinder(false), half_cylinder(true));
}

#[test]
fn sphere_band_latlong_matches_sinusoidal() {
    check_pair(sphere_band(false), sphere_band(true));
}

#[test]
fn panel_stretched_in_one_corner_matches_isometric() {
    check_pair(panel(false), panel(true));
}

/// The measurement above can fail: with spacing measured in UV the warped cylinder's
/// strokes are badly spaced on the part (a control for the figures, not a requirement).
#[test]
fn uv_spacing_on_the_warped_cylinder_fails_the_figures() {
    let case = half_cylinder(true);
    let dom = Domain::new(case.mesh.clone()).unwrap();
    let opts = PlacementOptions { spacing: Spacing::Uv, ..PlacementOptions::new(D_SEP, 0.0) };
    let f = measure(&case, &place_strokes(&dom, &opts).unwrap());
    eprintln!("UV spacing on the warped cylinder: {f:?}");
    assert!(f.share < 0.8, "{f:?}");
}

// ---------------------------------------------------------------------------------------
// Item 2: clean ends and full coverage.

/// Coverage of a flat domain, measured at the area-weighted centroids of a fine sampling
/// of its triangles (each triangle split 4 × 4), planar distances to the stroke polylines.
fn flat_coverage(uv: &[Vec2], tris: &[[u32; 3]], pl: &Placement) -> f64 {
    let lines: Vec<(Vec<Vec3>, bool)> = pl
        .strokes
        .iter()
        .map(|s| (s.brushed_uv().iter().map(|p| [p[0], p[1], 0.0]).collect(), s.fill))
        .collect();
    let segs = Segs::new(&lines, |_| true, D_SEP);
    let (mut cov, mut tot) = (0.0, 0.0);
    let n = 4;
    for t in tris {
        let [a, b, c] = t.map(|v| uv[v as usize]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
        for i in 0..n {
            for j in 0..n - i {
                // Centroids of the upward sub-triangles of an n-subdivision (weights equal).
                let (s, r) = ((i as f64 + 1.0 / 3.0) / n as f64, (j as f64 + 1.0 / 3.0) / n as f64);
                let p = [
                    a[0] + s * (b[0] - a[0]) + r * (c[0] - a[0]),
                    a[1] + s * (b[1] - a[1]) + r * (c[1] - a[1]),
                    0.0,
                ];
                let w = area;
                tot += w;
                if segs.nearest(p, usize::MAX, D_SEP) <= 0.5 * D_SEP {
                    cov += w;
                }
            }
        }
    }
    cov / tot
}

/// A disk of radius 30 with three holes, cut from a 0.5 mm grid (triangles whose centroid
/// is inside), no lift (flat sheet).
fn disk_with_holes() -> (Vec<Vec2>, Vec<[u32; 3]>) {
    let (uv, tris) = param_grid([-30.0, 30.0], [-30.0, 30.0], 120, 120);
    let holes = [([-12.0, 0.0], 6.0), ([10.0, 8.0], 5.0), ([6.0, -14.0], 4.0)];
    let inside = |p: Vec2| {
        p[0].hypot(p[1]) < 30.0 && holes.iter().all(|(c, r)| (p[0] - c[0]).hypot(p[1] - c[1]) > *r)
    };
    let kept: Vec<[u32; 3]> = tris
        .into_iter()
        .filter(|t| {
            let c = [0, 1].map(|k| t.iter().map(|&v| uv[v as usize][k]).sum::<f64>() / 3.0);
            inside(c)
        })
        .collect();
    // Drop unused vertices (not needed by the crate, but keeps the mesh honest).
    let mut map = vec![u32::MAX; uv.len()];
    let mut out = Vec::new();
    let tris = kept
        .iter()
        .map(|t| {
            t.map(|v| {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = out.len() as u32;
                    out.push(uv[v as usize]);
                }
                map[v as usize]
            })
        })
        .collect();
    (out, tris)
}

#[test]
fn rectangle_disk_with_holes_and_half_cylinder_are_covered() {
    // Rectangle 40 × 30, grain turning slowly (strokes fan out): acute corners at both ends.
    let (uv, tris) = common::rect_mesh(40.0, 30.0, 80, 60);
    let rect = common::field_mesh((uv.clone(), tris.clone()), Symmetry::Line, |p| {
        let a = 0.5 + 0.012 * p[0];
        [a.cos(), a.sin()]
    });
    let dom = Domain::new(rect).unwrap();
    let opts = PlacementOptions::new(D_SEP, 0.0);
    let pl = place_strokes(&dom, &opts).unwrap();
    let c = flat_coverage(&uv, &tris, &pl);
    eprintln!(
        "rectangle: coverage {:.2}%, {} strokes ({} fill), {} dropped",
        100.0 * c,
        pl.strokes.len(),
        pl.fill_strokes,
        pl.dropped_short
    );
    // Issue 31, item 3 (no dabs): coverage at least as before (99.45 %, 17 strokes of which 2
    // were corner pieces shorter than 2 w) and no dab (see `no_dabs`).
    assert!(c >= 0.9945, "rectangle coverage {c}");
    // Short strokes are dropped by default (min_length = 2 × width) and counted; 0 keeps all.
    assert_eq!(pl.min_length, 2.0 * D_SEP);
    no_dabs("rectangle", &pl, true);
    let keep =
        place_strokes(&dom, &PlacementOptions { min_length: Some(0.0), ..opts.clone() }).unwrap();
    assert_eq!(keep.dropped_short, 0);
    assert!(pl.dropped_short > 0 && keep.strokes.iter().any(|s| s.length < 2.0 * D_SEP));

    let (uv, tris) = disk_with_holes();
    let disk = common::field_mesh((uv.clone(), tris.clone()), Symmetry::Line, |p| {
        [1.0, 0.25 * (p[1] / 9.0).sin()]
    });
    let dom = Domain::new(disk).unwrap();
    let pl = place_strokes(&dom, &opts).unwrap();
    let c = flat_coverage(&uv, &tris, &pl);
    eprintln!(
        "disk with holes: coverage {:.2}%, {} strokes ({} fill), {} dropped",
        100.0 * c,
        pl.strokes.len(),
        pl.fill_strokes,
        pl.dropped_short
    );
    // Before: 99.16 %, 53 strokes of which 6 shorter than 2 w.
    assert!(c >= 0.9916, "disk coverage {c}");
    no_dabs("disk with holes", &pl, true);

    for warped in [false, true] {
        let case = half_cylinder(warped);
        let f = run(&case);
        // Before: 99.76 % (isometric), 99.67 % (warped); 10 of 35 strokes shorter than 2 w.
        assert!(f.coverage >= 0.9967, "{}: {f:?}", case.name);
        let dom = Domain::new(case.mesh.clone()).unwrap();
        no_dabs(case.name, &place_strokes(&dom, &opts).unwrap(), false);
    }
}

/// Issue 31, item 3, no dabs (eq. D1 in place.rs): a stroke that plunges or lifts off on the
/// metal (an end inside the part) lies on the part for at least 2 w; one that runs in from past
/// the part's edge and out past it again (run-outs at both ends: no mark on the metal) is
/// brushed over at least 2 w in all and lies on the part for at least w. Run-outs are at the
/// ends on the edge, and nowhere else; on a flat layout (`flat`: UV in mm) each is w long.
fn no_dabs(name: &str, pl: &Placement, flat: bool) {
    let w = D_SEP;
    let through = |s: &Stroke| s.run_out[0].is_some() && s.run_out[1].is_some();
    let dab = |s: &&Stroke| {
        let brushed = s.length + s.overtravel[0] + s.overtravel[1];
        if through(s) {
            brushed < 2.0 * w - 1e-9 || s.length < w
        } else {
            s.length < 2.0 * w - 1e-9
        }
    };
    let dabs: Vec<f64> = pl.strokes.iter().filter(dab).map(|s| s.length).collect();
    let shortest = |f: &dyn Fn(&Stroke) -> bool| {
        pl.strokes.iter().filter(|s| f(s)).map(|s| s.length).fold(f64::INFINITY, f64::min)
    };
    eprintln!(
        "{name}: shortest stroke on the part {:.2} mm, of those ending on the metal {:.2} mm \
         ({} of {} run from past the edge to past the edge); dabs {dabs:?}",
        shortest(&|_| true),
        shortest(&|s| !through(s)),
        pl.strokes.iter().filter(|s| through(s)).count(),
        pl.strokes.len()
    );
    assert!(dabs.is_empty(), "{name}: dabs (lengths on the part): {dabs:?}");
    for s in &pl.strokes {
        let n = s.uv.len();
        for (k, end) in [(0, s.uv[0]), (1, s.uv[n - 1])] {
            let stop = if k == 0 { s.start } else { s.end };
            assert_eq!(s.run_out[k].is_some(), stop == StopReason::Boundary && !s.is_closed());
            if let (Some(q), true) = (s.run_out[k], flat) {
                let len = (q[0] - end[0]).hypot(q[1] - end[1]);
                assert!((len - w).abs() < 1e-9, "{name}: run-out {len} mm");
            }
        }
    }
}

/// The whole job on the disk with holes: the report counts the dropped strokes and the
/// fill strokes, and the G-code passes LinuxCNC's interpreter.
#[test]
fn disk_with_holes_job_report_and_gcode() {
    let (uv, tris) = disk_with_holes();
    let mesh = common::field_mesh((uv, tris), Symmetry::Line, |p| [1.0, 0.25 * (p[1] / 9.0).sin()]);
    let opts = JobOptions {
        placement: PlacementOptions::new(D_SEP, 0.0),
        plan: PlanOptions {
            lead_in: 1.0,
            lead_out: 1.0,
            ramp_height: 1.0,
            overtravel: 1.0,
            ..Default::default()
        },
        coverage: Some(CoverageOptions::default()),
        gcode: Some(GcodeOptions::default()),
        ..Default::default()
    };
    let out = generate(mesh, &opts).unwrap();
    let r = &out.report;
    assert_eq!(r.min_length, 2.0 * D_SEP);
    assert_eq!(r.dropped_short, out.placement.dropped_short);
    assert_eq!(r.fill_strokes, out.placement.strokes.iter().filter(|s| s.fill).count());
    assert_eq!((r.charts, r.charts_with_strokes), (1, 1));
    let cov = r.coverage.as_ref().unwrap();
    assert!(!cov.largest_gap_capped);
    let Some(tool) = common::shared_tool("check-gcode") else { return };
    let dir = common::scratch("any-layout-disk");
    let path = dir.join("disk.ngc");
    std::fs::write(&path, out.gcode.unwrap()).unwrap();
    let (ok, text) = common::run_tool(&tool, &[&path]);
    assert!(ok, "{text}");
}

/// A single short stroke on a large sheet: the largest gap reaches the cap and says so.
#[test]
fn capped_largest_gap_is_flagged() {
    let mesh =
        common::field_mesh(common::rect_mesh(60.0, 60.0, 30, 30), Symmetry::Line, |_| [0.0, 1.0]);
    let dom = Domain::new(mesh).unwrap();
    let mut pl = place_strokes(&dom, &PlacementOptions::new(1.0, 0.0)).unwrap();
    pl.strokes.truncate(1);
    let cov = coverage(&dom, &pl, &CoverageOptions::default()).unwrap();
    assert!(cov.largest_gap_capped);
    assert!((cov.largest_gap - 8.0 * pl.d_sep).abs() < 1e-6, "{}", cov.largest_gap);
    let all = place_strokes(&dom, &PlacementOptions::new(1.0, 0.0)).unwrap();
    let cov = coverage(&dom, &all, &CoverageOptions::default()).unwrap();
    assert!(!cov.largest_gap_capped);
}

// ---------------------------------------------------------------------------------------
// Item 3: every chart gets strokes, mirrored and overlapping charts included.

/// Three 30 × 20 mm flat pieces of a part. Chart A: UV = (x, y). Chart B: mirrored, UV =
/// (30 − x, y), exactly over A. Chart C: UV = (x + 10, y + 5), overlapping A. On the part
/// they lie apart: A at the origin, B at x + 40, C at y + 40 (z = 0). Grain at 25° on the
/// part.
/// UV of a chart → a point on the part.
type ToPart = Box<dyn Fn(Vec2) -> Vec3>;
/// How a chart is laid out: part → UV, part → 3D, part direction → UV direction.
type Layout = (fn(Vec2) -> Vec2, fn(Vec2) -> Vec3, fn(Vec2) -> Vec2);

fn three_charts(lift: bool) -> (FieldMesh, [ToPart; 3]) {
    let (g, t) = common::rect_mesh(30.0, 20.0, 45, 30);
    let a = 25f64.to_radians();
    let d = [a.cos(), a.sin()];
    let (mut uv, mut tris, mut pos, mut dirs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let charts: [Layout; 3] = [
        (|p| p, |p| [p[0], p[1], 0.0], |d| d),
        (|p| [30.0 - p[0], p[1]], |p| [p[0] + 40.0, p[1], 0.0], |d| [-d[0], d[1]]),
        (|p| [p[0] + 10.0, p[1] + 5.0], |p| [p[0], p[1] + 40.0, 0.0], |d| d),
    ];
    for (to_uv, to_3d, dir) in charts {
        let base = uv.len() as u32;
        uv.extend(g.iter().map(|&p| to_uv(p)));
        pos.extend(g.iter().map(|&p| to_3d(p)));
        dirs.extend(g.iter().map(|_| dir(d)));
        tris.extend(t.iter().map(|tr| tr.map(|v| v + base)));
    }
    let mut mesh = FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Line);
    if lift {
        let n = pos.len();
        mesh = mesh.with_lift(pos, Some(vec![[0.0, 0.0, 1.0]; n]));
    }
    // Inverse maps: UV of each chart → the part.
    let back: [ToPart; 3] = [
        Box::new(|p| [p[0], p[1], 0.0]),
        Box::new(|p| [30.0 - p[0] + 40.0, p[1], 0.0]),
        Box::new(|p| [p[0] - 10.0, p[1] - 5.0 + 40.0, 0.0]),
    ];
    (mesh, back)
}

/// A 3D stroke on a flat part continued straight by its run-outs past the chart edges.
fn with_run_outs(l: &[Vec3], s: &Stroke) -> Vec<Vec3> {
    let run = |a: Vec3, b: Vec3, len: f64| {
        let t = sub3(b, a);
        let n = dot3(t, t).sqrt();
        [0, 1, 2].map(|k| b[k] + t[k] * len / n)
    };
    let mut out = l.to_vec();
    if s.run_out[0].is_some() && l.len() > 1 {
        out.insert(0, run(l[1], l[0], s.overtravel[0]));
    }
    if s.run_out[1].is_some() && l.len() > 1 {
        out.push(run(l[l.len() - 2], l[l.len() - 1], s.overtravel[1]));
    }
    out
}

#[test]
fn mirrored_and_overlapping_charts_all_get_strokes() {
    // On the part (lift): strokes are measured in 3D from the job's lifted strokes.
    let (mesh, _) = three_charts(true);
    let dom = Domain::new(mesh.clone()).unwrap();
    assert_eq!(dom.chart_count(), 3);
    assert_eq!(dom.overlapping_charts(), vec![(0, 1), (0, 2), (1, 2)]);
    let opts = JobOptions { placement: PlacementOptions::new(D_SEP, 0.0), ..Default::default() };
    let out = generate(mesh, &opts).unwrap();
    assert_eq!(out.report.charts_with_strokes, 3);
    let lines: Vec<(Vec<Vec3>, bool)> = out
        .strokes_3d
        .iter()
        .zip(&out.placement.strokes)
        .map(|(l, s)| (with_run_outs(l, s), s.fill))
        .collect();
    let segs = Segs::new(&lines, |_| true, D_SEP);
    for (k, origin) in [[0.0, 0.0], [40.0, 0.0], [0.0, 40.0]].iter().enumerate() {
        let (mut cov, mut tot) = (0.0, 0.0);
        for (p, w, _) in planar_samples(30.0, 20.0, |_, _| 0.0) {
            let q = [p[0] + origin[0], p[1] + origin[1], 0.0];
            tot += w;
            if segs.nearest(q, usize::MAX, D_SEP) <= 0.5 * D_SEP {
                cov += w;
            }
        }
        eprintln!("chart {k} (lift): coverage {:.2}%", 100.0 * cov / tot);
        assert!(cov / tot >= 0.98, "chart {k}: coverage {}", cov / tot);
    }

    // A flat sheet job (no lift): each overlapping chart is its own sheet, with its own
    // SVG layer and a pause between sheets in one G-code program.
    let (mesh, back) = three_charts(false);
    let opts = JobOptions {
        placement: PlacementOptions::new(D_SEP, 0.0),
        coverage: Some(CoverageOptions::default()),
        svg: Some(SvgOptions::default()),
        gcode: Some(GcodeOptions::default()),
        ..Default::default()
    };
    let out = generate(mesh, &opts).unwrap();
    assert_eq!(out.report.charts_with_strokes, 3);
    let sheets: std::collections::BTreeSet<usize> =
        out.plan.passes.iter().map(|p| p.sheet).collect();
    assert_eq!(sheets.into_iter().collect::<Vec<_>>(), vec![0, 1, 2]);
    assert!(out.plan.passes.windows(2).all(|w| w[0].sheet <= w[1].sheet));
    let svg = out.svg.unwrap();
    assert!(svg.contains("id=\"strokes\"") && svg.contains("strokes-sheet-2"));
    let gcode = out.gcode.unwrap();
    assert_eq!(gcode.lines().filter(|l| l.trim() == "M0").count(), 2);
    // Per chart, on the part: each pass belongs to one sheet = one chart here.
    for (k, map) in back.iter().enumerate() {
        let lines: Vec<(Vec<Vec3>, bool)> = out
            .plan
            .passes
            .iter()
            .filter(|p| p.sheet == k)
            .flat_map(|p| p.uv.iter().map(|l| (l.iter().map(|&q| map(q)).collect(), false)))
            .collect();
        let segs = Segs::new(&lines, |_| true, D_SEP);
        let origin = [[0.0, 0.0], [40.0, 0.0], [0.0, 40.0]][k];
        let (mut cov, mut tot) = (0.0, 0.0);
        for (p, w, _) in planar_samples(30.0, 20.0, |_, _| 0.0) {
            let q = [p[0] + origin[0], p[1] + origin[1], 0.0];
            tot += w;
            if segs.nearest(q, usize::MAX, D_SEP) <= 0.5 * D_SEP {
                cov += w;
            }
        }
        eprintln!("chart {k} (flat): coverage {:.2}%", 100.0 * cov / tot);
        assert!(cov / tot >= 0.98, "chart {k}: coverage {}", cov / tot);
    }
    let Some(tool) = common::shared_tool("check-gcode") else { return };
    let dir = common::scratch("any-layout-sheets");
    let path = dir.join("sheets.ngc");
    std::fs::write(&path, gcode).unwrap();
    let (ok, text) = common::run_tool(&tool, &[&path]);
    assert!(ok, "{text}");
}

/// Two faces of a part laid side by side (a 30 × 20 and a 20 × 20 mm chart, 10 mm apart in
/// U, no overlap) with the grain along U: by default one sheet; with `plan.sheets: chart` each
/// face is a sheet of its own, cut whole before the next, its own SVG layer, and one `M0`
/// between the two in the G-code, which rs274 accepts.
#[test]
fn sheets_chart_cuts_each_chart_as_its_own_sheet() {
    let (mut uv, mut tris) = (Vec::new(), Vec::new());
    for (w, u0) in [(30.0, 0.0), (20.0, 40.0)] {
        let (g, t) = common::rect_mesh(w, 20.0, 30, 20);
        let base = uv.len() as u32;
        uv.extend(g.iter().map(|p| [p[0] + u0, p[1]]));
        tris.extend(t.iter().map(|tr| tr.map(|v| v + base)));
    }
    let n = uv.len();
    let mesh = FieldMesh::new(uv, tris, Directions::Vectors(vec![[1.0, 0.0]; n]), Symmetry::Line);
    let job = |sheets: Sheets| JobOptions {
        placement: PlacementOptions::new(2.0, 0.0),
        plan: PlanOptions { sheets, ..Default::default() },
        svg: Some(SvgOptions::default()),
        gcode: Some(GcodeOptions::default()),
        ..Default::default()
    };
    let one = generate(mesh.clone(), &job(Sheets::Overlap)).unwrap();
    assert!(one.plan.passes.iter().all(|p| p.sheet == 0));
    assert_eq!(one.gcode.unwrap().lines().filter(|l| l.trim() == "M0").count(), 0);
    let out = generate(mesh, &job(Sheets::Chart)).unwrap();
    assert_eq!(out.report.charts_with_strokes, 2);
    // Sheets in order, each pass on its own chart: sheet 0 at u < 30, sheet 1 at u > 40.
    assert!(out.plan.passes.windows(2).all(|w| w[0].sheet <= w[1].sheet));
    for p in &out.plan.passes {
        let on_first = p.uv.iter().flatten().all(|q| q[0] <= 30.0 + 1e-9);
        let on_second = p.uv.iter().flatten().all(|q| q[0] >= 40.0 - 1e-9);
        assert!(
            if p.sheet == 0 { on_first } else { p.sheet == 1 && on_second },
            "sheet {}",
            p.sheet
        );
    }
    assert!(out.plan.passes.iter().any(|p| p.sheet == 1));
    let svg = out.svg.unwrap();
    assert!(svg.contains("id=\"strokes\"") && svg.contains("strokes-sheet-1"));
    assert!(!svg.contains("strokes-sheet-2"));
    let gcode = out.gcode.unwrap();
    assert_eq!(gcode.lines().filter(|l| l.trim() == "M0").count(), 1);
    let Some(tool) = common::shared_tool("check-gcode") else { return };
    let dir = common::scratch("any-layout-chart-sheets");
    let path = dir.join("sheets.ngc");
    std::fs::write(&path, gcode).unwrap();
    let (ok, text) = common::run_tool(&tool, &[&path]);
    assert!(ok, "{text}");
}
