//! Issue 47, acceptance line 2: the run report's as-brushed fidelity agrees with an outside
//! measure — the as-brushed glb read as a viewer reads it.
//!
//! The part is the corpus's coarse kettle-like body (tests/corpus: `body`, `Size::Small`) with
//! the corpus's S-curve across its key highlight (radius 2 % of the diagonal), brushed with a
//! brush of 0.8 % of the diagonal (overlap 0.1). Its strokes lose part of the edit (about 83 %
//! of the target within 0.05 r as brushed, 100 % as designed), so the check tells the two apart.
//!
//! 1. `grainline run SCENE --report R` writes the report (`as_brushed.fidelity`) and FIELD.json.
//! 2. `grainline export SCENE --glb F --as-brushed` writes the grain rebuilt from the strokes.
//! 3. The glb is read with the `gltf` crate as a viewer reads KHR_materials_anisotropy: per glTF
//!    vertex the `anisotropyTexture` sampled bilinearly at TEXCOORD_0, RG mapped to [−1, 1], is
//!    the anisotropy direction d = x·T + y·B in the frame of TANGENT (T, w) and NORMAL (N),
//!    B = w·(N × T), turned by `anisotropyRotation` (0); the grain is across it, u = N × d
//!    (docs/gltf.md); where the texture's strength (B) is below ½ the viewer shows no grain, and
//!    those must be exactly the vertices the report counts beyond the brush's reach. The glb's
//!    triangles are the mesh's faces in order (FIELD.json's `faces`), so each glTF corner names
//!    its mesh vertex; a vertex written more than once (a UV seam) takes the sum of its copies'
//!    lines, each turned to agree with the first (and none if any copy shows none).
//! 4. The edit is measured on that grain with the library's published measure
//!    (`grainline::fidelity::edit_fidelity`), on the part, key light and edit shape the library
//!    prepares for the scene, and compared with the report's `as_brushed` figures.
//!
//! **Tolerance: 0.02 in `within`, 0.01 r in p95.** The viewer does not see the per-vertex grain:
//! it sees the texture, baked per texel from the corners' grain interpolated at the texel's
//! centre and read back bilinearly, so at a vertex it reads the grain of points up to about a
//! texel away (the body's 4096² texture: ≈ 0.09 mm around the body, 0.017 r of the curve's brush
//! radius r ≈ 5.3 mm), 16-bit quantized, in f32 frames, and a seam vertex's copies are merged.
//! Where the as-brushed grain turns quickly (between strokes, at a stroke's end) that moves the
//! highlight's zero crossing by a small fraction of r, and the samples lying that close to the
//! 0.05 r threshold may change side. Measured: 0.830 (report) against 0.831 (glb) within, p95
//! 0.1131 against 0.1132 r; the bounds leave twenty and a hundred times that. The designed and
//! as-brushed figures differ by 17 points, eight times the bound, so a report that gave the
//! designed figure as the as-brushed one, or an export that wrote the designed grain, fails.

use std::path::Path;

mod common;
mod corpus;
#[allow(dead_code)]
#[path = "support/glb_texture.rs"]
mod glb_texture;

use common::{grainline, ok, read_json, scratch_dir};
use glb_texture::{glb_json, read_texture};
use grainline::fidelity::{edit_fidelity, FidelityOptions};
use grainline::pipeline::optimize::optimize_stage;
use grainline::pipeline::{prepare_with, Silent, StagePlan, Stages};
use grainline::scene::LoadedScene;
use nalgebra::Vector3;
use serde_json::Value;

type V3 = Vector3<f64>;

/// Largest difference between the report's `within` and the viewer's.
const WITHIN_TOLERANCE: f64 = 0.02;
/// Largest difference between the report's p95 and the viewer's, units of r.
const P95_TOLERANCE: f64 = 0.01;

