//! [`DeviceFilm`]: an integrator's film where it lives on the GPU, for watchers that show
//! it without copying it to the host first.

use std::sync::Arc;

use crate::vk::Buffer;

/// A film kept on the GPU as one `vec4` per pixel (row 0 at the top, `y * width + x`):
/// the sum of the pixel's samples' RGB in `xyz` and their number (or total weight) in
/// `w`, so the pixel's estimate is `xyz / w`; then as many `vec4` of the sums'
/// remainders ([`compensated`](super::compensated)). The sums alone are the f32
/// nearest to the exact ones, which is all a display needs.
///
/// Only submissions to the main stream write it, and each leaves every pixel's `vec4`
/// whole: work recorded on the main stream (which runs in submission order) reads a
/// consistent film whenever it runs, even in the middle of a pass. An integrator that
/// adds a sample's light over several submissions shows, mid-pass, some pixels one
/// sample behind; its film at pass boundaries is exact.
#[derive(Clone, Debug)]
pub struct DeviceFilm {
    pub sums: Arc<Buffer>,
    pub width: u32,
    pub height: u32,
}

impl DeviceFilm {
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}
