//! The code's structure, read from the sources: the layer order of src's top-level modules
//! written in the crate docs (src/lib.rs, "Layers") is the one the code obeys — no module uses
//! one on its own or a higher layer, and no set of modules uses each other in a cycle —, the files of
//! toolpaths/src and of every folder of src and toolpaths/src form no cycle, nothing is
//! imported through a re-export of src/lib.rs, and no function outside tests (nor an
//! example's `main`) is longer than 120 lines.
//!
//! A use is any `crate::name` path in code (comments, doc links and `#[cfg(test)]` items are
//! not code). The checks are plain text scans: they need no build of the crate they read.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_FUNCTION_LINES: usize = 120;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `text` with comments, string and char literals blanked (newlines kept, so line numbers
/// stay), and every `#[cfg(test)]` item removed.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    let blank = |out: &mut Vec<u8>, c: u8| out.push(if c == b'\n' { b'\n' } else { b' ' });
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                out.push(b' ');
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                    depth += 1;
                    out.extend([b' ', b' ']);
                    i += 2;
                } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                    depth -= 1;
                    out.extend([b' ', b' ']);
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
        } else if c == b'r' && matches!(b.get(i + 1), Some(b'"') | Some(b'#')) && !ident(b, i) {
            // A raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&b'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&b'"') {
                out.push(c);
                i += 1;
                continue;
            }
            let close: Vec<u8> =
                std::iter::once(b'"').chain(std::iter::repeat_n(b'#', hashes)).collect();
            out.extend(std::iter::repeat_n(b' ', j + 1 - i));
            i = j + 1;
            while i < b.len() && !b[i..].starts_with(&close) {
                blank(&mut out, b[i]);
                i += 1;
            }
            out.extend(std::iter::repeat_n(b' ', close.len().min(b.len() - i)));
            i += close.len();
        } else if c == b'"' {
            out.push(b' ');
            i += 1;
            while i < b.len() && b[i] != b'"' {
                if b[i] == b'\\' {
                    blank(&mut out, b[i]);
                    i += 1;
                }
                if i < b.len() {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
            out.push(b' ');
            i += 1;
        } else if c == b'\'' && char_literal_len(b, i).is_some() {
            let n = char_literal_len(b, i).unwrap();
            out.extend(std::iter::repeat_n(b' ', n));
            i += n;
        } else {
            out.push(c);
            i += 1;
        }
    }
    let text = String::from_utf8(out).unwrap();
    remove_test_items(&text)
}

fn ident(b: &[u8], i: usize) -> bool {
    i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')
}

/// The length of a char literal starting at `i` (`'x'`, `'\n'`, `'\u{..}'`, `'é'`), or `None`
/// for a lifetime.
fn char_literal_len(b: &[u8], i: usize) -> Option<usize> {
    if b.get(i + 1) == Some(&b'\\') {
        let end = (i + 2..(i + 12).min(b.len())).find(|&j| b[j] == b'\'')?;
        return Some(end + 1 - i);
    }
    // One UTF-8 character, then the closing quote.
    let first = *b.get(i + 1)?;
    let width = match first {
        0x00..=0x7f => 1,
        0xc0..=0xdf => 2,
        0xe0..=0xef => 3,
        _ => 4,
    };
    (b.get(i + 1 + width) == Some(&b'\'')).then_some(width + 2)
}

/// Blanks every item marked `#[cfg(test)]` (the attribute through the item's closing brace
/// or semicolon), keeping newlines.
fn remove_test_items(text: &str) -> String {
    let mut out = text.as_bytes().to_vec();
    let mut from = 0;
    while let Some(k) = text[from..].find("#[cfg(test)]") {
        let start = from + k;
        let end = item_end(text.as_bytes(), start + "#[cfg(test)]".len());
        for c in &mut out[start..end] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
        from = end;
    }
    String::from_utf8(out).unwrap()
}

/// The end (exclusive) of the item starting at or after `i`: its matching closing brace, or
/// its semicolon when it has no body.
fn item_end(b: &[u8], i: usize) -> usize {
    let mut depth = 0usize;
    for (j, &c) in b.iter().enumerate().skip(i) {
        match c {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return j + 1;
                }
            }
            b';' if depth == 0 => return j + 1,
            _ => {}
        }
    }
    b.len()
}

