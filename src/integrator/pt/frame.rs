//! `pt` on an animated scene: a new frame moves the path tracer's scene tables in place.

use super::{upload_or_dummy, LightTable, PtIntegrator, Strategy};
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

impl PtIntegrator<'_> {
    /// Triangles, shading normals and the tracer's geometry in the changed ranges; the
    /// light table where it changed (emitters that moved); the camera, the ray offset
    /// (from the scene's extent) and the light count.
    pub(super) fn move_to_frame(&mut self, frame: &SceneFrame<'_>) -> vk::Result<()> {
        self.gpu.wait_idle()?;
        let scene = frame.scene;
        if frame.geometry_changed() {
            self.tracer
                .update_geometry(frame.triangles, frame.changed)?;
            let s = &self.scene;
            write_ranges(&s.triangles, frame.triangles, frame.changed, 1)?;
            // The table is three per triangle when any triangle has normals, else a
            // placeholder; which triangles have them never changes within a scene.
            if s.normals.size() as usize >= scene.triangles.len() * 3 * 16 {
                for r in frame.changed {
                    s.normals
                        .write_at(3 * r.start, &normals_of(scene, r.clone()))?;
                }
            }
        }
        let lights = LightTable::new(scene);
        let s = &mut self.scene;
        let old = &self.light_table;
        replace_table(
            &self.gpu,
            "pt-lights",
            &mut s.lights,
            &old.lights,
            &lights.lights,
        )?;
        replace_table(
            &self.gpu,
            "pt-light-cdf",
            &mut s.light_cdf,
            &old.cdf,
            &lights.cdf,
        )?;
        replace_table(
            &self.gpu,
            "pt-tri-light-pmf",
            &mut s.tri_pmf,
            &old.tri_pmf,
            &lights.tri_pmf,
        )?;
        let posed = PtParams::new(&frame.camera);
        let p = &mut self.params;
        (p.origin, p.forward, p.right, p.up) = (posed.origin, posed.forward, posed.right, posed.up);
        p.light_count = lights.lights.len() as u32;
        p.ray_epsilon = 1e-4 * scene.bounds().radius().max(1e-3);
        self.nee_on = self.options.strategy != Strategy::Bsdf && !lights.lights.is_empty();
        self.light_table = lights;
        Ok(())
    }
}
