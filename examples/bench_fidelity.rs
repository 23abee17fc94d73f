//! Benchmark of issue 13's acceptance corpus: do the edits land?
//!
//! ```text
//! cargo run --release --example bench_fidelity -- [--energy position|tensor|both]
//!     [--cases NAME,...] [--edits bend,expand,curve] [--small] [--dump DIR]
//!     [--solver JSON] [--field JSON] [--mesh FILE [--weld D]]... [--as-brushed [--toolpaths JSON]]
//! ```
//!
//! `--as-brushed` (issue 47) runs every edit instead as `grainline run` does with strokes
//! (`pipeline::run::run`, position energy): a brush of 0.8 % of the part's bounding-box diagonal
//! (`toolpaths.placement.width`), overlap 0.1, and prints each edit's fidelity as designed and
//! as brushed (the run report's `as_brushed.fidelity`: the same measure on the grain rebuilt
//! from the strokes), the singular triangles the strokes add, where the two highlights depart
//! most, and the time the as-brushed rebuild and its fidelity add to the run (the stages
//! `as-brushed` and `as-brushed fidelity` against the rest of the run's wall time).
//!
//! `--mesh FILE` (repeatable) runs the three edits on any mesh (OBJ, STL, PLY) instead of the
//! corpus, lit and placed as the shared meshes are (`corpus::mesh_case`): a part the corpus has
//! never seen. `--weld D` welds its vertices closer than D (file units) and accepts the
//! non-manifold vertices that leaves.
//!
//! `--toolpaths '{"carry_edits": "off"}'` merges further `toolpaths` keys into every
//! `--as-brushed` run's scene.
//! `--solver '{"smoothness": 1e-6}'` merges further `solver` keys into every case's settings,
//! `--field '{"fit_radius": 8}'` further `field` keys into every case's scene.
//! `--dump DIR` also writes each case's edited scene as `DIR/CASE-EDIT-ENERGY.json` (mesh path
//! absolute, a 768² preview with the key highlight curves and the edit's support drawn), so that
//! `grainline run DIR/CASE-EDIT-ENERGY.json --out-dir DIR` shows by eye what the figures say.
//!
//! For every part of the corpus (tests/corpus/mod.rs: generated bodies of revolution, curved
//! panels and flat sheets, with and without a 0.15 mm ripple, and the smooth meshes of
//! ../shared/meshes, skipped with a message when absent) the scene is built in memory and run
//! through the library's pipeline (`pipeline::prepare`, `pipeline::optimize::optimize_stage`, as
//! `grainline optimize` does) once per edit — a bend, an expand and a curve placed on the key
//! highlight by code — and per highlight energy (`solver.highlight_energy`; an energy this
//! build's scene loader does not know is skipped, and "tensor" then runs today's solver). Prints
//! a markdown table: the share of the target highlight within 0.05 r of the solved one, its
//! 95th-percentile distance (× r), the singular triangles inside the support before → after
//! (with the number the solved highlight forces, docs/math.md §10, when it is not 0),
//! the iterations, the stop reason and the wall time of the optimize stage (the edits, the solve
//! and the fidelity measure).
//!
//! Cases: body, body-ripple, panel, panel-ripple, sheet, sheet-ripple, spot, blub, bunny,
//! fandisk, rocker-arm, teapot. `--small` uses the test's coarse generated parts.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[path = "../tests/corpus/mod.rs"]
mod corpus;

use corpus::{Outcome, Size};

fn list(s: &str) -> Vec<String> {
    s.split(',').map(|x| x.trim().to_string()).filter(|x| !x.is_empty()).collect()
}

