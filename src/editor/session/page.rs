//! The page's view of a drag step made from the previous step's: a step changes φ only on the
//! dragged brush's free vertices (and h only where a light tool acts), so the grain u is
//! recomputed at the vertices whose φ or h changed and the key light's highlight curves on the
//! faces around them; the rest is the previous step's. Each value is computed as the whole
//! part's would be (the same functions on the same inputs), so the result is the same bits.

use std::sync::Arc;

use nalgebra::Vector3;

use crate::fidelity::highlight_segments_of_faces;
use crate::highlight::Symmetry;
use crate::mesh::VertexFaces;
use crate::pipeline::Prepared;
use crate::{Error, Result};

/// Past this fraction of the part's vertices changed, a step is computed whole.
const MAX_CHANGED_FRACTION: usize = 4;

/// The last drag step's page field on one part (its base's generation and the part's id).
pub(super) struct PageField {
    gen: u64,
    part: u32,
    phi: Vec<f64>,
    /// The half vectors (shared with the drag step's: a step that leaves the light hands the
    /// same ones, and only φ is compared).
    h: Arc<Vec<Vector3<f64>>>,
    u: Vec<Vector3<f64>>,
    /// `u` as the page is sent it.
    pub(super) u32s: Vec<[f32; 3]>,
    /// The highlight segments with their faces, in face order.
    segments: Vec<(usize, [f32; 6])>,
    faces: VertexFaces,
}

/// The grain u of `phi` at vertex `i`, refused when it is not finite.
fn direction(p: &Prepared, phi: &[f64], i: usize) -> Result<Vector3<f64>> {
    let u = p.field.geometry.frames[i].direction(phi[i]);
    if !u.iter().all(|c| c.is_finite()) {
        return Err(Error::invalid_arg("solve", format!("the grain at vertex {i} is not finite")));
    }
    Ok(u)
}

fn segments_on(
    p: &Prepared,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    faces: &[usize],
) -> Vec<(usize, [f32; 6])> {
    highlight_segments_of_faces(&p.mesh, h, u, symmetry, faces)
        .into_iter()
        .map(|(f, [a, b])| (f, [a.x, a.y, a.z, b.x, b.y, b.z].map(|c| c as f32)))
        .collect()
}

impl PageField {
    /// The page field of `phi`, `h` on the whole part `p`.
    pub(super) fn new(
        gen: u64,
        part: u32,
        p: &Prepared,
        phi: &[f64],
        h: &Arc<Vec<Vector3<f64>>>,
    ) -> Result<PageField> {
        let u = (0..phi.len()).map(|i| direction(p, phi, i)).collect::<Result<Vec<_>>>()?;
        let faces: Vec<usize> = (0..p.mesh.num_faces()).collect();
        let segments = segments_on(p, h, &u, p.field_options.symmetry, &faces);
        Ok(PageField {
            gen,
            part,
            phi: phi.to_vec(),
            h: Arc::clone(h),
            u32s: u.iter().map(|v| [v.x as f32, v.y as f32, v.z as f32]).collect(),
            u,
            segments,
            faces: VertexFaces::new(&p.mesh),
        })
    }

    /// Whether this field is on the part `part` of the base of generation `gen`.
    pub(super) fn is_on(&self, gen: u64, part: u32, vertices: usize) -> bool {
        self.gen == gen && self.part == part && self.phi.len() == vertices
    }

