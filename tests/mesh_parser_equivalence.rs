//! The parallel OBJ number parser against tobj, the reference reader: for the same file and
//! options, `load_obj_with(.., ObjParser::Parallel)` and `load_obj_with(.., ObjParser::Tobj)` must
//! give the same mesh and report bit for bit (Rust's `{:?}` of an `f64` is its exact
//! round-trip value, so comparing the debug text compares every bit but NaN payloads, and a
//! loaded mesh has no NaN), or the same error message. The corpus is generated (proptest) with
//! the forms OBJ files use: negative and relative indices, `v`, `v/vt`, `v//vn`, `v/vt/vn`,
//! polygons, comments, `o`/`g`, blank lines, CRLF, exponents, signs, tabs, `w`, and bad input.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use grainline::mesh::load::{load_obj_with, DegeneratePolicy, LoadOptions, ObjParser};
use proptest::prelude::*;

fn outcome(path: &Path, options: &LoadOptions, parser: ObjParser) -> String {
    match load_obj_with(path, options, parser) {
        Ok(m) => format!(
            "{:?}\n{:?}\n{:?}\n{:?}",
            m.mesh, m.report, m.report.source_vertex, m.report.face_line
        ),
        Err(e) => format!("error: {e}"),
    }
}

fn option_sets() -> Vec<LoadOptions> {
    let d = LoadOptions::default;
    vec![
        d(),
        d().tolerant(),
        LoadOptions { object: Some("second".into()), ..d() },
        LoadOptions { object: Some("unnamed_object".into()), ..d() },
        LoadOptions { weld: Some(0.05), ..d().tolerant() },
        LoadOptions { degenerate: DegeneratePolicy::Error, ..d() },
    ]
}