/// The first segment of every `prefix` path in `code`: `crate::mesh::Mesh` gives `mesh`,
/// `crate::{a::X, b}` gives `a` and `b`.
fn used_modules(code: &str, prefix: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    let b = code.as_bytes();
    let mut from = 0;
    while let Some(k) = code[from..].find(prefix) {
        let at = from + k;
        from = at + prefix.len();
        if ident(b, at) {
            continue;
        }
        if b.get(from) == Some(&b'{') {
            let end = item_end(b, from);
            let mut depth = 0;
            let mut word = String::new();
            let mut expect = true;
            for &c in &b[from..end] {
                match c {
                    b'{' => {
                        depth += 1;
                        expect = depth == 1;
                    }
                    b'}' => {
                        depth -= 1;
                        if !word.is_empty() {
                            found.insert(std::mem::take(&mut word));
                        }
                    }
                    b',' if depth == 1 => {
                        if !word.is_empty() {
                            found.insert(std::mem::take(&mut word));
                        }
                        expect = true
                    }
                    c if (c.is_ascii_alphanumeric() || c == b'_') && expect && depth == 1 => {
                        word.push(c as char)
                    }
                    _ => {
                        if !word.is_empty() {
                            found.insert(std::mem::take(&mut word));
                            expect = false;
                        }
                    }
                }
            }
        } else {
            let word: String = code[from..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !word.is_empty() {
                found.insert(word);
            }
        }
    }
    found
}

/// The layers written in src/lib.rs's docs: lines `//! N. `a`, `b` — …`, bottom first.
fn documented_layers() -> BTreeMap<String, usize> {
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).unwrap();
    let mut layers = BTreeMap::new();
    for line in lib.lines().filter_map(|l| l.strip_prefix("//! ")) {
        let Some((n, rest)) = line.split_once(". ") else { continue };
        let Ok(n) = n.trim().parse::<usize>() else { continue };
        let names = rest.split('—').next().unwrap_or("");
        for name in names.split('`').skip(1).step_by(2) {
            layers.insert(name.to_string(), n);
        }
    }
    layers
}

/// A module graph: who uses whom (a module's own files count as it).
type Graph = BTreeMap<String, BTreeMap<String, BTreeSet<String>>>;

fn add_uses(
    graph: &mut Graph,
    module: &str,
    file: &Path,
    uses: BTreeSet<String>,
    known: &BTreeSet<String>,
) {
    let entry = graph.entry(module.to_string()).or_default();
    for u in uses.into_iter().filter(|u| known.contains(u) && u != module) {
        entry.entry(u).or_default().insert(file.display().to_string());
    }
}

/// Every cycle's modules (strongly connected components with more than one module).
fn cycles(graph: &Graph) -> Vec<Vec<String>> {
    let names: Vec<&String> = graph.keys().collect();
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.to_string()];
        while let Some(m) = stack.pop() {
            for next in graph.get(&m).into_iter().flat_map(|e| e.keys()) {
                if seen.insert(next.clone()) {
                    stack.push(next.clone());
                }
            }
        }
        seen
    };
    let reaches: BTreeMap<&String, BTreeSet<String>> =
        names.iter().map(|n| (*n, reach(n))).collect();
    let mut out: Vec<Vec<String>> = Vec::new();
    for a in &names {
        if !reaches[a].contains(*a) || out.iter().any(|c| c.contains(a)) {
            continue;
        }
        let scc: Vec<String> = names
            .iter()
            .filter(|b| reaches[a].contains(**b) && reaches[*b].contains(*a))
            .map(|b| (*b).clone())
            .collect();
        out.push(scc);
    }
    out
}

fn src_graph() -> (Graph, BTreeSet<String>) {
    let src = root().join("src");
    let mut known = BTreeSet::new();
    for e in std::fs::read_dir(&src).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        if (p.is_dir() || p.extension().is_some_and(|x| x == "rs"))
            && name != "lib"
            && name != "main"
        {
            known.insert(name);
        }
    }
    // The binary's modules (src/cli, src/main.rs) use the library by name, not `crate::`.
    known.remove("cli");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut graph = Graph::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap();
        let top = rel.components().next().unwrap().as_os_str().to_string_lossy();
        let top = top.trim_end_matches(".rs").to_string();
        if !known.contains(&top) {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(&f).unwrap());
        add_uses(&mut graph, &top, rel, used_modules(&code, "crate::"), &known);
    }
    (graph, known)
}

#[test]
fn src_modules_use_only_their_layer_and_below() {
    let layers = documented_layers();
    let (graph, known) = src_graph();
    let missing: Vec<&String> = known.iter().filter(|m| !layers.contains_key(*m)).collect();
    assert!(missing.is_empty(), "modules missing from src/lib.rs's layer list: {missing:?}");
    let stale: Vec<&String> = layers.keys().filter(|m| !known.contains(*m)).collect();
    assert!(stale.is_empty(), "src/lib.rs's layer list names modules that do not exist: {stale:?}");
    let mut upward = Vec::new();
    for (m, uses) in &graph {
        for (u, files) in uses {
            if layers[u] >= layers[m] {
                upward.push(format!(
                    "{m} (layer {}) uses {u} (layer {}) in {files:?}",
                    layers[m], layers[u]
                ));
            }
        }
    }
    assert!(upward.is_empty(), "uses of the same or a higher layer:\n{}", upward.join("\n"));
    let c = cycles(&graph);
    assert!(c.is_empty(), "src's modules use each other in cycles: {c:?} ({graph:?})");
}

