//! Integrators: what is computed along the rays a tracer casts.
//!
//! `primary` (eye-light shading) and `ao` (ambient occlusion) are the first-image
//! integrators; both run as a sequence of named GPU stages per pass and chunk:
//! generate camera rays → trace → (AO: generate AO rays → trace occlusion) → shade.
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
            IntegratorKind::Pt,
            "wavefront path tracing: NEE + MIS, Russian roulette, material sorting",
        ),
    ];

    pub fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary",
            Self::Ao => "ao",
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