/// Asserts both readers agree on `text` under every option set; returns the default outcome.
fn assert_same(text: &str, name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("grainline-eq-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let mut first = None;
    for o in option_sets() {
        let a = outcome(&path, &o, ObjParser::Tobj);
        let b = outcome(&path, &o, ObjParser::Parallel);
        assert_eq!(a, b, "readers differ with {o:?} on:\n{text}");
        first.get_or_insert(a);
    }
    std::fs::remove_file(&path).ok();
    first.unwrap()
}

/// How one number is written.
fn write_number(out: &mut String, x: f64, style: u8) {
    match style % 7 {
        0 => write!(out, "{x:.6}"),
        1 => write!(out, "{x:e}"),
        2 => write!(out, "{:.3E}", x),
        3 => write!(out, "{x}"),
        4 if x >= 0.0 => write!(out, "+{x:.4}"),
        5 if x.fract() == 0.0 => write!(out, "{x:.0}."),
        _ => write!(out, "{x:.9}"),
    }
    .unwrap();
}

fn sep(out: &mut String, style: u8) {
    out.push_str(match style % 4 {
        0 | 1 => " ",
        2 => "\t",
        _ => "  \t ",
    });
}

fn end_line(out: &mut String, crlf: bool) {
    out.push_str(if crlf { "\r\n" } else { "\n" });
}

/// Parameters of one generated file.
#[derive(Debug, Clone)]
struct Spec {
    /// Grid side (vertices per row and column).
    n: usize,
    /// Per-vertex noise and number styles.
    seeds: Vec<u8>,
    /// 0: v, 1: v/vt, 2: v//vn, 3: v/vt/vn, 4: mixed per face.
    corner_form: u8,
    /// Write faces with relative (negative) indices.
    relative: bool,
    /// Quads instead of triangle pairs where the seed says so.
    quads: bool,
    crlf: bool,
    /// Split the faces into two objects, and name forms.
    objects: u8,
    /// A defect to insert: 0 none, 1 bad number, 2 w = 0, 3 index out of range, 4 nan,
    /// 5 forward reference, 6 `l` statement, 7 vertex colours (`r g b` on the first vertex,
    /// `r g b a` on the seed's), 8 `w` on every vertex,
    /// 9 vt after the first object, 10 a zero-area face, 11 a non-manifold fin.
    defect: u8,
}

fn generate(s: &Spec) -> String {
    let n = s.n;
    let mut out = String::new();
    let seed = |k: usize| s.seeds[k % s.seeds.len()];
    out.push_str("# generated\n\n");
    if s.objects % 3 == 1 {
        out.push_str("o first\n");
    } else if s.objects % 3 == 2 {
        out.push_str("  g   \n");
    }
    let forward = s.defect == 5;
    let mut vertices = String::new();
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            let z = (seed(k) as f64 - 128.0) / 97.0;
            let p = [i as f64 * 0.5, j as f64 * 0.25 - 1.0, z];
            if seed(k) % 5 == 0 {
                vertices.push('\t');
            }
            vertices.push('v');
            for c in p {
                sep(&mut vertices, seed(k * 7 + c.to_bits() as usize % 5));
                write_number(&mut vertices, c, seed(k * 3 + 1));
            }
            if s.defect == 8 || (s.defect == 2 && k == n) {
                vertices.push_str(if s.defect == 2 { " 0" } else { " 2.5" });
            }
            if s.defect == 7 && k == 0 {
                vertices.push_str(" 0.1 0.2 0.3");
            } else if s.defect == 7 && seed(k) % 3 == 0 {
                vertices.push_str(" 0 1 0.5 1");
            }
            if s.defect == 1 && k == n + 1 {
                vertices.push('x');
            }
            if s.defect == 4 && k == 2 {
                vertices = vertices.trim_end_matches(|c: char| c != ' ' && c != '\t').to_string();
                vertices.push_str("NaN");
            }
            end_line(&mut vertices, s.crlf && k.is_multiple_of(2));
            if seed(k) % 11 == 0 {
                vertices.push_str("# comment v 1 2\n\n");
            }
        }
    }
    let mut attrs = String::new();
    for k in 0..n * n {
        attrs.push_str("vt ");
        write_number(&mut attrs, (k % n) as f64 / n as f64, seed(k));
        attrs.push(' ');
        write_number(&mut attrs, (k / n) as f64 / n as f64, seed(k + 1));
        if seed(k) % 3 == 0 {
            attrs.push_str(" 0");
        }
        end_line(&mut attrs, s.crlf);
    }
    for k in 0..n * n {
        let z = 1.0 - (seed(k) as f64) / 512.0;
        write!(attrs, "vn 0 {:e} {z}", (seed(k) as f64) / 1024.0).unwrap();
        end_line(&mut attrs, s.crlf);
    }
    if !forward {
        out.push_str(&vertices);
        if s.defect != 9 {
            out.push_str(&attrs);
        }
    }
    let mut written = n * n; // entries of each kind written so far (for relative indices)
    if forward {
        written = 0;
    }
    let corner = |out: &mut String, v: usize, face: usize| {
        let form =
            if s.corner_form == 4 { (seed(face) % 4) as usize } else { s.corner_form as usize };
        let idx = |x: usize| {
            // (A relative index before the first `vt` makes tobj overflow in debug builds,
            // where the scanner refuses the file anyway: not generated.)
            if s.relative && !forward && s.defect != 9 {
                format!("-{}", written - x)
            } else {
                format!("{}", x + 1)
            }
        };
        let text = match form {
            0 => idx(v),
            1 => format!("{}/{}", idx(v), idx(v)),
            2 => format!("{}//{}", idx(v), idx(v)),
            _ => format!("{}/{}/{}", idx(v), idx(v), idx(v)),
        };
        sep(out, seed(face + v));
        out.push_str(&text);
    };
    let mut face = 0;
    for j in 0..n - 1 {
        if j == (n - 1) / 2 && s.objects % 2 == 1 {
            out.push_str(if s.objects % 4 == 1 { "o second\n" } else { "g second \r\n" });
            if s.defect == 9 {
                out.push_str(&attrs);
            }
        }
        for i in 0..n - 1 {
            let a = j * n + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n);
            if s.quads && seed(a) % 2 == 0 {
                out.push('f');
                for v in [a, b, c, d] {
                    corner(&mut out, v, face);
                }
                end_line(&mut out, s.crlf);
            } else {
                for tri in [[a, b, c], [a, c, d]] {
                    out.push('f');
                    for v in tri {
                        corner(&mut out, v, face);
                    }
                    end_line(&mut out, s.crlf);
                }
            }
            face += 1;
            if seed(face) % 13 == 0 {
                out.push_str("s 1\nusemtl steel\n\n");
            }
        }
    }
    match s.defect {
        3 => out.push_str(&format!("f 1 2 {}\n", n * n + 5)),
        6 => out.push_str("l 1 2\n"),
        10 => out.push_str("f 1 2 1\n"),
        11 => out.push_str(&format!("v 0.25 0.125 3\nf 1 2 {}\n", n * n + 1)),
        _ => {}
    }
    if forward {
        out.push_str(&vertices);
        out.push_str(&attrs);
    }
    if s.defect == 9 && s.objects.is_multiple_of(2) {
        out.push_str(&attrs);
    }
    out
}

