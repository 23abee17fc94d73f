//! Test meshes and helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use grainline_toolpaths::{Directions, FieldMesh, Symmetry, Vec2};

/// A `w × h` rectangle at the origin split into `nx × ny` quads of two triangles, the
/// diagonal alternating so the mesh has no preferred direction.
pub fn rect_mesh(w: f64, h: f64, nx: usize, ny: usize) -> (Vec<Vec2>, Vec<[u32; 3]>) {
    let mut uv = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            uv.push([w * i as f64 / nx as f64, h * j as f64 / ny as f64]);
        }
    }
    let mut tris = Vec::new();
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            } else {
                tris.push([a, b, d]);
                tris.push([b, c, d]);
            }
        }
    }
    (uv, tris)
}

/// An annulus `r0 ≤ r ≤ r1` about the origin, `nr` rings by `nt` sectors.
pub fn annulus_mesh(r0: f64, r1: f64, nr: usize, nt: usize) -> (Vec<Vec2>, Vec<[u32; 3]>) {
    let mut uv = Vec::new();
    for j in 0..=nr {
        let r = r0 + (r1 - r0) * j as f64 / nr as f64;
        for i in 0..nt {
            let t = 2.0 * std::f64::consts::PI * i as f64 / nt as f64;
            uv.push([r * t.cos(), r * t.sin()]);
        }
    }
    let id = |i: usize, j: usize| (j * nt + i % nt) as u32;
    let mut tris = Vec::new();
    for j in 0..nr {
        for i in 0..nt {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (uv, tris)
}

/// A field mesh with directions from `f(uv)`.
pub fn field_mesh(
    (uv, tris): (Vec<Vec2>, Vec<[u32; 3]>),
    sym: Symmetry,
    f: impl Fn(Vec2) -> Vec2,
) -> FieldMesh {
    let d = uv.iter().map(|&p| f(p)).collect();
    FieldMesh::new(uv, tris, Directions::Vectors(d), sym)
}

/// `<workspace>/../shared/tools/NAME`, or `None` (with a skip message) when absent.
pub fn shared_tool(name: &str) -> Option<PathBuf> {
    // GRAINLINE_SHARED overrides the location (a worktree placed elsewhere).
    let shared = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared"));
    let p = shared.join("tools").join(name);
    if p.exists() {
        if name == "check-gcode" {
            ensure_rs274(&p);
        }
        Some(p)
    } else {
        eprintln!("skipping: {} not found (../shared absent)", p.display());
        None
    }
}

/// A fresh scratch directory under the target dir.
pub fn scratch(name: &str) -> PathBuf {
    let base = std::env::var_os("CARGO_TARGET_TMPDIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir)
        .join("grainline-toolpaths-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).expect("create scratch dir");
    base
}

/// Run a shared tool on files; returns (success, stdout).
///
/// A checker that *crashed* (LinuxCNC's rs274 died once of a bus error in about ten runs of
/// the suite here, on a program it accepts every other time) has given no verdict: the run is
/// tried again, at most twice, and the crash is printed. A rejection is never retried.
pub fn run_tool(tool: &std::path::Path, args: &[&std::path::Path]) -> (bool, String) {
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    rs274::run_checker(tool, &args)
}

/// A canonical move read back from rs274's output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Canon {
    /// G0 to (x, y, z).
    Traverse([f64; 3]),
    /// G1/G2/G3 ending at (x, y, z) with the feed rate in force.
    Feed([f64; 3], f64),
}

/// Parse an rs274 `.canon` file into moves.
pub fn parse_canon(text: &str) -> Vec<Canon> {
    let mut feed = 0.0;
    let mut out = Vec::new();
    let args = |l: &str| -> Vec<f64> {
        let a = &l[l.find('(').unwrap() + 1..l.rfind(')').unwrap()];
        a.split(',').filter_map(|x| x.trim().parse().ok()).collect()
    };
    for line in text.lines() {
        if line.contains("SET_FEED_RATE(") {
            feed = args(line)[0];
        } else if line.contains("STRAIGHT_TRAVERSE(") {
            let a = args(line);
            out.push(Canon::Traverse([a[0], a[1], a[2]]));
        } else if line.contains("STRAIGHT_FEED(") {
            let a = args(line);
            out.push(Canon::Feed([a[0], a[1], a[2]], feed));
        } else if line.contains("ARC_FEED(") {
            // ARC_FEED(end1, end2, c1, c2, turn, end3, ...) in the XY plane.
            let a = args(line);
            out.push(Canon::Feed([a[0], a[1], a[5]], feed));
        }
    }
    out
}

/// A canonical move with its arc geometry, read back from rs274's output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CanonMove {
    /// G0 to (x, y, z).
    Traverse([f64; 3]),
    /// G1 to (x, y, z) at a feed.
    Line([f64; 3], f64),
    /// G2/G3 in the XY plane to (x, y, z) about (cx, cy); `ccw` for G3.
    Arc { end: [f64; 3], center: [f64; 2], ccw: bool, feed: f64 },
}

/// Parse an rs274 `.canon` file into moves with arc centres and the length unit it
/// reports (`true` when `USE_LENGTH_UNITS(CANON_UNITS_MM)` was the last unit set).
pub fn parse_canon_moves(text: &str) -> (Vec<CanonMove>, bool) {
    let mut feed = 0.0;
    let mut mm = true;
    let mut out = Vec::new();
    let args = |l: &str| -> Vec<f64> {
        let a = &l[l.find('(').unwrap() + 1..l.rfind(')').unwrap()];
        a.split(',').filter_map(|x| x.trim().parse().ok()).collect()
    };
    for line in text.lines() {
        if line.contains("USE_LENGTH_UNITS(") {
            mm = line.contains("CANON_UNITS_MM");
        } else if line.contains("SET_FEED_RATE(") {
            feed = args(line)[0];
        } else if line.contains("STRAIGHT_TRAVERSE(") {
            let a = args(line);
            out.push(CanonMove::Traverse([a[0], a[1], a[2]]));
        } else if line.contains("STRAIGHT_FEED(") {
            let a = args(line);
            out.push(CanonMove::Line([a[0], a[1], a[2]], feed));
        } else if line.contains("ARC_FEED(") {
            // ARC_FEED(end1, end2, c1, c2, turn, end3, ...) in the XY plane.
            let a = args(line);
            out.push(CanonMove::Arc {
                end: [a[0], a[1], a[5]],
                center: [a[2], a[3]],
                ccw: a[4] > 0.0,
                feed,
            });
        }
    }
    (out, mm)
}

/// Points along every move of a canon program (arcs sampled every ≤ 1°), each with whether
/// it is a rapid, starting from `start`.
pub fn canon_points(moves: &[CanonMove], start: [f64; 3]) -> Vec<([f64; 3], bool)> {
    let mut cur = start;
    let mut pts = Vec::new();
    for m in moves {
        match *m {
            CanonMove::Traverse(p) => {
                pts.push((p, true));
                cur = p;
            }
            CanonMove::Line(p, _) => {
                pts.push((p, false));
                cur = p;
            }
            CanonMove::Arc { end, center, ccw, .. } => {
                let a0 = (cur[1] - center[1]).atan2(cur[0] - center[0]);
                let a1 = (end[1] - center[1]).atan2(end[0] - center[0]);
                let r = ((cur[0] - center[0]).powi(2) + (cur[1] - center[1]).powi(2)).sqrt();
                let tau = std::f64::consts::TAU;
                let mut sweep =
                    if ccw { (a1 - a0).rem_euclid(tau) } else { (a0 - a1).rem_euclid(tau) };
                if sweep == 0.0 {
                    sweep = tau;
                }
                let n = (sweep.to_degrees().ceil() as usize).max(1);
                for i in 1..=n {
                    let t = i as f64 / n as f64;
                    let a = if ccw { a0 + sweep * t } else { a0 - sweep * t };
                    let z = cur[2] + (end[2] - cur[2]) * t;
                    pts.push(([center[0] + r * a.cos(), center[1] + r * a.sin(), z], false));
                }
                cur = end;
            }
        }
    }
    pts
}

/// Length of every feed move (arcs by their sweep) and of every rapid of a canon program.
pub fn canon_lengths(moves: &[CanonMove], start: [f64; 3]) -> (f64, f64) {
    let mut cur = start;
    let (mut feed, mut rapid) = (0.0, 0.0);
    let d = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    for m in moves {
        match *m {
            CanonMove::Traverse(p) => {
                rapid += d(cur, p);
                cur = p;
            }
            CanonMove::Line(p, _) => {
                feed += d(cur, p);
                cur = p;
            }
            CanonMove::Arc { end, center, ccw, .. } => {
                let a0 = (cur[1] - center[1]).atan2(cur[0] - center[0]);
                let a1 = (end[1] - center[1]).atan2(end[0] - center[0]);
                let r = ((cur[0] - center[0]).powi(2) + (cur[1] - center[1]).powi(2)).sqrt();
                let tau = std::f64::consts::TAU;
                let sweep = if ccw { (a1 - a0).rem_euclid(tau) } else { (a0 - a1).rem_euclid(tau) };
                feed += ((r * sweep).powi(2) + (end[2] - cur[2]).powi(2)).sqrt();
                cur = end;
            }
        }
    }
    (feed, rapid)
}

#[path = "../../../tests/support/rs274.rs"]
mod rs274;
#[allow(unused_imports)] // not every test binary runs check-gcode
pub use rs274::ensure_rs274;
