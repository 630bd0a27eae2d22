//! [`FilmReader`]: a film on the GPU read to the host while the render goes on.
//!
//! The copy is recorded on the main stream, so it lands between two of the integrator's
//! submissions and sees a whole film ([`DeviceFilm`]); it goes into a buffer of the
//! reader's own, which nothing else writes, so the host reads it once the copy is done
//! without waiting for the render's later work.

use crate::film::{compensated, DeviceFilm};
use crate::vk::{self, Buffer, MemoryKind, StreamKind};

/// Reads one [`DeviceFilm`] to the host, as often as asked.
pub struct FilmReader {
    staging: Buffer,
}

impl FilmReader {
    pub fn new(film: &DeviceFilm) -> vk::Result<Self> {
        Ok(Self {
            staging: film.sums.gpu().create_buffer(
                "display-film-readback",
                film.sums.size(),
                MemoryKind::Readback,
            )?,
        })
    }

    /// Each pixel's estimate now: sum / weight, black where it has no weight yet. At a
    /// pass boundary this is `FilmSums::mean` of the same film, value for value.
    pub fn read_mean(&self, film: &DeviceFilm) -> vk::Result<Vec<[f32; 3]>> {
        let gpu = film.sums.gpu();
        let mut rec = gpu.recorder(StreamKind::Main)?;
        rec.copy(&film.sums, 0, &self.staging, 0, film.sums.size());
        let copied = rec.submit(&[])?;
        let film_sums = self.staging.read_after::<[f32; 4]>(&copied)?;
        let (sums, rests) = film_sums.split_at(film.pixel_count());
        Ok(sums.iter().zip(rests).map(|(s, r)| mean_of(s, r)).collect())
    }
}

/// The estimate of a pixel whose sums are `s` and remainders `r`: `xyz / w`, each the
/// pair's sum in `f64`, rounded once to `f32` (as `FilmSums::mean` divides).
pub fn mean_of(s: &[f32; 4], r: &[f32; 4]) -> [f32; 3] {
    let [x, y, z, w] = std::array::from_fn(|c| compensated::join(s[c], r[c]));
    if w > 0.0 {
        [x, y, z].map(|c| (c / w) as f32)
    } else {
        [0.0; 3]
    }
}
