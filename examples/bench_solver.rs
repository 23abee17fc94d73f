//! Time per Levenberg–Marquardt iteration against the number of edited vertices, measured the
//! way of the paper's Fig. 12a (Jacobian assembly and linear solve separately).
//!
//! ```text
//! cargo run --release --example bench_solver
//! cargo run --release --example bench_solver -- --whole-mesh [VERTICES...]
//! BENCH_SIZES=656 BENCH_REPS=100 BENCH_DEBUG=1 cargo run --release --example bench_solver
//! ```
//!
//! With `--whole-mesh`, every vertex of a torus of about 100k (or the given) vertices is free
//! (λ_s relative 1e-6 plus the turning-radius hinge, so every block is assembled), and the
//! seconds per iteration (assembly + solve) are reported as min/median/max over 3 runs of 3
//! iterations (`BENCH_RUNS`, `BENCH_ITERATIONS`). The first run of a process also pays the first
//! touch of the solve's memory (later runs reuse it: the allocator keeps freed memory).
//!
//! On an icosphere of 40,962 vertices, a brush around one point is made free with the brush
//! radius chosen so it holds about 14, 32, 89, 217, 420 and 656 vertices; targets are the
//! highlights of a smooth field and the start is that field bumped inside the brush.
//!
//! The allocator is the `grainline` binary's (mimalloc, freed memory kept: grainline::allocator).

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::Symmetry;
use grainline::solve::{solve, HighlightTerm, LinearSolver, LmOptions};
use nalgebra::Vector3;

/// A line-field term whose targets are `phi_true`'s own highlights (so `phi_true` has zero
/// highlight energy), every vertex weighted 1.
fn own_targets<'a>(g: &'a Geometry, h: &'a [Vector3<f64>], phi_true: &[f64]) -> HighlightTerm<'a> {
    HighlightTerm::own_targets(g, h, Symmetry::Line, GradientForm::Angle, phi_true)
}

/// `GRAINLINE_LM_SOLVER=direct|cg` forces a linear solver (default: auto).
fn linear_solver() -> LinearSolver {
    match std::env::var("GRAINLINE_LM_SOLVER").as_deref() {
        Ok("direct") => LinearSolver::Direct,
        Ok("cg") => LinearSolver::ConjugateGradient,
        _ => LinearSolver::Auto,
    }
}

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn whole_mesh(targets: &[usize]) {
    println!("| vertices | free | iterations | energy by iteration | wall s/it incl. setup and rejected tries (min/median/max) | assembly s/it (min/median/max) | solve s/it (min/median/max) | total s/it (median) |");
    println!("|---:|---:|---:|---|---:|---:|---:|---:|");
    for &nv in targets {
        let minor = ((nv as f64 / 4.0).sqrt()).round().max(3.0) as usize;
        let major = (nv / minor).max(3);
        let mesh = grainline::generate::torus(2.0, 0.7, major, minor);
        let g = Geometry::compute(&mesh, &GeometryOptions::default());
        let n = mesh.num_vertices();
        let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); n];
        let phi_true: Vec<f64> = (0..n)
            .map(|i| {
                let p = mesh.positions[i];
                g.frames[i].angle_of(&Vector3::new(-p.y, p.x, 0.3 * p.z))
            })
            .collect();
        let term = own_targets(&g, &h, &phi_true);
        let phi: Vec<f64> =
            (0..n).map(|i| phi_true[i] + 0.2 * (3.0 * mesh.positions[i].x).sin()).collect();
        let free: Vec<u32> = (0..n as u32).collect();
        let opts = LmOptions {
            smoothness: 1e-6 * g.areas.iter().sum::<f64>(),
            max_iterations: env_usize("BENCH_ITERATIONS", 3),
            turning: Some(grainline::solve::HingeOptions { bound: 2.0, weight: 1.0 }),
            linear_solver: linear_solver(),
            ..Default::default()
        };
        let (mut a, mut s, mut its, mut wall) = (Vec::new(), Vec::new(), 0, Vec::new());
        let mut energies = String::new();
        for _ in 0..env_usize("BENCH_RUNS", 3) {
            let t = std::time::Instant::now();
            let r = solve(&mesh, &term, &phi, &free, &opts).unwrap();
            wall.push(t.elapsed().as_secs_f64() / opts.max_iterations as f64);
            energies = std::iter::once(r.initial_energy.total())
                .chain(r.iterations.iter().map(|i| i.energies.total()))
                .map(|e| format!("{e:.2e}"))
                .collect::<Vec<_>>()
                .join(" → ");
            let k = r.iterations.len().max(1) as f64;
            its = r.iterations.len();
            a.push(r.iterations.iter().map(|i| i.assembly_seconds).sum::<f64>() / k);
            s.push(r.iterations.iter().map(|i| i.solve_seconds).sum::<f64>() / k);
        }
        let stats = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            (v[0], v[v.len() / 2], v[v.len() - 1])
        };
        let (sa, ss, sw) = (stats(&mut a), stats(&mut s), stats(&mut wall));
        println!(
            "| {n} | {n} | {its} | {energies} | {:.3}/{:.3}/{:.3} | {:.3}/{:.3}/{:.3} | {:.3}/{:.3}/{:.3} | {:.3} |",
            sw.0,
            sw.1,
            sw.2,
            sa.0,
            sa.1,
            sa.2,
            ss.0,
            ss.1,
            ss.2,
            sa.1 + ss.1
        );
    }
}