fn main() {
    let Args { energies, cases, tools, size, dump, meshes, weld, as_brushed } = parse_args();
    if let Some(t) = tools.iter().find(|t| !corpus::TOOLS.contains(&t.as_str())) {
        usage(&format!("unknown edit {t:?} (bend, expand, curve)"));
    }
    for e in &energies {
        match corpus::solver_settings(e) {
            Ok(Some((_, true))) => {}
            Ok(Some((_, false))) => eprintln!(
                "note: this build has no `solver.highlight_energy`; \"{e}\" runs today's solver"
            ),
            Ok(None) => {
                eprintln!("note: this build has no `solver.highlight_energy`; skipping \"{e}\"")
            }
            Err(m) => eprintln!("note: {m}"),
        }
    }
    let names = cases.as_deref();
    let all = gather_cases(size, names, &meshes, weld);
    let mut rows: Vec<Outcome> = Vec::new();
    let mut brushed_rows: Vec<corpus::BrushedOutcome> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    for case in &all {
        let t = std::time::Instant::now();
        let p = match corpus::prepare_case(case) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("{}: {e}", case.name);
                notes.push(format!("{}: {e}", case.name));
                continue;
            }
        };
        match &p.placement {
            Ok(pl) => eprintln!(
                "{}: {} vertices, field {:.2} s; C0 {} segments, stretch {:.1} mm, centre \
                 [{:.1}, {:.1}, {:.1}] clearance {:.1} mm, curve {} points; obstacles: {} \
                 boundary edges, {} creases, {} critical vertices, {} singular triangles",
                case.name,
                p.prepared.mesh.num_vertices(),
                t.elapsed().as_secs_f64(),
                pl.c0_segments,
                pl.stretch,
                pl.point.x,
                pl.point.y,
                pl.point.z,
                pl.clearance,
                pl.curve.len(),
                pl.obstacles[0],
                pl.obstacles[1],
                pl.obstacles[2],
                pl.obstacles[3]
            ),
            Err(e) => {
                eprintln!("{}: no placement: {e}", case.name);
                notes.push(format!("{}: no placement: {e}", case.name));
                continue;
            }
        }
        for tool in &tools {
            if as_brushed {
                match corpus::run_brushed(case, &p, tool) {
                    Ok(o) => {
                        eprintln!("  {}", brushed_row(&o));
                        brushed_rows.push(o);
                    }
                    Err(e) => notes.push(format!("{} {tool} as brushed: {e}", case.name)),
                }
                continue;
            }
            for energy in &energies {
                if let (Some(dir), Ok(pl)) = (&dump, &p.placement) {
                    dump_scene(dir, case, pl, tool, energy);
                }
                match corpus::run_edit(case, &p, tool, energy) {
                    Ok(Some(o)) => {
                        eprintln!("  {}", row(&o));
                        rows.push(o);
                    }
                    Ok(None) => {}
                    Err(e) => notes.push(format!("{} {tool} {energy}: {e}", case.name)),
                }
            }
        }
    }
    if as_brushed {
        print_brushed(&brushed_rows, &notes);
        return;
    }
    println!(
        "| case | V (+refined) | edit | energy | within 0.05 r | p95 (× r) | median (× r) | singular \
         before → after | iterations | stop | optimize stage (s) | prepare (s) |"
    );
    println!("|---|---:|---|---|---:|---:|---:|---:|---:|---|---:|---:|");
    for o in &rows {
        println!("{}", row(o));
    }
    let landed = rows
        .iter()
        .filter(|o| o.error.is_none() && o.figures.as_ref().is_some_and(|f| f.landed))
        .count();
    println!();
    println!(
        "{landed} of {} edits landed (within ≥ 0.9, p95 ≤ 0.10 r, no new singular triangle but \
         those forced).",
        rows.len()
    );
    for n in notes {
        println!("- {n}");
    }
}