/// The grain a viewer shows at each vertex of the mesh whose `faces` and `positions` FIELD.json
/// gives, read from the glb (see the module docs); the zero vector where none was read.
fn viewer_grain(glb: &Path, faces: &[[usize; 3]], positions: &[V3]) -> Vec<V3> {
    let bytes = std::fs::read(glb).unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.as_deref().unwrap();
    let doc = glb_json(&bytes);
    let ext = &doc["materials"][0]["extensions"]["KHR_materials_anisotropy"];
    let rot = ext["anisotropyRotation"].as_f64().unwrap_or(0.0);
    let tex = &ext["anisotropyTexture"];
    assert_eq!(tex["texCoord"].as_u64().unwrap_or(0), 0, "{ext}");
    let texture = read_texture(&doc, blob, tex["index"].as_u64().unwrap() as usize);
    eprintln!("anisotropyTexture: {0} × {0} texels", texture.size);
    let prim = g.meshes().next().unwrap().primitives().next().unwrap();
    let reader = prim.reader(|_| Some(blob));
    let p: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    let n: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
    let t: Vec<[f32; 4]> = reader.read_tangents().unwrap().collect();
    let uv: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
    let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
    assert_eq!(idx.len(), 3 * faces.len(), "the glb's triangles are the mesh's faces");
    let v3 = |a: [f32; 3]| V3::new(a[0].into(), a[1].into(), a[2].into());
    // Per glTF vertex, the grain the viewer shades with.
    let seen: Vec<V3> = (0..p.len())
        .map(|k| {
            let (nn, tt, w) = (v3(n[k]), v3([t[k][0], t[k][1], t[k][2]]), f64::from(t[k][3]));
            let b = nn.cross(&tt) * w;
            let st = uv[k].map(f64::from);
            // Where the strength falls to zero the viewer shades isotropic metal: no grain.
            if texture.sample_strength(st) < 0.5 {
                return V3::zeros();
            }
            let [x, y] = texture.sample(st);
            let a = y.atan2(x) + rot;
            let d = tt * a.cos() + b * a.sin();
            nn.cross(&d).try_normalize(1e-12).unwrap_or_default()
        })
        .collect();
    let mut u = vec![V3::zeros(); positions.len()];
    let mut first: Vec<Option<V3>> = vec![None; positions.len()];
    let mut bare = vec![false; positions.len()];
    for (f, face) in faces.iter().enumerate() {
        for (c, &v) in face.iter().enumerate() {
            let k = idx[3 * f + c] as usize;
            let q = v3(p[k]);
            let err = (q - positions[v]).norm();
            assert!(err <= 1e-5 * (1.0 + positions[v].norm()), "vertex {v}: glb {q:?}");
            let s = seen[k];
            bare[v] |= s.norm_squared() == 0.0;
            let r = *first[v].get_or_insert(s);
            u[v] += if s.dot(&r) < 0.0 { -s } else { s };
        }
    }
    // A vertex bare in any of its copies was not brushed.
    u.iter()
        .zip(&bare)
        .map(|(x, &b)| if b { V3::zeros() } else { x.try_normalize(1e-12).unwrap_or_default() })
        .collect()
}