fn main() {
    // As the `grainline` binary does (see grainline::allocator).
    grainline::allocator::keep_freed_memory();
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--whole-mesh") {
        let sizes: Vec<usize> = args[1..].iter().filter_map(|a| a.parse().ok()).collect();
        whole_mesh(if sizes.is_empty() { &[100_000] } else { &sizes });
        return;
    }
    let mesh = grainline::generate::icosphere(1.0, 6);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); n];
    let phi_true: Vec<f64> = (0..n)
        .map(|i| {
            let p = mesh.positions[i];
            g.frames[i].angle_of(&Vector3::new(
                (0.8 * p.y).cos(),
                (0.8 * p.y).sin() + 0.3 * p.x,
                0.1,
            ))
        })
        .collect();
    let term = own_targets(&g, &h, &phi_true);
    let centre = Vector3::new(0.0, 0.0, 1.0);
    let mut dist: Vec<(f64, u32)> =
        (0..n as u32).map(|i| ((mesh.positions[i as usize] - centre).norm(), i)).collect();
    dist.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("| edited vertices | paper: Jacobian | paper: solver | paper: total | iterations | JᵀJ refill (1st iteration: + rows, pattern, ordering, symbolic) | damping + factorization + solve + trial point (rows, Jᵀr, energy) | total (ms/iteration) |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (count, paper) in [
        (14, (0.6, 0.8, 1.4)),
        (32, (1.4, 0.4, 1.8)),
        (89, (3.0, 2.7, 5.7)),
        (217, (3.9, 23.4, 27.3)),
        (420, (9.5, 55.2, 64.7)),
        (656, (14.2, 120.5, 134.7)),
    ] {
        // BENCH_SIZES=656,420 runs only those rows; BENCH_REPS the repetitions (default 20).
        if let Ok(only) = std::env::var("BENCH_SIZES") {
            if !only.split(',').any(|x| x.trim().parse() == Ok(count)) {
                continue;
            }
        }
        let reps: usize =
            std::env::var("BENCH_REPS").ok().and_then(|v| v.parse().ok()).unwrap_or(20);
        let radius = dist[count].0;
        let free: Vec<u32> = dist[..count].iter().map(|d| d.1).collect();
        let mut phi = phi_true.clone();
        for &i in &free {
            let d = (mesh.positions[i as usize] - centre).norm() / radius;
            phi[i as usize] += 0.3 * (1.0 - d * d).powi(2);
        }
        // Several repetitions, fastest kept, to damp the noise of a shared machine.
        let mut best = (f64::INFINITY, 0.0, 0.0, 0);
        for _ in 0..reps {
            let r = solve(
                &mesh,
                &term,
                &phi,
                &free,
                &LmOptions { smoothness: 1e-4, max_iterations: 10, ..Default::default() },
            )
            .unwrap();
            let its = r.iterations.len().max(1) as f64;
            let a: f64 = r.iterations.iter().map(|i| i.assembly_seconds).sum::<f64>() / its * 1e3;
            let s: f64 = r.iterations.iter().map(|i| i.solve_seconds).sum::<f64>() / its * 1e3;
            if std::env::var("BENCH_DEBUG").is_ok() {
                // The result's bits (FNV-1a of φ, the energies and the iteration count), to
                // check a speed change leaves the solve as it was.
                let mut hash = 0xcbf29ce484222325u64;
                let bits = r.phi.iter().chain(r.iterations.iter().map(|i| &i.energies.highlight));
                for b in bits.map(|x| x.to_bits()).chain([r.iterations.len() as u64]) {
                    hash = (hash ^ b).wrapping_mul(0x100000001b3);
                }
                eprintln!("{count}: result {hash:016x}");
                let per: Vec<String> = r
                    .iterations
                    .iter()
                    .map(|i| {
                        format!("{:.3}+{:.3}", i.assembly_seconds * 1e3, i.solve_seconds * 1e3)
                    })
                    .collect();
                eprintln!("{count}: {}", per.join(" "));
            }
            if a + s < best.0 {
                best = (a + s, a, s, r.iterations.len());
            }
        }
        println!(
            "| {count} | {} | {} | {} | {} | {:.3} | {:.3} | {:.3} |",
            paper.0, paper.1, paper.2, best.3, best.1, best.2, best.0
        );
    }
}