    /// Moves this field to `phi`, `h` (on the same part): false, and unchanged, when more than
    /// a quarter of the vertices changed (the caller computes it whole).
    pub(super) fn update(
        &mut self,
        p: &Prepared,
        phi: &[f64],
        h: &Arc<Vec<Vector3<f64>>>,
    ) -> Result<bool> {
        let same = |a: &Vector3<f64>, b: &Vector3<f64>| {
            a.iter().zip(b.iter()).all(|(x, y)| x.to_bits() == y.to_bits())
        };
        let changed: Vec<usize> = if Arc::ptr_eq(h, &self.h) {
            (0..phi.len()).filter(|&i| phi[i].to_bits() != self.phi[i].to_bits()).collect()
        } else {
            (0..phi.len())
                .filter(|&i| phi[i].to_bits() != self.phi[i].to_bits() || !same(&h[i], &self.h[i]))
                .collect()
        };
        if changed.len() > phi.len() / MAX_CHANGED_FRACTION {
            return Ok(false);
        }
        // Checked first, in vertex order: the error names the vertex the whole part's would.
        let u = changed.iter().map(|&i| direction(p, phi, i)).collect::<Result<Vec<_>>>()?;
        // The new half vectors: the same bits as the kept ones but at the changed vertices.
        self.h = Arc::clone(h);
        let mut faces = Vec::new();
        for (&i, ui) in changed.iter().zip(u) {
            self.phi[i] = phi[i];
            self.u[i] = ui;
            self.u32s[i] = [ui.x as f32, ui.y as f32, ui.z as f32];
            faces.extend(self.faces.of(i).iter().map(|&(f, _)| f as usize));
        }
        faces.sort_unstable();
        faces.dedup();
        let fresh = segments_on(p, &self.h, &self.u, p.field_options.symmetry, &faces);
        // The kept segments off those faces and the fresh ones, merged in face order (a face
        // has at most one segment).
        let mut merged = Vec::with_capacity(self.segments.len() + fresh.len());
        let (mut next, mut k) = (fresh.into_iter().peekable(), 0);
        for &(f, s) in &self.segments {
            while let Some(n) = next.next_if(|n| n.0 < f) {
                merged.push(n);
            }
            while k < faces.len() && faces[k] < f {
                k += 1;
            }
            if k < faces.len() && faces[k] == f {
                continue;
            }
            merged.push((f, s));
        }
        merged.extend(next);
        self.segments = merged;
        Ok(true)
    }

    /// The highlight segments as the page is sent them.
    pub(super) fn segments(&self) -> Vec<[f32; 6]> {
        self.segments.iter().map(|s| s.1).collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::edit::{Centre, Edit, Metric, WarpEdit};
    use crate::editor::Session;

    /// Drag steps after the first make the grain and the curves from the previous step's, and
    /// give the bits the whole stage gives for the same edit (a bend dragged on a cylinder).
    #[test]
    fn a_drag_steps_page_field_is_the_whole_stages() {
        let dir = std::env::temp_dir().join(format!("grainline-page-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh = crate::generate::cylinder(30.0, 80.0, 160, 70);
        std::fs::write(dir.join("part.obj"), crate::mesh::write::obj_string(&mesh, "t")).unwrap();
        std::fs::write(
            dir.join("scene.json"),
            r#"{"mesh": "part.obj", "view": {"eye": [0, -300, 0]},
                "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
                "field": {"init": "uv", "symmetry": "line"}}"#,
        )
        .unwrap();
        let session = Session::open(&dir.join("scene.json")).unwrap();
        let base = session.base_for(None).unwrap();
        let bend = |strength: f64| {
            Edit::Bend(WarpEdit {
                centre: Centre::Point([0.0, -30.0, 5.0]),
                radius: 14.0,
                metric: Metric::Geodesic,
                strength,
                direction: Some([0.0, 0.0, 1.0]),
                weight: 1.0,
            })
        };
        for (k, strength) in [0.2, 0.5, 0.8].into_iter().enumerate() {
            let step = session.solve_drag(&base, &[], &bend(strength), k as u64 + 1).unwrap();
            let whole = session.solve(&base, &[bend(strength)], k as u64 + 1).unwrap();
            assert_eq!(step.part.id, whole.part.id, "nothing refined on this part");
            assert!(step.u == whole.u, "strength {strength}: the grain differs");
            assert!(step.segments == whole.segments, "strength {strength}: the curves differ");
            assert!(!step.segments.is_empty());
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