/// The cases to run: the generated and shared corpus (`names` only, when given), or the
/// `--mesh` parts.
fn gather_cases(
    size: Size,
    names: Option<&[String]>,
    meshes: &[std::path::PathBuf],
    weld: Option<f64>,
) -> Vec<corpus::Case> {
    let mut all = Vec::new();
    if meshes.is_empty() {
        match corpus::generated_cases(size, names) {
            Ok(c) => all.extend(c),
            Err(e) => fail(&e),
        };
        match corpus::shared_cases(names) {
            Ok(c) => all.extend(c),
            Err(e) => fail(&e),
        }
    }
    for m in meshes {
        let name = m.file_stem().map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
        // Non-manifold vertices are accepted when a weld is asked for (welded patches, as
        // the teapot's, leave some).
        match corpus::mesh_case(&name, m, true, weld, weld.is_some()) {
            Ok(c) => all.push(c),
            Err(e) => fail(&format!("{}: {e}", m.display())),
        }
    }
    if let Some(n) = names {
        for want in n {
            if !all.iter().any(|c| &c.name == want) {
                eprintln!("note: no case named {want:?} (or its mesh is absent)");
            }
        }
    }
    all
}

/// The command line (see the module docs).
struct Args {
    energies: Vec<String>,
    cases: Option<Vec<String>>,
    tools: Vec<String>,
    size: Size,
    dump: Option<std::path::PathBuf>,
    meshes: Vec<std::path::PathBuf>,
    weld: Option<f64>,
    as_brushed: bool,
}

/// Reads the command line; `--field` and `--solver` are passed on to the corpus through the
/// environment.
fn parse_args() -> Args {
    let mut energies = vec!["position".to_string(), "tensor".to_string()];
    let mut cases: Option<Vec<String>> = None;
    let mut tools: Vec<String> = corpus::TOOLS.iter().map(|s| s.to_string()).collect();
    let mut size = Size::Full;
    let mut dump: Option<std::path::PathBuf> = None;
    let mut meshes: Vec<std::path::PathBuf> = Vec::new();
    let mut weld: Option<f64> = None;
    let mut as_brushed = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--energy" => match args.next().as_deref() {
                Some("both") => {}
                Some(e @ ("position" | "tensor")) => energies = vec![e.to_string()],
                other => usage(&format!("--energy takes position, tensor or both, got {other:?}")),
            },
            "--cases" => cases = Some(list(&args.next().unwrap_or_default())),
            "--edits" => tools = list(&args.next().unwrap_or_default()),
            "--small" => size = Size::Small,
            "--as-brushed" => as_brushed = true,
            "--dump" => dump = args.next().map(Into::into),
            "--mesh" => match args.next() {
                Some(m) => meshes.push(m.into()),
                None => usage("--mesh takes a mesh file"),
            },
            "--weld" => match args.next().and_then(|w| w.parse::<f64>().ok()) {
                Some(w) if w >= 0.0 => weld = Some(w),
                _ => usage("--weld takes a distance ≥ 0 in the file's units"),
            },
            "--field" => {
                let extra = args.next().unwrap_or_default();
                if !serde_json::from_str::<serde_json::Value>(&extra).is_ok_and(|v| v.is_object()) {
                    usage(&format!("--field takes a JSON object of `field` keys, got {extra:?}"));
                }
                // SAFETY: single-threaded here, before any thread starts.
                unsafe { std::env::set_var("GRAINLINE_CORPUS_FIELD", extra) }
            }
            "--toolpaths" => {
                let extra = args.next().unwrap_or_default();
                if !serde_json::from_str::<serde_json::Value>(&extra).is_ok_and(|v| v.is_object()) {
                    usage(&format!(
                        "--toolpaths takes a JSON object of `toolpaths` keys, got {extra:?}"
                    ));
                }
                // SAFETY: single-threaded here, before any thread starts.
                unsafe { std::env::set_var("GRAINLINE_CORPUS_TOOLPATHS", extra) }
            }
            // SAFETY: single-threaded here, before any thread starts.
            "--solver" => unsafe {
                std::env::set_var("GRAINLINE_CORPUS_SOLVER", args.next().unwrap_or_default())
            },
            "-h" | "--help" => usage(""),
            other => usage(&format!("unknown argument {other:?}")),
        }
    }
    Args { energies, cases, tools, size, dump, meshes, weld, as_brushed }
}

