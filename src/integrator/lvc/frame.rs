//! `lvc-bdpt` and `cis-lbdpt` on an animated scene: a new frame moves the scene tables
//! in place (`pt`'s, `SceneBuffers::move_to_frame`) and measures the cache anew.
//!
//! What the integrators keep between passes and what becomes of it:
//!
//! - the scene tables and the tracer's geometry: the changed triangle ranges written in
//!   place, the light table where it changed (emitter areas and edges move with their
//!   triangles, and with them every light's probability of choice);
//! - the constants: the camera, the ray offset and the brightness scale (from the
//!   scene's extent: point lights count at its radius) and the light count of the posed
//!   scene; the film's second moments, summed at the old brightness scale, are
//!   rewritten at the new one (exactly: the ratio is a power of two);
//! - v̄, the mean cached vertices per light path, and what follows from it — the
//!   connections' MIS count N / v̄, N_L and the passes per chunk fitted to one binding,
//!   the cache's capacity: a function of the geometry, so the prepass runs again on the
//!   posed scene, from the plan a new integrator would start from;
//! - the light vertex cache and the splat film: filled afresh by every chunk's light
//!   pass and light tracing before its camera pass reads them, and a chunk never
//!   outlives a call to `render_passes`, so no vertex of the old pose is ever read.
//!
//! The wavefront, the splat film and the kernels do not depend on the scene. The cache
//! keeps its buffers unless the posed scene needs more slots than they hold
//! ([`super::cache::LightCache::set_capacity`]).

use super::gpu::FLAG_NORMALS;
use super::plan::Plan;
use super::{prepass_constants, LvcIntegrator};
use crate::integrator::pt::rescale_moments;
use crate::integrator::{IntegratorError, SceneFrame};

impl LvcIntegrator<'_> {
    /// Moves everything the passes read to `frame` (see the module docs).
    pub(super) fn move_to_frame(&mut self, frame: &SceneFrame<'_>) -> Result<(), IntegratorError> {
        self.gpu.wait_idle()?;
        if frame.geometry_changed() {
            self.tracer
                .update_geometry(frame.triangles, frame.changed)?;
        }
        self.light_table = self
            .scene
            .move_to_frame(&self.gpu, frame, &self.light_table)?;
        let camera = &frame.camera;
        self.plan = Plan::new(&self.gpu, camera.width, camera.height, &self.options);
        let kept_scale = self.constants.brightness_scale;
        let bounds = frame.scene.bounds();
        // Posing moves normals, never adds or drops them.
        let normals = self.constants.flags & FLAG_NORMALS;
        self.constants = prepass_constants(
            &self.options,
            &self.plan,
            camera,
            &bounds,
            bounds.ray_epsilon(frame.scene.ray_sources()),
            &self.light_table,
        );
        self.constants.flags |= normals;
        rescale_moments(&self.accum2, kept_scale, self.constants.brightness_scale)?;
        self.constants_buffer.write(&[self.constants])?;
        self.prepass()
    }
}
