//! 8-bit sRGB PNG preview of a [`Film`].
//!
//! Pipeline per pixel: estimate ([`Film::mean_rgb`]) → multiply by `exposure` →
//! tone curve ([`ToneMap`], default: plain clamp to `[0, 1]`) → sRGB OETF (the exact
//! piecewise IEC 61966-2-1 curve, not a 2.2 gamma) → round to 8 bits. Negative components
//! are clamped to 0. Pixels with any NaN or infinite component are painted
//! [`NON_FINITE_COLOR`] (magenta) so bugs stand out instead of turning black or white.
//!
//! The PNG is RGB without alpha, 8 bits per channel, with an `sRGB` chunk.
//! The preview is for looking at; the EXR is the data.

use std::io::Write;
use std::path::Path;

use super::atomic::AtomicFile;
use super::{Film, FilmError};

/// Colour of pixels whose estimate is NaN or infinite.
pub const NON_FINITE_COLOR: [u8; 3] = [255, 0, 255];

/// Tone curve applied after exposure, before the sRGB OETF.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMap {
    /// Clamp each channel to `[0, 1]`. Values in range are reproduced exactly; highlights
    /// clip. The default: predictable and what most reference renderers do.
    #[default]
    Clamp,
    /// Reinhard on luminance: `rgb * (L / (1 + L)) / L` with Rec.709 luminance `L`, then
    /// clamp. Compresses highlights while keeping hue; darkens mid-tones somewhat.
    ReinhardLuminance,
}

/// How a preview is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewSettings {
    /// Linear multiplier applied to radiance before tone mapping (1.0 = unchanged;
    /// use `2f32.powf(stops)` for photographic stops).
    pub exposure: f32,
    /// Tone curve.
    pub tone_map: ToneMap,
}

impl Default for PreviewSettings {
    fn default() -> Self {
        Self {
            exposure: 1.0,
            tone_map: ToneMap::Clamp,
        }
    }
}

/// The sRGB opto-electronic transfer function (linear `[0, 1]` → encoded `[0, 1]`).
pub fn srgb_oetf(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// Maps one linear RGB value to 8-bit sRGB according to `settings`.
pub fn tonemap_pixel(rgb: [f32; 3], settings: &PreviewSettings) -> [u8; 3] {
    if rgb.iter().any(|c| !c.is_finite()) {
        return NON_FINITE_COLOR;
    }
    let mut c = rgb.map(|v| (v * settings.exposure).max(0.0));
    if c.iter().any(|v| !v.is_finite()) {
        // Finite input overflowed by a huge exposure: saturate.
        c = c.map(|v| if v.is_finite() { v } else { f32::MAX });
    }
    if settings.tone_map == ToneMap::ReinhardLuminance {
        let l = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        if l > 0.0 && l.is_finite() {
            let s = 1.0 / (1.0 + l);
            c = c.map(|v| v * s);
        } else if !l.is_finite() {
            c = [1.0; 3];
        }
    }
    c.map(|v| (srgb_oetf(v.clamp(0.0, 1.0)) * 255.0).round() as u8)
}

/// The preview as tightly packed 8-bit RGB rows, top row first.
pub fn preview_rgb8(film: &Film, settings: &PreviewSettings) -> Vec<u8> {
    (0..film.pixel_count())
        .flat_map(|i| tonemap_pixel(film.mean_rgb(i), settings))
        .collect()
}

/// Writes an 8-bit sRGB PNG preview (exposure, then plain clamp; see the module docs),
/// atomically.
pub fn write_png_preview(
    path: impl AsRef<Path>,
    film: &Film,
    exposure: f32,
) -> Result<(), FilmError> {
    write_png_preview_with(
        path,
        film,
        &PreviewSettings {
            exposure,
            tone_map: ToneMap::Clamp,
        },
    )
}

/// [`write_png_preview`] with explicit settings.
pub fn write_png_preview_with(
    path: impl AsRef<Path>,
    film: &Film,
    settings: &PreviewSettings,
) -> Result<(), FilmError> {
    // Generic only in this shim: the encoder is compiled once, here, not in every caller.
    write_png_preview_at(path.as_ref(), film, settings)
}

fn write_png_preview_at(
    path: &Path,
    film: &Film,
    settings: &PreviewSettings,
) -> Result<(), FilmError> {
    let mut file = AtomicFile::create(path)?;
    encode_png(film, settings, file.writer(), path)?;
    super::exr_out::warn_non_finite(film, path);
    file.commit()?;
    Ok(())
}

/// Encodes the preview PNG into `out`; `path` is only used in error messages.
pub(crate) fn encode_png<W: Write>(
    film: &Film,
    settings: &PreviewSettings,
    out: W,
    path: &Path,
) -> Result<(), FilmError> {
    film.refuse_empty(path)?;
    let png_err = |error| FilmError::Png {
        path: path.to_path_buf(),
        error,
    };
    let mut encoder = png::Encoder::new(out, film.width(), film.height());
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    encoder
        .add_text_chunk(
            "Software".to_owned(),
            format!("splitray {}", env!("CARGO_PKG_VERSION")),
        )
        .map_err(png_err)?;
    let mut writer = encoder.write_header().map_err(png_err)?;
    writer
        .write_image_data(&preview_rgb8(film, settings))
        .map_err(png_err)?;
    writer.finish().map_err(png_err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oetf_endpoints_and_known_values() {
        assert_eq!(srgb_oetf(0.0), 0.0);
        assert!((srgb_oetf(1.0) - 1.0).abs() < 1e-6);
        // Linear segment.
        assert!((srgb_oetf(0.002) - 0.02584).abs() < 1e-6);
        // 0.5 linear is 0.7354 encoded → 188 in 8 bits; 0.18 (mid grey) → 118.
        let s = PreviewSettings::default();
        assert_eq!(tonemap_pixel([0.5, 0.18, 0.0], &s), [188, 118, 0]);
        assert_eq!(tonemap_pixel([1.0, 7.0, -3.0], &s), [255, 255, 0]);
    }

    #[test]
    fn exposure_scales_linearly() {
        let s = PreviewSettings {
            exposure: 2.0,
            ..Default::default()
        };
        assert_eq!(tonemap_pixel([0.25, 0.25, 0.25], &s), [188; 3]);
        let huge = PreviewSettings {
            exposure: f32::MAX,
            ..Default::default()
        };
        assert_eq!(tonemap_pixel([1e30, 0.0, 0.0], &huge), [255, 0, 0]);
    }

    #[test]
    fn non_finite_is_magenta() {
        let s = PreviewSettings::default();
        assert_eq!(tonemap_pixel([f32::NAN, 0.0, 0.0], &s), NON_FINITE_COLOR);
        assert_eq!(
            tonemap_pixel([0.0, f32::INFINITY, 0.0], &s),
            NON_FINITE_COLOR
        );
        assert_eq!(
            tonemap_pixel([0.0, 0.0, f32::NEG_INFINITY], &s),
            NON_FINITE_COLOR
        );
    }

    #[test]
    fn reinhard_compresses_luminance() {
        let s = PreviewSettings {
            exposure: 1.0,
            tone_map: ToneMap::ReinhardLuminance,
        };
        // Grey 1.0 → 0.5 → 188.
        assert_eq!(tonemap_pixel([1.0; 3], &s), [188; 3]);
        // Very bright grey approaches white without clipping hue.
        assert_eq!(tonemap_pixel([1e6; 3], &s), [255; 3]);
        assert_eq!(tonemap_pixel([0.0; 3], &s), [0; 3]);
    }
}