/// Writes the edited scene of one row (see `--dump`).
fn dump_scene(
    dir: &std::path::Path,
    case: &corpus::Case,
    pl: &corpus::Placement,
    tool: &str,
    energy: &str,
) {
    let Some((_, edit)) = corpus::edits_json(pl).into_iter().find(|(n, _)| *n == tool) else {
        return;
    };
    let name = format!("{}-{tool}-{energy}", case.name);
    let mut json = corpus::scene_json(case);
    json["edits"] = serde_json::json!([edit]);
    json["solver"] = serde_json::json!({ "highlight_energy": energy });
    json["render"] = serde_json::json!({
        "width": 768, "height": 768, "output": format!("{name}.png"),
        "effects": { "shading": true, "highlight_curves": {}, "edits": {} }
    });
    let _ = std::fs::create_dir_all(dir);
    let text = serde_json::to_string_pretty(&json).unwrap_or_default();
    if let Err(e) = std::fs::write(dir.join(format!("{name}.json")), text) {
        eprintln!("note: --dump: {e}");
    }
}

fn row(o: &Outcome) -> String {
    let energy = if o.energy_key { o.energy.clone() } else { format!("{} (today)", o.energy) };
    if let Some(e) = &o.error {
        return format!(
            "| {} | {} | {} | {} | – | – | – | – | – | error: {} | – | – |",
            o.case,
            o.vertices,
            o.edit,
            energy,
            e.replace('|', "/")
        );
    }
    let Some(f) = &o.figures else {
        return format!(
            "| {} | {} | {} | {} | – | – | – | – | – | no figures | – | – |",
            o.case, o.vertices, o.edit, energy
        );
    };
    let mono = if o.energy_monotone() { "" } else { ", energy rose" };
    let figs = if f.samples == 0 {
        format!("– | – | – ({})", f.note.as_deref().unwrap_or("nothing measured").replace('|', "/"))
    } else {
        let off = if f.off_part > 0 {
            let all = (f.off_part + f.samples) as f64;
            format!(" ({:.0} % out of reach)", 100.0 * f.off_part as f64 / all)
        } else {
            String::new()
        };
        format!("{:.1} %{off} | {:.3} | {:.3}", 100.0 * f.within, f.p95, f.median)
    };
    let forced = f.singular_forced_after.saturating_sub(f.singular_forced_before);
    let forced = if forced > 0 { format!(" ({forced} forced)") } else { String::new() };
    format!(
        "| {} | {} | {} | {} | {} | {} → {}{forced} | {} | {}{mono} | {:.2} | {:.2} |",
        o.case,
        vertices(o),
        o.edit,
        energy,
        figs,
        f.singular_before,
        f.singular_after,
        o.iterations,
        o.stop,
        o.seconds,
        o.prepare_seconds
    )
}

/// "V" or "V (+added)" when the mesh was refined inside the brush.
fn vertices(o: &Outcome) -> String {
    if o.vertices_added > 0 {
        format!("{} (+{})", o.vertices - o.vertices_added, o.vertices_added)
    } else {
        o.vertices.to_string()
    }
}

fn usage(msg: &str) -> ! {
    if !msg.is_empty() {
        eprintln!("error: {msg}");
    }
    eprintln!(
        "usage: bench_fidelity [--energy position|tensor|both] [--cases NAME,...] \
         [--edits bend,expand,curve] [--small] [--dump DIR] [--solver JSON] [--field JSON] \
         [--mesh FILE [--weld D]]... [--as-brushed [--toolpaths JSON]]"
    );
    std::process::exit(if msg.is_empty() { 0 } else { 2 });
}

fn fail(msg: &str) -> ! {
    eprintln!("error: {msg}");
    std::process::exit(1);
}

