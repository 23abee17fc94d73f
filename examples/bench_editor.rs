//! One drag step of `grainline edit` on a ~50k-vertex part with a 1–2k-vertex brush (issue 16:
//! ≤ 30 ms median): the edit's targets, the solve, the new grain and the key light's highlight
//! curves for the page — what the editor's solver thread does for each preview
//! ([`grainline::editor::Session::solve_drag`], incremental) — plus encoding the grain for the
//! page ([`grainline::editor::grain_bytes`]). Then the whole stage for each step's edit
//! ([`grainline::editor::Session::solve`], what a commit does), which must give the same grain and
//! highlight curves (a step after the first makes them only around the vertices it changed).
//! FIELD.json is not part of a step (it is made when the page or a test asks for it); its cost
//! is printed apart.
//!
//! `cargo run --release --example bench_editor [VERTICES]` (GRAINLINE_BENCH_STEPS to change the
//! 30 steps; GRAINLINE_BENCH_DRAG_ONLY=1 times the drag steps alone, for a profiler). VERTICES
//! (default 50,000) scales the cylinder's grid (~50k, ~200k, ~500k vertices) and the brush's
//! radius with its edge length, so the brush's support stays about 1.2k vertices.
//!
//! It prints an FNV-1a hash of every drag step's φ bits, in order: a change that keeps the
//! algorithm keeps the hash (the drag steps' φ bit for bit).
//!
//! The allocator is the `grainline` binary's (mimalloc, freed memory kept: grainline::allocator),
//! as `grainline edit` runs.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::time::Instant;

use grainline::edit::{Centre, Edit, Metric, WarpEdit};
use grainline::editor::{grain_bytes, Session};

