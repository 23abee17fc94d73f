//! Issue 46, item 6: every key of the example scenes, given a wrong type, an empty value, a
//! huge number, a NaN-like string or an out-of-range value, is either read or refused with a
//! message that names the scene file and that key (or the list item or section holding it), in
//! the scene's terms: no serde wording (`expected value`, `u32`, `struct`, `invalid length`),
//! no "line 0", one line of reasonable length. Every variant of every key is tried (no sampling),
//! in-process, in well under a second.

use std::path::{Path, PathBuf};

use grainline::scene::Scene;
use serde_json::{json, Value};

fn example_scenes() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path().join("scene.json"))
        .filter(|p| p.exists())
        .collect();
    v.sort();
    assert!(v.len() >= 4, "{v:?}");
    v
}

/// Every key path of `v` (`edits[0].radius`) with its JSON pointer, parents before children.
fn keys(v: &Value, key: &str, pointer: &str, out: &mut Vec<(String, String)>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let key = if key.is_empty() { k.clone() } else { format!("{key}.{k}") };
                let pointer = format!("{pointer}/{k}");
                out.push((key.clone(), pointer.clone()));
                keys(x, &key, &pointer, out);
            }
        }
        Value::Array(a) => {
            // The first two items: lists of numbers stop at the vector itself.
            for (i, x) in a.iter().enumerate().take(2) {
                if x.is_object() || x.is_array() {
                    let key = format!("{key}[{i}]");
                    let pointer = format!("{pointer}/{i}");
                    out.push((key.clone(), pointer.clone()));
                    keys(x, &key, &pointer, out);
                }
            }
        }
        _ => {}
    }
}

/// The bad values tried for a key holding `v`.
fn variants(v: &Value) -> Vec<Value> {
    let mut out = vec![json!(null), json!("NaN"), json!(""), json!([]), json!({}), json!(true)];
    match v {
        Value::Number(_) => out.extend([json!(1e308), json!(-1e308), json!(0), json!(-1)]),
        Value::String(_) => out.extend([json!(5), json!("\u{1b}[31m"), json!("/")]),
        Value::Array(a) => {
            let mut longer = a.clone();
            longer.push(json!(1));
            out.extend([Value::Array(longer), json!([1e308, 1e308, 1e308]), json!(["a", "b"])]);
        }
        Value::Object(_) => out.push(json!([1, 2, 3])),
        _ => out.push(json!(5)),
    }
    out
}

/// The key paths a message may name for `key`: itself and its ancestors, longest first.
fn ancestors(key: &str) -> Vec<String> {
    let mut out = vec![key.to_string()];
    let mut k = key.to_string();
    while let Some(i) = k.rfind(['.', '[']) {
        k.truncate(i);
        out.push(k.clone());
    }
    out
}

#[test]
fn every_key_of_every_example_is_refused_in_the_scene_s_terms() {
    let mut tried = 0;
    let mut failures = Vec::new();
    for path in example_scenes() {
        let text = std::fs::read_to_string(&path).unwrap();
        let scene: Value = serde_json::from_str(&text).unwrap();
        let mut all = Vec::new();
        keys(&scene, "", "", &mut all);
        for (key, pointer) in all {
            let old = scene.pointer(&pointer).unwrap().clone();
            for bad in variants(&old) {
                let mut s = scene.clone();
                *s.pointer_mut(&pointer).unwrap() = bad.clone();
                let text = serde_json::to_string_pretty(&s).unwrap();
                tried += 1;
                let Err(e) = Scene::from_str(&text, Path::new("fuzz.json")) else { continue };
                let e = e.to_string();
                let named = ancestors(&key).iter().any(|k| e.contains(k.as_str()));
                let serde_words = [
                    "expected value",
                    "invalid length",
                    "expected u32",
                    "expected u64",
                    "expected f64",
                    "expected struct",
                    "trailing characters",
                    "expected usize",
                ]
                .iter()
                .any(|w| e.contains(w));
                if !e.starts_with("fuzz.json")
                    || !named
                    || serde_words
                    || e.contains(":0:")
                    || e.contains('\n')
                    || e.len() > 800
                {
                    failures.push(format!("{} {key} = {bad}: {e}", path.display()));
                }
            }
        }
    }
    assert!(tried > 500, "{tried}");
    assert!(
        failures.is_empty(),
        "{} of {tried} messages do not name their key in the scene's terms:\n{}",
        failures.len(),
        failures.iter().take(40).cloned().collect::<Vec<_>>().join("\n")
    );
}