#[test]
fn toolpaths_files_form_no_cycle() {
    let src = root().join("toolpaths/src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let module = |f: &Path| {
        let rel = f.strip_prefix(&src).unwrap();
        let top = rel.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
        top.trim_end_matches(".rs").to_string()
    };
    let known: BTreeSet<String> = files.iter().map(|f| module(f)).filter(|m| m != "lib").collect();
    let mut graph = Graph::new();
    for f in &files {
        let m = module(f);
        if m == "lib" {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        let mut uses = used_modules(&code, "crate::");
        // A top-level file's `super::x` is its sibling `x`.
        if f.parent() == Some(src.as_path()) {
            uses.extend(used_modules(&code, "super::"));
        }
        add_uses(&mut graph, &m, f.strip_prefix(&src).unwrap(), uses, &known);
    }
    let c = cycles(&graph);
    assert!(c.is_empty(), "toolpaths' files use each other in cycles: {c:?}");
}

/// The module path (`crate::` segments) of the files directly in `dir`, a folder under the
/// crate's `src`: `src/mesh` is `mesh`, `src/edit/untangle` is `edit::untangle`.
fn folder_module(src: &Path, dir: &Path) -> String {
    let rel = dir.strip_prefix(src).unwrap();
    rel.components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("::")
}

/// The cycles among the files of one folder: a file uses a sibling through `super::x` or
/// through its full path (`crate::folder::x`). A folder's `mod.rs` (or `lib.rs`, `main.rs`)
/// is the folder's own module, not a sibling, and is left out.
fn folder_cycles(src: &Path, dir: &Path) -> Vec<Vec<String>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    files.sort();
    let stem = |p: &Path| p.file_stem().unwrap().to_string_lossy().into_owned();
    let facade = |name: &str| matches!(name, "mod" | "lib" | "main");
    let known: BTreeSet<String> = files.iter().map(|f| stem(f)).filter(|n| !facade(n)).collect();
    let module = folder_module(src, dir);
    let full = if module.is_empty() { "crate::".to_string() } else { format!("crate::{module}::") };
    let mut graph = Graph::new();
    for f in &files {
        let name = stem(f);
        if facade(&name) {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        let mut uses = used_modules(&code, "super::");
        uses.extend(used_modules(&code, &full));
        add_uses(&mut graph, &name, f.strip_prefix(src).unwrap(), uses, &known);
    }
    cycles(&graph)
}

fn folders(dir: &Path, out: &mut Vec<PathBuf>) {
    out.push(dir.to_path_buf());
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries.into_iter().filter(|p| p.is_dir()) {
        folders(&p, out);
    }
}

#[test]
fn the_files_of_a_folder_form_no_cycle() {
    let mut found = Vec::new();
    for crate_src in ["src", "toolpaths/src"] {
        let src = root().join(crate_src);
        let mut dirs = Vec::new();
        folders(&src, &mut dirs);
        for dir in dirs {
            for c in folder_cycles(&src, &dir) {
                found.push(format!("{}: {c:?}", dir.strip_prefix(root()).unwrap().display()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "files of one folder use each other in cycles:\n{}",
        found.join("\n")
    );
}

/// The names src/lib.rs re-exports (`pub use a::{B, c};` gives `B` and `c`).
fn lib_reexports() -> BTreeSet<String> {
    let lib = code_only(&std::fs::read_to_string(root().join("src/lib.rs")).unwrap());
    let mut names = BTreeSet::new();
    for item in lib.split(';').filter_map(|i| i.trim().strip_prefix("pub use ")) {
        let tail = item.rsplit("::").next().unwrap_or(item);
        for name in tail.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
            if !name.is_empty() && name != "self" {
                names.insert(name.to_string());
            }
        }
    }
    names
}

#[test]
fn nothing_is_imported_through_a_lib_reexport() {
    // The crate's error type is named at the top, as every crate names its own.
    let allowed = ["Error", "Result"];
    let reexports: BTreeSet<String> =
        lib_reexports().into_iter().filter(|n| !allowed.contains(&n.as_str())).collect();
    assert!(
        reexports.is_empty(),
        "src/lib.rs re-exports more than the error type: {reexports:?}; import each name \
         from the module that defines it"
    );
    let mut files = Vec::new();
    for dir in ["src", "examples", "tests"] {
        rust_files(&root().join(dir), &mut files);
    }
    let mut through = Vec::new();
    for f in files.iter().filter(|f| !f.ends_with("src/lib.rs")) {
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        // Outside src, `crate::` is the test's or the example's own crate.
        let prefixes: &[&str] = if f.starts_with(root().join("src")) {
            &["crate::", "grainline::"]
        } else {
            &["grainline::"]
        };
        for prefix in prefixes {
            for name in used_modules(&code, prefix) {
                let defined = root().join("src").join(&name);
                let module = defined.is_dir() || defined.with_extension("rs").is_file();
                if !module && !allowed.contains(&name.as_str()) {
                    through.push(format!(
                        "{}: {prefix}{name}",
                        f.strip_prefix(root()).unwrap().display()
                    ));
                }
            }
        }
    }
    through.sort();
    through.dedup();
    assert!(through.is_empty(), "imports through src/lib.rs's re-exports:\n{}", through.join("\n"));
}

/// Every `fn` item's first and last line in `code` (1-based), with its name.
fn functions(code: &str) -> Vec<(String, usize, usize)> {
    let b = code.as_bytes();
    let line_of = |i: usize| code[..i].bytes().filter(|&c| c == b'\n').count() + 1;
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("fn ") {
        let at = from + k;
        from = at + 3;
        if ident(b, at) {
            continue;
        }
        let name: String =
            code[from..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
        if name.is_empty() {
            continue; // `fn(` types
        }
        // The body: the first `{` before any `;` at depth 0 of brackets.
        let mut depth = 0i32;
        let mut body = None;
        for (j, &c) in b.iter().enumerate().skip(from) {
            match c {
                b'(' | b'[' | b'<' => depth += 1,
                b')' | b']' | b'>' if depth > 0 => depth -= 1,
                b';' if depth == 0 => break,
                b'{' if depth == 0 => {
                    body = Some(j);
                    break;
                }
                _ => {}
            }
        }
        let Some(open) = body else { continue };
        let end = item_end(b, open);
        out.push((name, line_of(at), line_of(end.saturating_sub(1))));
    }
    out
}

#[test]
fn no_function_outside_tests_is_longer_than_120_lines() {
    let mut files = Vec::new();
    for dir in ["src", "toolpaths/src"] {
        rust_files(&root().join(dir), &mut files);
    }
    let mut long = Vec::new();
    for f in &files {
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        for (name, first, last) in functions(&code) {
            let n = last + 1 - first;
            if n > MAX_FUNCTION_LINES {
                let rel = f.strip_prefix(root()).unwrap();
                long.push(format!("{}:{first} {name}: {n} lines", rel.display()));
            }
        }
    }
    assert!(long.is_empty(), "functions over {MAX_FUNCTION_LINES} lines:\n{}", long.join("\n"));
}

#[test]
fn no_example_main_is_longer_than_120_lines() {
    let mut files = Vec::new();
    rust_files(&root().join("examples"), &mut files);
    let mut long = Vec::new();
    for f in &files {
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        for (name, first, last) in functions(&code) {
            let n = last + 1 - first;
            if name == "main" && n > MAX_FUNCTION_LINES {
                let rel = f.strip_prefix(root()).unwrap();
                long.push(format!("{}:{first} main: {n} lines", rel.display()));
            }
        }
    }
    assert!(long.is_empty(), "example mains over {MAX_FUNCTION_LINES} lines:\n{}", long.join("\n"));
}

#[test]
fn the_scanner_sees_what_it_must() {
    let code = code_only(
        "use crate::{a::X, b};\n// crate::c\nfn f() { let s = \"crate::d\"; crate::e::g(); }\n\
         #[cfg(test)]\nmod tests { use crate::h; }\n",
    );
    let uses: Vec<String> = used_modules(&code, "crate::").into_iter().collect();
    assert_eq!(uses, ["a", "b", "e"]);
    let long = format!("fn big() {{\n{}}}\nfn small() {{ '}}'; }}\n", "    x();\n".repeat(130));
    let f = functions(&code_only(&long));
    assert_eq!(f[0], ("big".to_string(), 1, 132));
    assert_eq!(f[1].0, "small");
    let graph: Graph = [
        ("a".to_string(), [("b".to_string(), BTreeSet::new())].into_iter().collect()),
        ("b".to_string(), [("a".to_string(), BTreeSet::new())].into_iter().collect()),
    ]
    .into_iter()
    .collect();
    assert_eq!(cycles(&graph), [vec!["a".to_string(), "b".to_string()]]);
}
