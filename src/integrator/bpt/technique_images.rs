//! Technique images (`--bdpt-techniques DIR`, pbrt-v4's `visualizeStrategies`): one
//! MIS-weighted image per technique (s, t) — what each technique adds to the render —
//! so that they sum to the image. Paths longer than [`MAX_SEGMENTS`] share one image
//! (`longer`), which keeps the sum exact under unbounded depth at bounded memory.

use std::collections::BTreeMap;

use super::pass::ChunkOutput;
use crate::integrator::NamedImage;

/// Paths of up to this many segments get an image per technique.
pub const MAX_SEGMENTS: u32 = 8;

/// The key of the image of paths longer than [`MAX_SEGMENTS`].
const LONGER: (u16, u16) = (u16::MAX, u16::MAX);

/// Whether `name` is the name of an image [`TechniqueImages::images`] may make:
/// `s{s}_t{t}` for a path of at most [`MAX_SEGMENTS`] segments, or `longer`.
pub fn is_image_name(name: &str) -> bool {
    if name == "longer" {
        return true;
    }
    let Some((s, t)) = name
        .strip_prefix('s')
        .and_then(|rest| rest.split_once("_t"))
    else {
        return false;
    };
    match (s.parse::<u16>(), t.parse::<u16>()) {
        // Spelled as `images` spells it: no sign, no leading zero.
        (Ok(s), Ok(t)) => {
            format!("s{s}_t{t}") == name && u32::from(s) + u32::from(t) <= MAX_SEGMENTS + 1
        }
        _ => false,
    }
}

/// Per-technique sums of the pass estimates.
pub struct TechniqueImages {
    width: u32,
    height: u32,
    /// Passes added since the images were created (restoring a film starts them anew).
    passes: u32,
    sums: BTreeMap<(u16, u16), Vec<[f64; 3]>>,
}

impl TechniqueImages {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            passes: 0,
            sums: BTreeMap::new(),
        }
    }

    /// Adds one pass's contributions (splats divided by the pass's light subpaths, as
    /// the render's pass estimate does).
    pub fn add_pass(&mut self, chunks: &[ChunkOutput], light_paths: f64) {
        let pixels = self.width as usize * self.height as usize;
        for chunk in chunks {
            for e in &chunk.entries {
                let key = if e.s as u32 + e.t as u32 - 1 <= MAX_SEGMENTS {
                    (e.s, e.t)
                } else {
                    LONGER
                };
                let image = self
                    .sums
                    .entry(key)
                    .or_insert_with(|| vec![[0.0; 3]; pixels]);
                let scale = if e.splat { 1.0 / light_paths } else { 1.0 };
                for (px, v) in image[e.pixel as usize].iter_mut().zip(e.rgb) {
                    *px += v as f64 * scale;
                }
            }
        }
        self.passes += 1;
    }

    /// The images so far (means over the passes), named `s{s}_t{t}` and `longer`.
    pub fn images(&self) -> Vec<NamedImage> {
        let n = self.passes.max(1) as f64;
        self.sums
            .iter()
            .map(|(&(s, t), sum)| NamedImage {
                name: if (s, t) == LONGER {
                    "longer".to_string()
                } else {
                    format!("s{s}_t{t}")
                },
                width: self.width,
                height: self.height,
                rgb: sum.iter().map(|v| v.map(|x| (x / n) as f32)).collect(),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_names_are_those_the_images_get() {
        for name in ["s0_t2", "s1_t1", "s2_t7", "s8_t1", "longer"] {
            assert!(is_image_name(name), "{name}");
        }
        for name in [
            "s1_t9",
            "s01_t2",
            "s1_t+2",
            "s1-t2",
            "s1_t2.exr",
            "longer2",
            "image",
        ] {
            assert!(!is_image_name(name), "{name}");
        }
    }
}
