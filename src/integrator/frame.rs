//! [`SceneFrame`]: the next frame of an animated scene, as an integrator takes it
//! ([`super::Integrator::set_frame`]).

use std::ops::Range;

use crate::scene::{CameraFrame, Scene};
use crate::trace::GpuTriangle;

/// A scene posed at a new time. Only vertex positions, shading normals and the camera
/// differ from the scene the integrator was made for (or last moved to): the triangle
/// count, materials, point lights and film size are the same.
pub struct SceneFrame<'a> {
    /// The posed scene.
    pub scene: &'a Scene,
    /// Its triangles as the tracers take them.
    pub triangles: &'a [GpuTriangle],
    /// Triangle ranges (in soup order) whose vertices or normals changed; an integrator
    /// uploads these and what it derives from them, nothing else.
    pub changed: &'a [Range<usize>],
    /// The camera resolved for the integrator's film.
    pub camera: CameraFrame,
}

impl SceneFrame<'_> {
    /// Whether `changed` holds anything.
    pub fn geometry_changed(&self) -> bool {
        self.changed.iter().any(|r| !r.is_empty())
    }
}

/// Writes `table[r]` into `buffer` for each changed range `r`, in place (`per` table
/// entries per triangle).
pub(crate) fn write_ranges<T: bytemuck::Pod>(
    buffer: &crate::vk::Buffer,
    table: &[T],
    changed: &[Range<usize>],
    per: usize,
) -> crate::vk::Result<()> {
    for r in changed {
        buffer.write_at(r.start * per, &table[r.start * per..r.end * per])?;
    }
    Ok(())
}
