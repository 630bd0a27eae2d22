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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::FilmSums;
    use crate::integrator::{Integrator, IntegratorError, IntegratorStats};

    /// An integrator that implements only what every integrator must.
    struct Still;

    impl Integrator for Still {
        fn name(&self) -> &'static str {
            "still"
        }
        fn render_passes(&mut self, _: u32, _: u32) -> Result<(), IntegratorError> {
            Ok(())
        }
        fn sums(&mut self) -> Result<FilmSums, IntegratorError> {
            Ok(FilmSums::new(1, 1, 1, false))
        }
        fn restore(&mut self, _: &FilmSums) -> Result<(), IntegratorError> {
            Ok(())
        }
        fn stats(&self) -> IntegratorStats {
            IntegratorStats::default()
        }
    }

    #[test]
    fn an_integrator_that_cannot_animate_says_so() {
        let scene = crate::scene::builtin("cornell-box").unwrap();
        let e = Still
            .set_frame(&SceneFrame {
                scene: &scene,
                triangles: &[],
                changed: &[0..1, 2..3],
                camera: scene.camera_frame(),
            })
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "the still integrator cannot render animated scenes yet"
        );
        let frame = SceneFrame {
            scene: &scene,
            triangles: &[],
            changed: &[3..3, 5..5],
            camera: scene.camera_frame(),
        };
        assert!(!frame.geometry_changed());
    }
}