#[test]
fn report_as_brushed_fidelity_agrees_with_the_glb_a_viewer_reads() {
    let cases = corpus::generated_cases(corpus::Size::Small, Some(&["body".to_string()])).unwrap();
    let case = &cases[0];
    let p = corpus::prepare_case(case).unwrap();
    let (mut json, width) = corpus::brushed_scene_json(case, &p, "curve").unwrap();
    let d = scratch_dir("brushed-outside", "body-curve");
    json["field"]["output"] = "field.json".into();
    let scene_path = d.join("scene.json");
    std::fs::write(&scene_path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
    let sc = scene_path.to_str().unwrap();
    let report_path = d.join("report.json");
    ok(&grainline(&["--quiet", "run", sc, "--report", report_path.to_str().unwrap()]));
    let glb = d.join("brushed.glb");
    ok(&grainline(&["--quiet", "export", sc, "--glb", glb.to_str().unwrap(), "--as-brushed"]));
    let report = read_json(&report_path);
    let field = read_json(&d.join("field.json"));
    let reported = &report["as_brushed"]["fidelity"][0];
    assert_eq!(reported["tool"], "curve", "{}", report["as_brushed"]);

    // The grain the viewer shows, per vertex of the mesh FIELD.json describes.
    let positions = common::json_vectors(&field, "position");
    let faces: Vec<[usize; 3]> = field["faces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| [0, 1, 2].map(|c| f[c].as_u64().unwrap() as usize))
        .collect();
    let seen = viewer_grain(&glb, &faces, &positions);
    // The vertices the viewer shows bare are the ones the report says the brush never reached.
    let unseen = seen.iter().filter(|u| u.norm_squared() == 0.0).count();
    let beyond = report["as_brushed"]["beyond_reach_vertices"].as_u64().unwrap() as usize;
    assert_eq!(unseen, beyond, "vertices without a grain in the glb");

    // The part, key light and edit as the library prepares them for this scene.
    let loaded = LoadedScene::read(&scene_path).unwrap();
    let plan = StagePlan::of(&loaded.scene);
    let mut stages = Stages::new(&Silent);
    let prepared = prepare_with(&loaded, &mut stages, &plan).unwrap();
    assert_eq!(prepared.mesh.num_vertices(), positions.len());
    let o = optimize_stage(&loaded, &prepared, &mut stages).unwrap();
    let geometry = &prepared.field.geometry;
    let edit = &o.report.edits[0];
    let viewer = edit_fidelity(
        &prepared.mesh,
        geometry,
        &o.h,
        prepared.field_options.symmetry,
        &geometry.directions_of(&o.phi_before),
        &seen,
        edit.index,
        &edit.tool,
        edit.shape.as_ref().unwrap(),
        &FidelityOptions::default(),
    )
    .unwrap();

    let f = |v: &Value, k: &str| v[k].as_f64().unwrap();
    let (designed, brushed) = (&reported["designed"], &reported["as_brushed"]);
    eprintln!(
        "brush {width:.2} mm; within / p95: designed {:.4} / {:.4}, as brushed (report) {:.4} / \
         {:.4}, the glb as a viewer reads it {:.4} / {:.4}; singular {} (report) vs {} (glb)",
        f(designed, "within"),
        f(designed, "p95"),
        f(brushed, "within"),
        f(brushed, "p95"),
        viewer.within,
        viewer.p95,
        brushed["singular_after"],
        viewer.singular_after
    );
    assert_eq!(viewer.samples as u64, brushed["samples"].as_u64().unwrap());
    assert!(
        (viewer.within - f(brushed, "within")).abs() <= WITHIN_TOLERANCE,
        "within: report {} vs glb {}",
        f(brushed, "within"),
        viewer.within
    );
    assert!(
        (viewer.p95 - f(brushed, "p95")).abs() <= P95_TOLERANCE,
        "p95: report {} vs glb {}",
        f(brushed, "p95"),
        viewer.p95
    );
    // The case tells the two fields apart: the designed figure is far outside the tolerance.
    assert!(
        (f(designed, "within") - viewer.within).abs() > 3.0 * WITHIN_TOLERANCE,
        "the strokes keep the edit here: the check cannot tell designed from as brushed"
    );
    std::fs::remove_dir_all(&d).ok();
}

/// The run measures its edits as brushed by default, FIELD.json carries the same figures as
/// the report, and `toolpaths.as_brushed_fidelity: "off"` leaves the rebuild and the measure
/// out; an unknown value is refused naming the key.
#[test]
fn the_run_measures_as_brushed_by_default_and_off_leaves_it_out() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scene: Value =
        serde_json::from_slice(&std::fs::read(root.join("examples/kettle/scene.json")).unwrap())
            .unwrap();
    scene["mesh"] = root.join("examples/data/kettle.obj").display().to_string().into();
    scene.as_object_mut().unwrap().remove("render");
    scene["field"]["output"] = "field.json".into();
    let d = scratch_dir("brushed-outside", "key");
    let run = |scene: &Value, name: &str| {
        let p = d.join(format!("{name}.json"));
        std::fs::write(&p, serde_json::to_vec(scene).unwrap()).unwrap();
        let r = d.join(format!("{name}-report.json"));
        let o =
            grainline(&["--quiet", "run", p.to_str().unwrap(), "--report", r.to_str().unwrap()]);
        (o, r)
    };
    let stages = |r: &Value| -> Vec<String> {
        r["stages"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["stage"].as_str().unwrap().into())
            .collect()
    };
    let (o, r) = run(&scene, "auto");
    ok(&o);
    let (report, field) = (read_json(&r), read_json(&d.join("field.json")));
    assert_eq!(report["plan"]["brushed_fidelity"], true);
    assert!(stages(&report).contains(&"as-brushed fidelity".to_string()));
    let f = &report["as_brushed"]["fidelity"];
    assert_eq!(f.as_array().map(Vec::len), Some(1), "{f}");
    assert_eq!((f[0]["index"].as_u64(), f[0]["tool"].as_str()), (Some(0), Some("bend")));
    // The designed figures are the optimize stage's.
    let designed = report["optimize"]["fidelity"][0]["within"].as_f64().unwrap();
    assert!((f[0]["designed"]["within"].as_f64().unwrap() - designed).abs() < 1e-9);
    assert_eq!(field["version"], 3);
    assert_eq!(&field["meta"]["diagnostics"]["fidelity"], f);
    scene["toolpaths"]["as_brushed_fidelity"] = "off".into();
    let (o, r) = run(&scene, "off");
    ok(&o);
    let (report, field) = (read_json(&r), read_json(&d.join("field.json")));
    assert_eq!(report["plan"]["brushed_fidelity"], false);
    assert!(!stages(&report).iter().any(|s| s.starts_with("as-brushed")), "{:?}", stages(&report));
    assert!(report["as_brushed"].is_null(), "{}", report["as_brushed"]);
    assert!(field["meta"]["diagnostics"].get("fidelity").is_none());
    scene["toolpaths"]["as_brushed_fidelity"] = "sometimes".into();
    let (o, _) = run(&scene, "bad");
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("toolpaths.as_brushed_fidelity"), "{e}");
    std::fs::remove_dir_all(&d).ok();
}

