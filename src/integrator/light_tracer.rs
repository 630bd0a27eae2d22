//! `light`: light tracing alone — every light subpath vertex connected to the pinhole
//! and splatted to the pixel it projects to (the t = 1 techniques of
//! [`crate::integrator::bpt`], emitters seen directly included), unweighted since no
//! other technique runs. It cannot render what the camera sees only through a delta
//! lobe (a mirror's reflection), and like `pt` it never shows a point light itself.

use super::bpt::{BidirMode, BptIntegrator, BptOptions};
use crate::scene::{CameraFrame, Scene};

/// The light tracer on `scene`.
pub fn light_tracer(scene: &Scene, camera: &CameraFrame, options: &BptOptions) -> BptIntegrator {
    BptIntegrator::new(BidirMode::Light, scene, camera, options)
}
