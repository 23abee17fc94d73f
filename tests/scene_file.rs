//! The scene file: strict reading with key paths and lines, range checks, the schema.

use std::path::Path;

use grainline::scene::{LoadedScene, Scene};
use grainline::Error;

fn parse(text: &str) -> Result<Scene, Error> {
    Scene::from_str(text, Path::new("scene.json"))
}

fn message(text: &str) -> String {
    parse(text).expect_err("the scene must be refused").to_string()
}

#[test]
fn minimal_scene_takes_documented_defaults() {
    let s = parse(r#"{"mesh": "part.obj", "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}}"#).unwrap();
    let m = s.mesh.as_ref().unwrap();
    assert_eq!(m.0.path, "part.obj");
    assert_eq!(m.0.scale, 1.0);
    assert_eq!(s.view.fov_deg, 35.0);
    assert_eq!(s.view.up, [0.0, 0.0, 1.0]);
    assert_eq!(s.field.critical_threshold, 0.9995);
    assert_eq!(s.units, grainline::mesh::Units::Mm);
}

#[test]
fn mesh_as_object_with_options() {
    let s = parse(
        r#"{"mesh": {"path": "p.obj", "weld": 0.001, "scale": 2},
            "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2], "model": "distant"}}"#,
    )
    .unwrap();
    assert_eq!(s.mesh.unwrap().0.weld, Some(0.001));
}

#[test]
fn unknown_key_names_its_path_and_line() {
    let m = message(
        "{\"mesh\": {\"path\": \"p.obj\",\n \"sclae\": 2},\n \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 1]}], \"view\": {\"eye\": [0, -5, 2]}}",
    );
    assert!(m.contains("mesh.sclae"), "{m}");
    assert!(m.contains("unknown field `sclae`"), "{m}");
    assert!(m.contains("scene.json:2"), "{m}");
    let m = message(
        r#"{"mesh": "p.obj", "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}, "feild": {}}"#,
    );
    assert!(m.contains("feild"), "{m}");
}

#[test]
fn wrong_type_names_the_key() {
    let m = message(r#"{"mesh": "p.obj", "view": {"eye": [0, "x", 2]}}"#);
    assert!(m.contains("view.eye[1]"), "{m}");
}

#[test]
fn syntax_error_names_the_line() {
    let m = message("{\"mesh\": \"p.obj\",\n\n \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 1]}], \"view\": {\"eye\": [0, -5, 2],}}");
    assert!(m.contains("scene.json:3"), "{m}");
}

#[test]
fn ranges_are_checked_with_key_paths() {
    for (text, key) in [
        (
            r#"{"mesh": "p.obj", "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2], "fov_deg": 190}}"#,
            "view.fov_deg",
        ),
        (r#"{"mesh": "p.obj", "view": {"eye": [0, 0, 0]}}"#, "view.target"),
        (r#"{"mesh": "p.obj", "view": {"eye": [0, 0, 5]}}"#, "view.up"),
        (
            r#"{"mesh": {"path": "p.obj", "scale": 0}, "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}}"#,
            "mesh.scale",
        ),
        (
            r#"{"mesh": "p.obj", "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}, "field": {"init": "world"}}"#,
            "field.world",
        ),
        (
            r#"{"mesh": "p.obj", "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}, "field": {"critical_threshold": 2}}"#,
            "field.critical_threshold",
        ),
        (
            r#"{"mesh": "p.obj", "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}, "field": {"fit_radius": 0}}"#,
            "field.fit_radius",
        ),
        (
            r#"{"mesh": {"path": "p.obj", "refine": {"turn": 2}}, "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}}"#,
            "mesh.refine.turn",
        ),
        (
            r#"{"lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}}"#,
            "mesh",
        ),
        (
            r#"{"mesh": "p.obj", "outline": {"path": "o.svg"}, "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}}"#,
            "outline",
        ),
    ] {
        let m = message(text);
        assert!(m.starts_with(&format!("scene.json: {key}")), "{key}: {m}");
    }
}

#[test]
fn relative_paths_resolve_against_the_scene_file() {
    let dir = std::env::temp_dir().join(format!("grainline-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("s.json");
    std::fs::write(&p, r#"{"mesh": "meshes/p.obj", "lights": [{"type": "directional", "direction": [0, 0, 1]}], "view": {"eye": [0, -5, 2]}}"#).unwrap();
    let s = LoadedScene::read(&p).unwrap();
    assert_eq!(s.input("meshes/p.obj"), dir.join("meshes/p.obj"));
    let missing = LoadedScene::read(&dir.join("nope.json")).unwrap_err().to_string();
    assert!(missing.contains("nope.json"), "{missing}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn schema_lists_every_top_level_key() {
    let schema = grainline::scene::json_schema();
    let props = schema["properties"].as_object().expect("properties");
    for key in ["mesh", "outline", "units", "material", "lights", "view", "field", "edits"] {
        assert!(props.contains_key(key), "{key} missing from the schema");
    }
    assert_eq!(schema["additionalProperties"], serde_json::Value::Bool(false));
}

#[test]
fn published_schema_is_current() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene.schema.json");
    let published = std::fs::read_to_string(&path).unwrap_or_default();
    let current = grainline::scene::json_schema_text();
    if std::env::var_os("GRAINLINE_BLESS").is_some() {
        std::fs::write(&path, &current).unwrap();
        return;
    }
    assert!(
        published == current,
        "docs/scene.schema.json is stale: run `grainline schema --out docs/scene.schema.json` \
         (or GRAINLINE_BLESS=1 cargo test --test scene_file)"
    );
}
