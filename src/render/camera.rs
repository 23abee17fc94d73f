//! The perspective pinhole camera and its projection to pixel coordinates.

use nalgebra::Vector3;

use crate::{Error, Result};

/// A perspective pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    /// Eye position.
    pub eye: Vector3<f64>,
    /// The point at the image centre.
    pub target: Vector3<f64>,
    /// Up direction (need not be orthogonal to the view direction, must not be parallel to it).
    pub up: Vector3<f64>,
    /// Vertical field of view, degrees, in (0, 179].
    pub fov_deg: f64,
}

impl Camera {
    /// Checks finiteness, eye ≠ target, up not parallel to the view, the field of view.
    pub fn validate(&self) -> Result<()> {
        let finite = |v: &Vector3<f64>| v.iter().all(|c| c.is_finite());
        if !(finite(&self.eye) && finite(&self.target) && finite(&self.up)) {
            return Err(Error::setting("view", "eye, target and up must be finite"));
        }
        let f = self.target - self.eye;
        if f.norm() <= 1e-12 * (1.0 + self.eye.norm()) {
            return Err(Error::setting("view.target", "must differ from the eye"));
        }
        if self.up.norm() == 0.0 || f.normalize().cross(&self.up.normalize()).norm() < 1e-6 {
            return Err(Error::setting("view.up", "must not be zero or parallel to target − eye"));
        }
        if !(self.fov_deg.is_finite() && self.fov_deg > 0.0 && self.fov_deg <= 179.0) {
            return Err(Error::setting(
                "view.fov_deg",
                format!("must be in (0, 179], got {}", crate::error::fmt_num(self.fov_deg)),
            ));
        }
        Ok(())
    }
}

/// A validated camera for an image of `width × height` pixels (pixel (i, j) has its centre at
/// (i + ½, j + ½); y grows downwards).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projector {
    pub eye: Vector3<f64>,
    pub right: Vector3<f64>,
    pub up: Vector3<f64>,
    pub fwd: Vector3<f64>,
    /// Focal length in pixels.
    pub focal: f64,
    pub cx: f64,
    pub cy: f64,
    /// Depth of the near clipping plane.
    pub near: f64,
}

impl Projector {
    pub fn new(c: &Camera, width: usize, height: usize) -> Self {
        let fwd = (c.target - c.eye).normalize();
        let right = fwd.cross(&c.up).normalize();
        let up = right.cross(&fwd);
        let focal = 0.5 * height as f64 / (0.5 * c.fov_deg.to_radians()).tan();
        let near = 1e-4 * (c.target - c.eye).norm();
        Projector {
            eye: c.eye,
            right,
            up,
            fwd,
            focal,
            cx: 0.5 * width as f64,
            cy: 0.5 * height as f64,
            near,
        }
    }

    /// Camera coordinates (right, up, depth).
    pub fn camera_coords(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let d = p - self.eye;
        Vector3::new(d.dot(&self.right), d.dot(&self.up), d.dot(&self.fwd))
    }

    /// Pixel coordinates of a camera-space point in front of the eye.
    pub fn cam_to_pixel(&self, c: &Vector3<f64>) -> [f64; 2] {
        [self.cx + self.focal * c.x / c.z, self.cy - self.focal * c.y / c.z]
    }

    /// Pixel coordinates and depth of a world point, `None` behind the near plane.
    pub fn project(&self, p: &Vector3<f64>) -> Option<([f64; 2], f64)> {
        let c = self.camera_coords(p);
        (c.z > self.near).then(|| (self.cam_to_pixel(&c), c.z))
    }
}