/// A brush too wide for an edit (issue 47, item 2): the run traces again with narrower brushes
/// and names the widest that carries the edit, in its warning and in the report; a second run
/// with that width in the scene lands the edit as brushed with the figures the first reported.
/// With `carry_edits: "straddle"` the placement puts strokes beside the highlight first.
#[test]
fn a_brush_too_wide_is_named_with_the_width_that_carries_the_edit() {
    let cases = corpus::generated_cases(corpus::Size::Small, Some(&["body".to_string()])).unwrap();
    let case = &cases[0];
    let p = corpus::prepare_case(case).unwrap();
    let (mut json, width) = corpus::brushed_scene_json(case, &p, "curve").unwrap();
    let d = scratch_dir("brushed-outside", "width");
    let run = |json: &Value, name: &str| {
        let scene = d.join(format!("{name}.json"));
        std::fs::write(&scene, serde_json::to_vec_pretty(json).unwrap()).unwrap();
        let r = d.join(format!("{name}-report.json"));
        let o = grainline(&["run", scene.to_str().unwrap(), "--report", r.to_str().unwrap()]);
        ok(&o);
        (read_json(&r), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (report, stderr) = run(&json, "wide");
    let f = &report["as_brushed"]["fidelity"][0];
    assert_eq!(f["designed"]["landed"], true, "{f}");
    assert_eq!(f["as_brushed"]["landed"], false, "the test needs a brush too wide: {f}");
    let c = &report["as_brushed"]["carrying_width"][0];
    assert_eq!(c["index"], 0, "{}", report["as_brushed"]);
    let tried: Vec<f64> =
        c["tried"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let carried = c["width"].as_f64().unwrap_or_else(|| panic!("no width carries it: {c}"));
    assert!(tried.windows(2).all(|w| w[1] < w[0]) && tried[0] < width, "{tried:?} from {width}");
    assert_eq!(carried, *tried.last().unwrap());
    assert!(carried >= width / 8.0, "{carried}");
    assert_eq!(c["as_brushed"]["landed"], true, "{c}");
    assert!(
        report["stages"].as_array().unwrap().iter().any(|s| s["stage"] == "brush width"),
        "{}",
        report["stages"]
    );
    // Three significant digits, as the warning writes a length.
    let digits = (2 - carried.log10().floor() as i32).clamp(0, 6) as usize;
    let named = format!("a brush {carried:.digits$} mm wide carries it");
    let warning = stderr.lines().find(|l| l.contains("not as brushed")).unwrap_or_default();
    assert!(warning.contains(&named), "{named} in {warning}");

    // The same scene with that brush: the edit lands as brushed, with the same figures.
    json["toolpaths"]["placement"]["width"] = carried.into();
    let (again, _) = run(&json, "carried");
    let g = &again["as_brushed"]["fidelity"][0]["as_brushed"];
    assert_eq!(g["landed"], true, "{g}");
    assert_eq!(g["within"], c["as_brushed"]["within"]);
    assert_eq!(g["p95"], c["as_brushed"]["p95"]);
    assert!(again["as_brushed"].get("carrying_width").is_none(), "{}", again["as_brushed"]);

    // Straddled: strokes half a spacing either side of the highlight where it runs along the
    // grain are placed first and counted; the edit is still measured the same way.
    json["toolpaths"]["placement"]["width"] = width.into();
    json["toolpaths"]["carry_edits"] = "straddle".into();
    let (straddled, _) = run(&json, "straddle");
    let n = straddled["toolpaths"]["job"]["straddle_strokes"].as_u64().unwrap_or(0);
    assert!(n >= 2, "{}", straddled["toolpaths"]["job"]);
    assert!(report["toolpaths"]["job"].get("straddle_strokes").is_none());
    std::fs::remove_dir_all(&d).ok();
}
