//! `pt` on an animated scene: a new frame moves the path tracer's scene tables in place.
//! The light-vertex-cache integrators read the same tables ([`SceneBuffers`]) and move
//! them the same way.

use super::{rescale_moments, upload_or_dummy, LightTable, PtIntegrator, SceneBuffers, Strategy};
use crate::integrator::frame::{write_ranges, SceneFrame};
use crate::integrator::pt::gpu::PtParams;
use crate::vk::{self, Buffer, Gpu};

/// The three shading normals of each triangle in `range` as the `pt-normals` table holds
/// them (w = 1 where the triangle has them).
fn normals_of(scene: &crate::scene::Scene, range: std::ops::Range<usize>) -> Vec<[f32; 4]> {
    scene.triangles[range]
        .iter()
        .flat_map(|t| match t.n {
            Some(n) => n.map(|v| v.extend(1.0).into()),
            None => [[0.0; 4]; 3],
        })
        .collect()
}

/// Writes `new` over `buffer` when it differs from `old`: in place when the sizes agree,
/// else into a new buffer (a light whose triangle became degenerate leaves the table).
fn replace_table<T: bytemuck::Pod + PartialEq>(
    gpu: &Gpu,
    name: &str,
    buffer: &mut Buffer,
    old: &[T],
    new: &[T],
) -> vk::Result<()> {
    if old == new {
        return Ok(());
    }
    if old.len() == new.len() {
        buffer.write(new)
    } else {
        *buffer = upload_or_dummy(gpu, name, new)?;
        Ok(())
    }
}

impl SceneBuffers {
    /// Moves the tables to `frame`: triangles and shading normals in the changed ranges,
    /// and the light table where it differs from `lights`, the table they hold now
    /// (emitters that moved change their edges, areas and so every light's probability
    /// of choice). Returns the posed scene's light table. The GPU must be done with the
    /// tables (the caller waits first).
    pub(crate) fn move_to_frame(
        &mut self,
        gpu: &Gpu,
        frame: &SceneFrame<'_>,
        lights: &LightTable,
    ) -> vk::Result<LightTable> {
        let scene = frame.scene;
        if frame.geometry_changed() {
            write_ranges(&self.triangles, frame.triangles, frame.changed, 1)?;
            // The table is three per triangle when any triangle has normals, else a
            // placeholder; which triangles have them never changes within a scene.
            if self.normals.size() as usize >= scene.triangles.len() * 3 * 16 {
                for r in frame.changed {
                    self.normals
                        .write_at(3 * r.start, &normals_of(scene, r.clone()))?;
                }
            }
        }
        let posed = LightTable::new(scene);
        replace_table(
            gpu,
            "pt-lights",
            &mut self.lights,
            &lights.lights,
            &posed.lights,
        )?;
        replace_table(
            gpu,
            "pt-light-cdf",
            &mut self.light_cdf,
            &lights.cdf,
            &posed.cdf,
        )?;
        replace_table(
            gpu,
            "pt-tri-light-pmf",
            &mut self.tri_pmf,
            &lights.tri_pmf,
            &posed.tri_pmf,
        )?;
        Ok(posed)
    }
}

impl PtIntegrator<'_> {
    /// Triangles, shading normals and the tracer's geometry in the changed ranges; the
    /// light table where it changed (emitters that moved); the camera, the ray offset
    /// and the brightness scale (from the scene's extent: point lights count at its
    /// radius), with the kept second moments rewritten at the new scale, and the light
    /// count.
    pub(super) fn move_to_frame(&mut self, frame: &SceneFrame<'_>) -> vk::Result<()> {
        self.gpu.wait_idle()?;
        let scene = frame.scene;
        if frame.geometry_changed() {
            self.tracer
                .update_geometry(frame.triangles, frame.changed)?;
        }
        let lights = self
            .scene
            .move_to_frame(&self.gpu, frame, &self.light_table)?;
        let posed = PtParams::new(&frame.camera);
        let p = &mut self.params;
        (p.origin, p.forward, p.right, p.up) = (posed.origin, posed.forward, posed.right, posed.up);
        p.light_count = lights.lights.len() as u32;
        let bounds = scene.bounds();
        p.ray_epsilon = bounds.ray_epsilon(scene.ray_sources());
        let scale = lights.brightness_scale(bounds.radius());
        rescale_moments(&self.accum2, p.brightness_scale, scale)?;
        p.brightness_scale = scale;
        self.nee_on = self.options.strategy != Strategy::Bsdf && !lights.lights.is_empty();
        self.light_table = lights;
        Ok(())
    }
}