fn spec() -> impl Strategy<Value = Spec> {
    (
        2usize..7,
        prop::collection::vec(any::<u8>(), 1..40),
        0u8..5,
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        0u8..6,
        prop_oneof![Just(0u8), 0u8..12],
    )
        .prop_map(|(n, seeds, corner_form, relative, quads, crlf, objects, defect)| Spec {
            n,
            seeds,
            corner_form,
            relative,
            quads,
            crlf,
            objects,
            defect,
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn parallel_parser_matches_tobj(s in spec()) {
        assert_same(&generate(&s), "gen.obj");
    }
}

/// Hand-picked forms, each checked for the outcome it must have.
#[test]
fn edge_forms_agree_and_load() {
    let ok = |text: &str| {
        let out = assert_same(text, "edge.obj");
        assert!(!out.starts_with("error"), "{out}\n{text}");
        out
    };
    // Tabs, CRLF, exponents, a leading '+', "1." and ".5", no final newline.
    let out = ok("v 0 0 0\r\nv\t1e0  0 +0\nv .5 1. 0\nf 1 2 3");
    assert!(out.contains("[0.5, 1.0, 0.0]"), "{out}");
    // `w` divides; `vt` ignores a third number; relative indices.
    let out =
        ok("v 0 0 0 2\nv 2 0 0 2\nv 0 4 0 2\nvt 0 0 7\nvt 1 0\nvt 0 1\nf -3/-3 -2/-2 -1/-1\n");
    assert!(out.contains("[1.0, 0.0, 0.0]") && out.contains("[0.0, 2.0, 0.0]"), "{out}");
    // An `o` line with leading whitespace names the object "o x" (tobj's rule), empty "o".
    let out = ok(" o x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\no\nf 1 3 4\n");
    assert!(out.contains("\"o x\"") && out.contains("unnamed_object"), "{out}");
    // Vertex colours (issue 46): r g b and r g b a on some vertices, beside a `w`; never a
    // weight.
    let out = ok("v 0 0 0 0 0 0\nv 2 0 0 0.1 0.2 0.3 1\nv 0 4 0 2\nv 0 0 1\nf 1 2 3\nf 2 1 4\n");
    assert!(out.contains("[2.0, 0.0, 0.0]") && out.contains("[0.0, 2.0, 0.0]"), "{out}");
    // The objects' names are the scanner's, as tobj forms them: `g` before any face renames.
    let out = ok("g a\ng b\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert!(out.contains("[\"b\"]"), "{out}");
}

#[test]
fn errors_agree() {
    let err = |text: &str, want: &str| {
        let out = assert_same(text, "err.obj");
        assert!(out.starts_with("error") && out.contains(want), "{out}\n{text}");
    };
    err("v 0 0 0\nv 1 0 zero\nv 0 1 0\nf 1 2 3\n", "err.obj:2: bad number");
    err("v 0 0 0\nv 1 0 0 0\nv 0 1 0\nf 1 2 3\n", "err.obj:2: vertex weight");
    err("v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n", "err.obj:2: vertex 2");
    err("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 x\nf 1/1 2/1 3/1\n", "err.obj:4: bad number");
    err("v 0 0 0\nv 1 0 0 1 1\nv 0 1 0\nf 1 2 3\n", "err.obj:2: vertex with 5 numbers");
    err("v 0 0 0\nv 1 0 0 inf\nv 0 1 0\nf 1 2 3\n", "err.obj:2: vertex weight w is inf");
    err("v 0 0 0 1 1 1\nv 1 0 x 1 1 1\nv 0 1 0\nf 1 2 3\n", "err.obj:2: bad number");
    err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "err.obj:4:");
    // An object with faces before any `vt`, then one with UVs: tobj gives the first object no
    // texture indices, which the loader refuses; the parallel reader must refuse it too.
    err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nvt 0 0\nf 1/1 3/1 2/1\n", "unsupported OBJ");
}

/// Every OBJ under tests/data, under every option set.
#[test]
fn test_data_files_agree() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "obj") {
            for o in option_sets() {
                let a = outcome(&p, &o, ObjParser::Tobj);
                assert_eq!(a, outcome(&p, &o, ObjParser::Parallel), "{}", p.display());
            }
            n += 1;
        }
    }
    assert!(n >= 10, "only {n} OBJ files found");
}

