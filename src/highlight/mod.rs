//! The highlight model: the tangent ℓ of anisotropic highlight curves produced by a grain field
//! (the paper's Eq. 4/7), its tensor form (Eq. 5), critical points, and initial fields.

pub mod critical;
pub mod ell;
pub mod init;
pub mod lighting;
pub mod singularities;
pub mod smoothest;
pub mod tensor;

pub use ell::{highlight_field, highlight_field_near, HighlightField};
pub use init::{initial_field, InitialField, InitialFieldResult};
pub use lighting::{h_gradients, half_vectors, Lighting, View};
pub use singularities::{singularities, Singularity};

/// The rotational symmetry of a grain field.
///
/// k = 1: an oriented field (u and −u differ), for BRDFs without central symmetry.
/// k = 2: a line field (φ modulo π), for centrally symmetric BRDFs (Ward, Ashikhmin–Shirley,
/// GGX): the paper's §4.4.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Symmetry {
    /// k = 1.
    #[default]
    Oriented,
    /// k = 2.
    Line,
}

impl Symmetry {
    /// The symmetry order k.
    pub fn k(self) -> u32 {
        match self {
            Symmetry::Oriented => 1,
            Symmetry::Line => 2,
        }
    }

    /// From the `symmetric` flag of the CLI and the file formats.
    pub fn from_symmetric(symmetric: bool) -> Self {
        if symmetric {
            Symmetry::Line
        } else {
            Symmetry::Oriented
        }
    }
}

/// Parses `X,Y,Z` (three finite numbers separated by commas) for the option `name`.
pub fn parse_vec3(name: &str, s: &str) -> crate::Result<nalgebra::Vector3<f64>> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let bad = || crate::Error::invalid_arg(name, format!("{s:?}: expected three numbers X,Y,Z"));
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p.parse::<f64>().map_err(|_| bad())?;
        if !v[k].is_finite() {
            return Err(crate::Error::invalid_arg(
                name,
                format!("{s:?}: components must be finite"),
            ));
        }
    }
    Ok(nalgebra::Vector3::new(v[0], v[1], v[2]))
}