fn main() {
    // As the `grainline` binary does (see grainline::allocator).
    grainline::allocator::keep_freed_memory();
    let steps: usize =
        std::env::var("GRAINLINE_BENCH_STEPS").ok().and_then(|s| s.parse().ok()).unwrap_or(30);
    let target: f64 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(50_000.0);
    let (dir, scale) = write_part(target);
    let t = Instant::now();
    let session = Session::open(&dir.join("scene.json")).unwrap();
    let open_s = t.elapsed().as_secs_f64();
    let n = session.prepared().mesh.num_vertices();
    // The key highlight of the initial field near the front: where a designer would press.
    let base = session.base_for(None).unwrap();
    let first = session.solve(&base, &[], 0).unwrap();
    let front = first
        .segments
        .iter()
        .map(|s| [(s[0] + s[3]) / 2.0, (s[1] + s[4]) / 2.0, (s[2] + s[5]) / 2.0])
        .filter(|p| p[1] < 0.0)
        .min_by(|a, b| a[2].abs().total_cmp(&b[2].abs()))
        .expect("a highlight on the front");
    let centre = [f64::from(front[0]), f64::from(front[1]), f64::from(front[2])];
    // 11 mm at 50k vertices (support ~1.26k vertices), shrunk with the edge length.
    let radius = 11.0 / scale;
    let edit = |k: usize| {
        Edit::Bend(WarpEdit {
            centre: Centre::Point(centre),
            radius,
            metric: Metric::Geodesic,
            strength: 0.05 + 0.9 * k as f64 / steps as f64,
            direction: Some([0.0, 0.0, 1.0]),
            weight: 1.0,
        })
    };
    // The drag: its steps back to back (Session::solve_drag, what the editor's solver thread
    // does for each preview). Then the whole stage for each step's edit (Session::solve: what a
    // commit does, and what every drag step did before the incremental path), which must give
    // the same grain and highlight curves.
    let drag_only = std::env::var_os("GRAINLINE_BENCH_DRAG_ONLY").is_some();
    let mut times = Vec::with_capacity(steps);
    let mut full_times = Vec::with_capacity(steps);
    let mut support = 0;
    let mut grains = Vec::with_capacity(steps);
    // FNV-1a of every step's φ bits, in order: the same number before and after a change that
    // keeps the algorithm (the drag steps' φ bit for bit).
    let mut phi_hash: u64 = 0xcbf2_9ce4_8422_2325;
    for k in 0..steps {
        let t = Instant::now();
        let solved = session.solve_drag(&base, &[], &edit(k), k as u64 + 1).unwrap();
        let bytes = grain_bytes(&solved);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(bytes);
        for x in solved.phi() {
            for b in x.to_bits().to_le_bytes() {
                phi_hash = (phi_hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
            }
        }
        support = solved.edited_vertices;
        if !drag_only {
            grains.push((solved.u.clone(), solved.segments.clone()));
        }
    }
    if drag_only {
        times.sort_by(f64::total_cmp);
        println!("drag steps only: median {:.1} ms, min {:.1} ms", times[steps / 2], times[0]);
        println!("  φ of the {steps} steps: FNV-1a {phi_hash:016x}");
        let _ = std::fs::remove_dir_all(&dir);
        return;
    }
    let mut last = None;
    for (k, (u, segments)) in grains.iter().enumerate() {
        let t = Instant::now();
        let full = session.solve(&base, &[edit(k)], k as u64 + 1).unwrap();
        let bytes = grain_bytes(&full);
        full_times.push(t.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(bytes);
        assert!(full.u == *u, "step {k}: the drag step's grain is not the whole stage's");
        assert!(
            full.segments == *segments,
            "step {k}: the drag step's highlight curves are not the whole stage's"
        );
        last = Some(full);
    }
    let last = last.unwrap();
    time_step_parts(&session, &dir, steps, &edit);
    let t = Instant::now();
    let json_len = session.field_json(&last).unwrap().len();
    let json_ms = t.elapsed().as_secs_f64() * 1e3;
    times.sort_by(f64::total_cmp);
    full_times.sort_by(f64::total_cmp);
    let q = |p: f64| times[((times.len() - 1) as f64 * p).round() as usize];
    let qf = |p: f64| full_times[((full_times.len() - 1) as f64 * p).round() as usize];
    println!(
        "bench_editor: {n} vertices, brush radius {radius:.2} mm with {support} vertices in its \
         support, {steps} drag steps (bend, strength 0.05 → 0.95)"
    );
    println!(
        "  one drag step (targets, solve, grain, highlight curves, encoding): median {:.1} ms, \
         p90 {:.1} ms, min {:.1} ms, max {:.1} ms",
        q(0.5),
        q(0.9),
        times[0],
        times[times.len() - 1]
    );
    println!(
        "  the whole stage for the same edit (a commit; a drag step before the incremental \
         path): median {:.1} ms, p90 {:.1} ms, min {:.1} ms",
        qf(0.5),
        qf(0.9),
        full_times[0]
    );
    println!("  φ of the {steps} steps: FNV-1a {phi_hash:016x}");
    println!("  session open (load, geometry, initial field): {:.0} ms", open_s * 1e3);
    println!("  FIELD.json when asked for: {json_ms:.0} ms ({:.1} MB)", json_len as f64 / 1e6);
    println!("  solver: {}; fidelity: {:?}", last.stop, last.fidelity.first().map(|f| f.landed));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes the part and its scene into a fresh temporary folder: a cylinder r = 30, h = 80
/// brushed around, 320 × 156 quads → 50,240 vertices at the default size; the grid scaled by
/// √(target / 50,000) on both axes otherwise. Returns the folder and that scale.
fn write_part(target: f64) -> (std::path::PathBuf, f64) {
    let dir = std::env::temp_dir().join(format!("grainline-bench-editor-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scale = (target / 50_000.0).sqrt();
    let (around, along) = ((320.0 * scale).round() as usize, (156.0 * scale).round() as usize);
    let mesh = grainline::generate::cylinder(30.0, 80.0, around, along);
    std::fs::write(dir.join("part.obj"), grainline::mesh::write::obj_string(&mesh, "bench"))
        .unwrap();
    std::fs::write(
        dir.join("scene.json"),
        r#"{"mesh": "part.obj", "view": {"eye": [0, -300, 0]},
            "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
            "field": {"init": "uv", "symmetry": "line"}}"#,
    )
    .unwrap();
    (dir, scale)
}

/// Where a step's time goes, printed: the stages of optimize_stage ("edits": targets, "solve":
/// the solver incl. the highlight field before/after, fidelity, critical points), the page's
/// grain and highlight curves, then the incremental step alone.
fn time_step_parts(
    session: &Session,
    dir: &std::path::Path,
    steps: usize,
    edit: &dyn Fn(usize) -> Edit,
) {
    let loaded = grainline::scene::LoadedScene::read(&dir.join("scene.json")).unwrap();
    let mut parts: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    for k in 0..steps.min(10) {
        let t = Instant::now();
        let text = session.scene_text(&[edit(k)]).unwrap();
        let scene = grainline::scene::Scene::from_str(&text, &loaded.path).unwrap();
        let s = grainline::scene::LoadedScene { scene, ..loaded.clone() };
        parts.entry("0 scene text + parse".into()).or_default().push(t.elapsed().as_secs_f64());
        let observer = grainline::pipeline::Silent;
        let mut stages = grainline::pipeline::Stages::new(&observer);
        let o = grainline::pipeline::optimize::optimize_stage(&s, session.prepared(), &mut stages)
            .unwrap();
        for st in stages.into_times() {
            parts.entry(format!("1 optimize_stage: {}", st.stage)).or_default().push(st.seconds);
        }
        let t = Instant::now();
        let g = &session.prepared().field.geometry;
        let u = g.directions_of(&o.phi);
        parts.entry("2 grain u".into()).or_default().push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        let segs = grainline::fidelity::highlight_segments(
            &session.prepared().mesh,
            &o.h,
            &u,
            session.prepared().field_options.symmetry,
        );
        std::hint::black_box(segs);
        parts.entry("3 highlight curves".into()).or_default().push(t.elapsed().as_secs_f64());
    }
    // The incremental step alone: the dragged edit's targets and the solve without the
    // whole-mesh report, on a base made once.
    let bare = grainline::scene::LoadedScene {
        scene: grainline::scene::Scene::from_str(&session.scene_text(&[]).unwrap(), &loaded.path)
            .unwrap(),
        ..loaded.clone()
    };
    let t = Instant::now();
    let base = grainline::editor::drag::DragBase::new(&bare, session.prepared()).unwrap();
    parts.entry("4 drag base (once per drag)".into()).or_default().push(t.elapsed().as_secs_f64());
    for k in 0..steps.min(10) {
        let text = session.scene_text(&[edit(k)]).unwrap();
        let scene = grainline::scene::Scene::from_str(&text, &loaded.path).unwrap();
        let s = grainline::scene::LoadedScene { scene, ..loaded.clone() };
        let t = Instant::now();
        let step = base.step(&s, session.prepared(), 1).unwrap();
        parts
            .entry("5 drag step: targets + solve".into())
            .or_default()
            .push(t.elapsed().as_secs_f64());
        std::hint::black_box(step);
    }
    for (name, mut v) in parts {
        v.sort_by(f64::total_cmp);
        println!("  {name}: median {:.1} ms", v[v.len() / 2] * 1e3);
    }
}