/// A file above the size threshold: `Auto` (the parallel parser) against tobj.
#[test]
fn large_file_auto_matches_tobj() {
    let s = Spec {
        n: 180,
        seeds: (0..=255).collect(),
        corner_form: 3,
        relative: false,
        quads: true,
        crlf: false,
        objects: 1,
        defect: 0,
    };
    let text = generate(&s);
    assert!(text.len() >= grainline::mesh::load::PARALLEL_MIN_BYTES, "{} bytes", text.len());
    let path = std::env::temp_dir().join(format!("grainline-eq-large-{}.obj", std::process::id()));
    std::fs::write(&path, &text).unwrap();
    let o = LoadOptions::default();
    let a = outcome(&path, &o, ObjParser::Tobj);
    assert!(!a.starts_with("error"), "{}", &a[..200.min(a.len())]);
    assert_eq!(a, outcome(&path, &o, ObjParser::Auto));
    std::fs::remove_file(&path).ok();
}

/// `text` as an exporter might write it (issue 15 item 17) and the plain text it must load as:
/// 0 a UTF-8 byte-order mark, 1 CR-only line ends, 2 a trailing `# comment` on every `v`/`f`
/// line, 3 every face continued with `\` before its last corner (the plain text then has a
/// blank line after each face, so that both have the same lines).
fn exporter_form(text: &str, form: u8) -> (String, String) {
    match form {
        0 => (text.to_string(), format!("\u{feff}{text}")),
        1 => (text.to_string(), text.replace("\r\n", "\r").replace('\n', "\r")),
        _ => {
            let (mut plain, mut out) = (String::new(), String::new());
            for line in text.split_inclusive('\n') {
                let (body, end) = line.split_at(line.trim_end_matches(['\r', '\n']).len());
                let end = if end.is_empty() { "\n" } else { end };
                let is = |k: &str| body.starts_with(k) && body[k.len()..].starts_with([' ', '\t']);
                if form == 2 && (is("v") || is("f")) {
                    plain += &format!("{body}{end}");
                    out += &format!("{body} # exported{end}");
                } else if form == 3 && is("f") {
                    let cut = body.trim_end().rfind([' ', '\t']).unwrap();
                    plain += &format!("{body}{end}{end}");
                    out += &format!("{} \\{end}{}{end}", &body[..cut], &body[cut..]);
                } else {
                    plain += &format!("{body}{end}");
                    out += &format!("{body}{end}");
                }
            }
            (plain, out)
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, ..ProptestConfig::default() })]

    /// Each exporter form loads exactly as the plain file does — same mesh, report, face lines
    /// or error — with both readers.
    #[test]
    fn item17_exporter_forms_load_as_the_plain_file(s in spec(), form in 0u8..4) {
        let (plain, exported) = exporter_form(&generate(&s), form);
        let want = assert_same(&plain, "form.obj");
        let got = assert_same(&exported, "form.obj");
        prop_assert_eq!(got, want);
    }
}

#[test]
fn item17_bom_is_accepted() {
    let plain = assert_same("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "a.obj");
    assert!(!plain.starts_with("error"), "{plain}");
    assert_eq!(assert_same("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "b.obj"), plain);
}

#[test]
fn item17_cr_only_line_endings_are_accepted() {
    let out = assert_same("v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r", "cr.obj");
    assert!(out.contains("[1.0, 0.0, 0.0]") && out.contains("[0.0, 1.0, 0.0]"), "{out}");
    // Errors keep the editor's line numbers: the bad index is on line 4.
    let err = assert_same("v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 9\r", "cr.obj");
    assert!(err.starts_with("error") && err.contains("cr.obj:4:"), "{err}");
}

#[test]
fn item17_backslash_continuation_lines_are_accepted() {
    let out = assert_same(
        "v 0 0 \\\n 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n2 \\\n  3\nv 5 5 5\nf 2 1 4\n",
        "bs.obj",
    );
    assert!(!out.starts_with("error"), "{out}");
    // Two faces, on the lines where their statements start (5, and 9 after the continued one).
    assert!(out.ends_with("[5, 9]"), "{out}");
}

#[test]
fn item17_trailing_comments_are_accepted() {
    let text = "o part#2 # the name keeps its '#'\nv 0 0 0 # origin\nv 1 0 0\t# x\nv 0 1 0\nf 1 2 3 # one face\n";
    let out = assert_same(text, "c.obj");
    assert!(out.contains("\"part#2\"") && out.contains("[0.0, 1.0, 0.0]"), "{out}");
}
