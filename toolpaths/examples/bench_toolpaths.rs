//! Benchmarks for grainline-toolpaths (run with `--release`):
//!
//! 1. Tracing + even spacing: ~10k strokes on a 1M-triangle UV mesh (a 100 × 100 mm sheet
//!    carrying a 40 × 40 lattice of Taylor–Green vortex cells, d_sep = 0.23 mm, or
//!    `BENCH_DSEP`).
//! 2. Ordering those strokes (greedy + 2-opt), and travel compared with vpype's
//!    `linesort --no-flip` through `../shared/tools/check-svg` when it is present.
//! 3. Integration tolerance vs streamline error vs time on the annulus (circles known).
//!
//! 4. Tracing + spacing on the same sheet given as a 3D lift under a warped UV layout
//!    (`--warped`, issue 14), against its isometric layout.
//!
//! `cargo run --release -p grainline-toolpaths --example bench_toolpaths [-- --quick] [--place-only] [--warped]`

use std::f64::consts::PI;
use std::path::PathBuf;
use std::time::Instant;

use grainline_toolpaths::*;

fn grid_mesh(w: f64, h: f64, nx: usize, ny: usize) -> (Vec<Vec2>, Vec<[u32; 3]>) {
    let mut uv = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            uv.push([w * i as f64 / nx as f64, h * j as f64 / ny as f64]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut tris = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (uv, tris)
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// CPU time of this process (user + system, 10 ms resolution) from /proc, so figures stay
/// meaningful when other jobs share the two cores; 0 where /proc is missing.
fn cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = rest.split_whitespace().filter_map(|x| x.parse().ok()).collect();
    // Numbers after the command (the state letter is skipped): ppid pgrp session tty_nr
    // tpgid flags minflt cminflt majflt cmajflt utime stime.
    if f.len() > 11 {
        (f[10] + f[11]) / 100.0
    } else {
        0.0
    }
}

fn check_svg(svg: &str, name: &str) -> Option<String> {
    let tool = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/tools/check-svg");
    if !tool.exists() || std::env::var_os("BENCH_NO_VPYPE").is_some() {
        return None;
    }
    let dir = std::env::temp_dir().join("grainline-bench");
    std::fs::create_dir_all(&dir).ok()?;
    let path = dir.join(name);
    std::fs::write(&path, svg).ok()?;
    let out = std::process::Command::new("bash").arg(tool).arg(&path).output().ok()?;
    Some(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// min / median / max of a sample.
fn stats(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2], v[v.len() - 1])
}

fn ordering_report(label: &str, dom: &Domain, pl: &Placement, direction: Direction) {
    let mut plan_opts = PlanOptions { direction, ..Default::default() };
    if let Some(k) = std::env::var("BENCH_K").ok().and_then(|v| v.parse().ok()) {
        plan_opts.order.neighbours = k;
    }
    let t = Instant::now();
    let plan = plan_toolpath(dom, pl, &plan_opts).unwrap();
    let t_plan = secs(t);
    // Ordering alone, on exactly the planned entry/exit points, repeated in-process.
    let ends = ordering_ends(dom, pl, &plan_opts).unwrap();
    let flip = direction == Direction::Alternate;
    let runs: usize =
        std::env::var("BENCH_ORDER_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(7);
    let (mut wall, mut cpus) = (Vec::new(), Vec::new());
    let mut o = None;
    for _ in 0..runs.max(1) {
        let (t, c) = (Instant::now(), cpu());
        let r = order_strokes(&ends, flip, &plan_opts.order);
        wall.push(secs(t));
        cpus.push(cpu() - c);
        if let Some(prev) = &o {
            assert_eq!(prev, &r, "ordering is not deterministic");
        }
        o = Some(r);
    }
    let o = o.unwrap();
    let (w0, w1, w2) = stats(wall);
    let (c0, c1, c2) = stats(cpus);
    println!(
        "{label}: {} strokes ({} loops); plan {t_plan:.3} s; ordering x{runs}: wall min/median/max \
         {w0:.3}/{w1:.3}/{w2:.3} s, CPU {c0:.2}/{c1:.2}/{c2:.2} s",
        ends.len(),
        ends.iter().filter(|e| !e.ring.is_empty()).count(),
    );
    println!(
        "  travel between strokes: greedy {:.1} mm -> ours {:.1} mm (plan {:.1} mm)",
        o.travel_greedy - o.travel + o.travel_between,
        o.travel_between,
        plan.travel_between,
    );
    if !flip && std::env::var_os("BENCH_NO_BOUND").is_none() {
        let t = Instant::now();
        let b = travel_bound(&ends, &BoundOptions::default());
        let a = b.assignment.unwrap_or(f64::NAN);
        println!(
            "  lower bound on travel between strokes (any --no-flip order): nearest {:.1} mm, \
             assignment {a:.1} mm (primal on lists {:.1} mm) [{:.3} s]; ours is {:+.1} % above it",
            b.nearest,
            b.assignment_primal.unwrap_or(f64::NAN),
            secs(t),
            100.0 * (o.travel_between / a - 1.0),
        );
    }
    // vpype sees the same oriented strokes twice: in our order, and in placement order (so
    // its `linesort --no-flip` starts from scratch rather than from our tour).
    let svg_opts = SvgOptions { outlines: false, ..Default::default() };
    let mut unordered = plan.clone();
    unordered.passes.sort_by_key(|p| p.stroke);
    for (tag, p) in [("ordered", &plan), ("placement-order", &unordered)] {
        let svg = write_svg(dom, p, &svg_opts).unwrap();
        match check_svg(&svg, &format!("{label}-{tag}.svg")) {
            Some(line) => println!("  check-svg ({tag}): {line}"),
            None => println!("  check-svg: skipped (../shared absent)"),
        }
    }
}

fn bench_cells(quick: bool, place_only: bool, order_only: bool) {
    let (n, cells) = if quick { (200, 10.0) } else { (707, 40.0) };
    let d_sep: f64 = std::env::var("BENCH_DSEP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(if quick { 0.5 } else { 0.23 });
    let side = 100.0;
    let c = side / cells;
    let t = Instant::now();
    let (uv, tris) = grid_mesh(side, side, n, n);
    let dirs: Vec<Vec2> = uv
        .iter()
        .map(|p| {
            let (x, y) = (PI * p[0] / c, PI * p[1] / c);
            [x.sin() * y.cos(), -x.cos() * y.sin()]
        })
        .collect();
    let nf = tris.len();
    let mesh = FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Vector);
    let t_mesh = secs(t);
    let t = Instant::now();
    let dom = Domain::new(mesh).unwrap();
    let t_dom = secs(t);
    let mut opts = PlacementOptions::new(d_sep, 0.0);
    if let Some(r) = std::env::var("BENCH_END_RUN").ok().and_then(|v| v.parse().ok()) {
        opts.end_run = r;
    }
    opts.fill_gaps = std::env::var_os("BENCH_NO_FILL").is_none();
    let (t, c) = (Instant::now(), cpu());
    let pl = place_strokes(&dom, &opts).unwrap();
    let (t_place, c_place) = (secs(t), cpu() - c);
    let pts: usize = pl.strokes.iter().map(|s| s.uv.len()).sum();
    let len: f64 = pl.strokes.iter().map(|s| s.length).sum();
    println!(
        "cells: {nf} triangles, {} singularities; build mesh {t_mesh:.3} s, Domain::new {t_dom:.3} s",
        pl.singularities.len()
    );
    println!(
        "cells: tracing + spacing {t_place:.3} s wall ({c_place:.2} s CPU) -> {} strokes, {pts} points, {len:.0} mm, \
         {} field evaluations",
        pl.strokes.len(),
        pl.field_evaluations
    );
    let mut stops = std::collections::BTreeMap::new();
    for s in &pl.strokes {
        *stops.entry(s.start.name()).or_insert(0) += 1;
        *stops.entry(s.end.name()).or_insert(0) += 1;
    }
    println!("cells: stroke ends by stop reason: {stops:?}");
    if place_only {
        return;
    }
    if order_only {
        ordering_report("cells", &dom, &pl, Direction::Along);
        return;
    }
    let t = Instant::now();
    let cov =
        coverage(&dom, &pl, &CoverageOptions { resolution: Some(d_sep / 2.0), keep_map: false })
            .unwrap();
    println!(
        "cells: coverage {:.3} s -> {:.2}% within d_sep/2, largest gap {:.3} mm",
        secs(t),
        100.0 * cov.fraction,
        cov.largest_gap
    );
    ordering_report("cells", &dom, &pl, Direction::Along);
}

fn bench_sheet() {
    // Open strokes: a wavy line field on a 200 x 100 mm sheet, brush 1 mm.
    let (uv, tris) = grid_mesh(200.0, 100.0, 200, 100);
    let dirs: Vec<Vec2> = uv
        .iter()
        .map(|p| {
            let a = 0.6 * (p[0] / 25.0).sin() + 0.4 * (p[1] / 15.0).cos();
            [a.cos(), a.sin()]
        })
        .collect();
    let dom =
        Domain::new(FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Line)).unwrap();
    let pl = place_strokes(&dom, &PlacementOptions::new(1.0, 0.0)).unwrap();
    ordering_report("sheet-along", &dom, &pl, Direction::Along);
    ordering_report("sheet-alternate", &dom, &pl, Direction::Alternate);
}

fn bench_annulus() {
    let (r0, r1, nr, nt) = (2.0, 10.0, 16, 128);
    let mut uv = Vec::new();
    for j in 0..=nr {
        let r = r0 + (r1 - r0) * j as f64 / nr as f64;
        for i in 0..nt {
            let t = 2.0 * PI * i as f64 / nt as f64;
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
    let d = uv.iter().map(|p: &Vec2| [-p[1], p[0]]).collect();
    let dom =
        Domain::new(FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Vector)).unwrap();
    println!("annulus (r = 2.5..9.5, 15 circles, max_step 1 mm): tolerance | max radius error (vertices and chord midpoints) | points | time");
    for tol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        let opts = TraceOptions { tolerance: tol, max_step: 1.0, ..Default::default() };
        let t = Instant::now();
        let (mut err, mut pts): (f64, usize) = (0.0, 0);
        let reps = 20;
        for _ in 0..reps {
            err = 0.0;
            pts = 0;
            for k in 0..15 {
                let r = 2.5 + 0.5 * k as f64;
                let s = trace_streamline(&dom, [r, 0.0], &opts).unwrap().unwrap();
                pts += s.uv.len();
                for w in s.uv.windows(2) {
                    let m = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                    for p in [w[0], m] {
                        err = err.max((p[0].hypot(p[1]) - r).abs());
                    }
                }
            }
        }
        println!("  {tol:.0e} | {err:.2e} mm | {pts} | {:.2} ms", 1e3 * secs(t) / reps as f64);
    }
}

/// Issue 14: the same 100 × 100 mm sheet and Taylor–Green lattice, but given as a 3D lift
/// (the sheet at z = 0) under a warped UV layout, `u = x`, `v = y (1 + c (x/W)² (y/H)²)`
/// with `c = 2/3` (stretched 3:1 towards one corner, sheared), so spacing is measured on
/// the lift. Tracing + spacing (gap filling included; `BENCH_NO_FILL=1` leaves it out) is
/// timed `BENCH_RUNS` times (default 3), then compared with the isometric layout of the same
/// lift; `BENCH_COVERAGE=1` also measures coverage, `BENCH_WARPED_ONLY=1` skips the
/// isometric layout. Each run's strokes are hashed (bit for bit) and the hash printed.
fn bench_warped() {
    let n = 707;
    let cells = 40.0;
    let d_sep: f64 = std::env::var("BENCH_DSEP").ok().and_then(|v| v.parse().ok()).unwrap_or(0.23);
    let runs: usize = std::env::var("BENCH_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(3);
    let side = 100.0;
    let cell = side / cells;
    let cc = 2.0 / 3.0;
    let (xy, tris) = grid_mesh(side, side, n, n);
    let nf = tris.len();
    let pos: Vec<Vec3> = xy.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let nrm = vec![[0.0, 0.0, 1.0]; pos.len()];
    let layouts: &[bool] =
        if std::env::var_os("BENCH_WARPED_ONLY").is_some() { &[true] } else { &[true, false] };
    for &warped in layouts {
        let (uv, dirs): (Vec<Vec2>, Vec<Vec2>) = xy
            .iter()
            .map(|p| {
                let (x, y) = (p[0], p[1]);
                let (a, b) = (PI * x / cell, PI * y / cell);
                let t = [a.sin() * b.cos(), -a.cos() * b.sin()];
                if !warped {
                    return (*p, t);
                }
                let q = cc * (x / side).powi(2) / (side * side);
                let v = y * (1.0 + q * y * y);
                let dv_dx = 2.0 * cc * x * y.powi(3) / side.powi(4);
                let dv_dy = 1.0 + 3.0 * q * y * y;
                ([x, v], [t[0], dv_dx * t[0] + dv_dy * t[1]])
            })
            .unzip();
        let mesh = FieldMesh::new(uv, tris.clone(), Directions::Vectors(dirs), Symmetry::Vector)
            .with_lift(pos.clone(), Some(nrm.clone()));
        let t = Instant::now();
        let dom = Domain::new(mesh).unwrap();
        let t_dom = secs(t);
        let fill_gaps = std::env::var_os("BENCH_NO_FILL").is_none();
        let opts = PlacementOptions { fill_gaps, ..PlacementOptions::new(d_sep, 0.0) };
        let (mut wall, mut cpus) = (Vec::new(), Vec::new());
        let mut last: Option<Placement> = None;
        for _ in 0..runs.max(1) {
            let (t, c) = (Instant::now(), cpu());
            let pl = place_strokes(&dom, &opts).unwrap();
            wall.push(secs(t));
            cpus.push(cpu() - c);
            if let Some(prev) = &last {
                assert_eq!(strokes_hash(prev), strokes_hash(&pl), "placement is not deterministic");
            }
            last = Some(pl);
        }
        let pl = last.unwrap();
        let (w0, w1, w2) = stats(wall);
        let (c0, c1, c2) = stats(cpus);
        let label = if warped { "warped" } else { "isometric" };
        println!(
            "{label}: {nf} triangles (lift, spacing on the part), Domain::new {t_dom:.3} s; tracing + \
             spacing x{runs}: wall min/median/max {w0:.3}/{w1:.3}/{w2:.3} s, CPU {c0:.2}/{c1:.2}/{c2:.2} s \
             -> {} strokes ({} fill, {} dropped short), {:.0} mm, hash {:016x}",
            pl.strokes.len(),
            pl.fill_strokes,
            pl.dropped_short,
            pl.strokes.iter().map(|s| s.length).sum::<f64>(),
            strokes_hash(&pl),
        );
        if std::env::var_os("BENCH_COVERAGE").is_some() {
            let cov = coverage(
                &dom,
                &pl,
                &CoverageOptions { resolution: Some(d_sep / 2.0), keep_map: false },
            )
            .unwrap();
            println!(
                "{label}: coverage {:.2}%, largest gap {:.3} mm",
                100.0 * cov.fraction,
                cov.largest_gap
            );
        }
    }
}

/// FNV-1a over the bits of every stroke point and length, in order: equal hashes mean
/// bit-identical placements (to compare builds before and after a speed-up).
fn strokes_hash(pl: &Placement) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    };
    for s in &pl.strokes {
        eat(s.uv.len() as u64);
        for p in &s.uv {
            eat(p[0].to_bits());
            eat(p[1].to_bits());
        }
        eat(s.length.to_bits());
    }
    h
}

fn main() {
    if std::env::args().any(|a| a == "--warped") {
        bench_warped();
        return;
    }
    if std::env::args().any(|a| a == "--order-only") {
        bench_cells(false, false, true);
        bench_sheet();
        return;
    }
    let quick = std::env::args().any(|a| a == "--quick");
    if std::env::args().any(|a| a == "--annulus-only") {
        bench_annulus();
        return;
    }
    let place_only = std::env::args().any(|a| a == "--place-only");
    bench_cells(quick, place_only, false);
    if place_only {
        return;
    }
    bench_sheet();
    bench_annulus();
}