/// One edit's figures as designed and as brushed: "within / p95 / singular after".
fn brushed_row(o: &corpus::BrushedOutcome) -> String {
    let head = format!("| {} | {} | {} | {:.2} |", o.case, o.vertices, o.edit, o.width);
    if let Some(e) = &o.error {
        return format!("{head} error: {} | – | – | – | – | – | – |", e.replace('|', "/"));
    }
    let Some(f) = &o.fidelity else {
        return format!("{head} not measured | – | – | – | – | – | – |");
    };
    let figs = |x: &serde_json::Value| {
        if x["samples"].as_u64().unwrap_or(0) == 0 {
            return "–".to_string();
        }
        format!(
            "{:.1} % / {:.3} / {}{}",
            100.0 * x["within"].as_f64().unwrap_or(0.0),
            x["p95"].as_f64().unwrap_or(0.0),
            x["singular_after"],
            if x["landed"].as_bool() == Some(true) { "" } else { " ✗" }
        )
    };
    let dep = match f["departure"].as_object() {
        Some(d) => format!(
            "{:+.3} r at ({:.1}, {:.1}, {:.1}) face {}",
            d["value"].as_f64().unwrap_or(0.0),
            d["point"][0].as_f64().unwrap_or(0.0),
            d["point"][1].as_f64().unwrap_or(0.0),
            d["point"][2].as_f64().unwrap_or(0.0),
            d["face"]
        ),
        None => "–".to_string(),
    };
    let rest = o.wall_seconds - o.brushed_seconds - o.width_seconds;
    let carried = match &o.carrying {
        None => "–".to_string(),
        Some(c) => match c["width"].as_f64() {
            Some(w) => format!(
                "{w:.2} ({:.1} %, {:.2} s)",
                100.0 * c["as_brushed"]["within"].as_f64().unwrap_or(0.0),
                o.width_seconds
            ),
            None => format!(
                "none ≥ {:.2} ({:.2} s)",
                c["tried"]
                    .as_array()
                    .and_then(|t| t.last())
                    .and_then(|x| x.as_f64())
                    .unwrap_or(0.0),
                o.width_seconds
            ),
        },
    };
    format!(
        "{head} {} | {} | {:+} | {dep} | {carried} | {} | {:.2} | {:.2} | {:.3} | {:.1} % |",
        figs(&f["designed"]),
        figs(&f["as_brushed"]),
        f["singular_added"].as_i64().unwrap_or(0),
        o.strokes,
        o.trace_seconds,
        rest,
        o.brushed_seconds,
        100.0 * o.brushed_seconds / rest.max(1e-9)
    )
}

/// The as-brushed table (`--as-brushed`) and its summary.
fn print_brushed(rows: &[corpus::BrushedOutcome], notes: &[String]) {
    println!(
        "| case | V | edit | brush (mm) | designed: within / p95 / singular | as brushed: within / \
         p95 / singular | singular added | largest departure (as brushed − designed) | carried \
         by (mm; within, brush width stage) | strokes | toolpaths (s) | run without (s) | \
         as-brushed + fidelity (s) | added |"
    );
    println!("|---|---:|---|---:|---|---|---:|---|---|---:|---:|---:|---:|---:|");
    for o in rows {
        println!("{}", brushed_row(o));
    }
    let landed = |k: &str| {
        rows.iter()
            .filter(|o| o.fidelity.as_ref().is_some_and(|f| f[k]["landed"].as_bool() == Some(true)))
            .count()
    };
    let (d, b) = (landed("designed"), landed("as_brushed"));
    let worst = rows
        .iter()
        .map(|o| {
            o.brushed_seconds / (o.wall_seconds - o.brushed_seconds - o.width_seconds).max(1e-9)
        })
        .fold(0.0f64, f64::max);
    println!();
    println!(
        "{d} of {} edits land as designed, {b} as brushed; the as-brushed rebuild and its \
         fidelity add at most {:.1} % to a run.",
        rows.len(),
        100.0 * worst
    );
    for n in notes {
        println!("- {n}");
    }
}
