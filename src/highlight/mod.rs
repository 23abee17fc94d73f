//! The highlight model: the tangent ℓ of anisotropic highlight curves produced by a grain field
//! (the paper's Eq. 4/7), its tensor form (Eq. 5), critical points, and initial fields.

pub mod critical;
pub mod ell;
pub mod init;
pub mod lighting;
pub mod smoothest;
pub mod tensor;

pub use ell::{highlight_field, highlight_field_near, HighlightField};
pub use init::{initial_field, InitialField, InitialFieldResult};
pub use lighting::{h_gradients, half_vectors, Lighting, View};

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
