//! Writing a [`Mesh`] as OBJ text (positions, UVs and faces), with a header naming the unit.

use std::fmt::Write;

use super::Mesh;

/// The mesh as OBJ text. Numbers are written with 9 significant decimals so the bytes are
/// reproducible; faces use `v/vt` when the mesh has UVs.
pub fn obj_string(mesh: &Mesh, comment: &str) -> String {
    let mut s = String::new();
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    let _ = writeln!(s, "# units: {}", mesh.units.as_str());
    for p in &mesh.positions {
        let _ = writeln!(s, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
    }
    if let Some(uv) = &mesh.uv {
        for t in &uv.values {
            let _ = writeln!(s, "vt {:.9} {:.9}", t.x, t.y);
        }
        for (f, c) in mesh.faces.iter().zip(&uv.corners) {
            let _ = writeln!(
                s,
                "f {}/{} {}/{} {}/{}",
                f[0] + 1,
                c[0] + 1,
                f[1] + 1,
                c[1] + 1,
                f[2] + 1,
                c[2] + 1
            );
        }
    } else {
        for f in &mesh.faces {
            let _ = writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
        }
    }
    s
}
