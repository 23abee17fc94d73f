//! The scene's fabrication constraints measured on the traced strokes (issue 17): what to
//! ask [`grainline_toolpaths::check_strokes`] for, built from `solver.constraints`.
//!
//! The turning radius R and the splay bound s_max are passed on as they are (scene units, the
//! same as the field mesh's lift); each lock of `constraints.locks` becomes one
//! [`LockProbe`] over the UV vertices whose mesh vertex it locks, with the lock's direction
//! uᵢ = cos φ̂ᵢ tᵢ + sin φ̂ᵢ bᵢ in the vertex's frame (the lock's own angle, not the field's).

use grainline_toolpaths::{LockProbe, StrokeCheckOptions};

use crate::geometry::Geometry;
use crate::mesh::Mesh;
use crate::solve::locks::resolve_locks;
use crate::solve::settings::Constraints;
use crate::Result;

/// The checks for `constraints`, or `None` when the scene has no fabrication constraint.
/// `uv_to_vertex` maps each field-mesh vertex to its mesh vertex; `k` is the symmetry.
pub fn check_options(
    mesh: &Mesh,
    geometry: &Geometry,
    constraints: &Constraints,
    uv_to_vertex: &[u32],
    k: u32,
) -> Result<Option<StrokeCheckOptions>> {
    let c = constraints;
    if c.turning_radius.is_none() && c.splay.is_none() && c.locks.is_empty() {
        return Ok(None);
    }
    let mut by_vertex: Vec<Vec<u32>> = vec![Vec::new(); mesh.num_vertices()];
    for (uv, &v) in uv_to_vertex.iter().enumerate() {
        if let Some(list) = by_vertex.get_mut(v as usize) {
            list.push(uv as u32);
        }
    }
    let mut locks = Vec::new();
    for (i, spec) in c.locks.iter().enumerate() {
        let key = format!("solver.constraints.locks[{i}]");
        let one = resolve_locks(
            mesh,
            geometry,
            std::slice::from_ref(spec),
            k,
            c.conflict_tolerance,
            &key,
        )?;
        let mut probe = LockProbe { name: key, ..Default::default() };
        let angles = one.hard.iter().copied().chain(one.soft.iter().map(|&(v, a, _)| (v, a)));
        for (v, a) in angles {
            let d = geometry.frames[v as usize].direction(a);
            for &uv in &by_vertex[v as usize] {
                probe.vertices.push(uv);
                probe.directions.push([d.x, d.y, d.z]);
            }
        }
        locks.push(probe);
    }
    Ok(Some(StrokeCheckOptions {
        turning_radius: c.turning_radius.as_ref().map(|t| t.radius),
        splay: c.splay.as_ref().map(|s| s.max),
        locks,
        ..Default::default()
    }))
}
