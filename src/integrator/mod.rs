//! Integrators: what is computed along the rays a tracer casts.
//!
//! The ray workloads of the PDACRT paper's Tables 1–2 as integrators: `primary`
//! (eye-light shading), `ao` (8 ambient-occlusion rays per hit), `shadow` (one point
//! light), `reflection` (one mirror bounce) and `path` (7 diffuse bounces). Each runs as
//! a sequence of named GPU stages per pass and chunk of pixels: generate camera rays →
//! trace → generate secondary rays → trace → shade.
//! `pt` is the physically based wavefront path tracer of [`pt`].

mod eye;
pub mod gpu_types;
pub mod pt;

use std::fmt;
use std::str::FromStr;

pub use eye::{render_passes, IntegratorOutput, PassInputs, PassOptions};
pub use gpu_types::{FrameParams, GpuMaterial};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorKind {
    /// Eye-light shading: albedo × |cos θ| as if the light sat at the camera, plus emission.
    #[default]
    Primary,
    /// Ambient occlusion: the fraction of cosine-distributed rays that escape.
    Ao,
    /// Direct light from one point light, with shadow rays.
    Shadow,
    /// One perfect-mirror bounce, eye-light shaded.
    Reflection,
    /// Diffuse path tracing, 7 bounces, emission only (no next-event estimation).
    Path,
    /// Wavefront path tracing with next-event estimation and MIS ([`pt`]).
    Pt,
}

impl IntegratorKind {
    pub const ALL: &'static [(IntegratorKind, &'static str)] = &[
        (
            IntegratorKind::Primary,
            "eye-light shading of the first hit",
        ),
        (
            IntegratorKind::Ao,
            "ambient occlusion (8 rays per hit by default)",
        ),
        (
            IntegratorKind::Shadow,
            "Lambertian direct light from one point light, shadow rays",
        ),
        (
            IntegratorKind::Reflection,
            "every surface a perfect mirror: one reflection bounce",
        ),
        (
            IntegratorKind::Path,
            "diffuse path tracing, 7 bounces, emitted light only",
        ),
        (
            IntegratorKind::Pt,
            "wavefront path tracing: NEE + MIS, Russian roulette, material sorting",
        ),
    ];

    pub fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary",
            Self::Ao => "ao",
            Self::Shadow => "shadow",
            Self::Reflection => "reflection",
            Self::Path => "path",
            Self::Pt => "pt",
        }
    }
}

impl fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for IntegratorKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .find(|(k, _)| k.name() == s)
            .map(|(k, _)| *k)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|(k, _)| k.name()).collect();
                format!(
                    "unknown integrator '{s}' (choose one of: {})",
                    names.join(", ")
                )
            })
    }
}
