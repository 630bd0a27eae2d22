//! Integrators: what is computed along the rays a tracer casts.
//!
//! Every integrator — GPU or CPU — renders through one interface, [`Integrator`]:
//! progressive *passes* into a film of per-pass sums ([`FilmSums`]), so that the render
//! loop (`crate::render`), progress, `--time`, checkpoints and shards treat them all
//! alike. A pass adds [`Integrator::samples_per_pass`] samples to every pixel, and its
//! random numbers are a function of (seed, pass index) only: the film after passes
//! `0..n` is the same however the passes were grouped into calls, interrupted or resumed.
//!
//! The ray workloads of the PDACRT paper's Tables 1–2 are integrators too (module `eye`):
//! `primary` (eye-light shading), `ao` (8 ambient-occlusion rays per hit), `shadow` (one
//! point light), `reflection` (one mirror bounce) and `path` (7 diffuse bounces). `pt` is
//! the physically based wavefront path tracer of [`pt`]; `bpt` and `light` the CPU
//! bidirectional integrators of [`bpt`]; `lvc-bdpt` and `cis-lbdpt` the GPU
//! light-vertex-cache ones of [`lvc`]. First-hit AOVs (depth, triangle
//! id, normal) come from one pass of pixel-centre rays for every integrator ([`aov`]).

pub mod aov;
pub mod bpt;
pub mod cbpt;
mod eye;
pub mod frame;
pub mod gpu_types;
pub mod light_tracer;
pub mod lvc;
pub mod pt;

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

pub use eye::{EyeInputs, EyeIntegrator, EyeOptions};
pub use frame::SceneFrame;
pub use gpu_types::{FrameParams, GpuMaterial};

use crate::film::{DeviceFilm, FilmSums};
use crate::vk;

/// What can go wrong while an integrator renders.
#[derive(Debug, thiserror::Error)]
pub enum IntegratorError {
    #[error(transparent)]
    Gpu(#[from] vk::VkError),
    /// A caller asked for something the integrator cannot do (sums of the wrong size …).
    #[error("{0}")]
    Usage(String),
}

/// Figures an integrator counts while it renders (reported by `--stats`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct IntegratorStats {
    /// Rays cast: closest-hit and occlusion queries alike.
    pub rays_traced: u64,
    /// Named counts: paths, connections, non-finite samples dropped, …
    pub counters: BTreeMap<String, u64>,
}

impl IntegratorStats {
    /// `rays_traced` and the named counts, as an integrator lists them.
    pub fn with_counters(rays_traced: u64, counters: &[(&str, u64)]) -> Self {
        Self {
            rays_traced,
            counters: counters.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        }
    }
}

/// An image an integrator writes beside the render (e.g. one per BPT technique).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedImage {
    /// A file-name-safe name, e.g. `s2_t3`.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Row 0 at the top.
    pub rgb: Vec<[f32; 3]>,
}

/// One integrator, set up for one scene, camera, film size and seed.
pub trait Integrator {
    /// The name `--integrator` takes.
    fn name(&self) -> &'static str;

    /// Samples per pixel that one pass adds.
    fn samples_per_pass(&self) -> u32 {
        1
    }

    /// The most passes a call to [`Integrator::render_passes`] should take: more per call
    /// lets an integrator fill a wide device when the image is small.
    fn passes_per_call(&self) -> u32 {
        1
    }

    /// Renders passes `first..first + count` and adds them to the film. Pass `k` uses
    /// the random numbers of pass `k`, whatever came before it.
    fn render_passes(&mut self, first: u32, count: u32) -> Result<(), IntegratorError>;

    /// [`Integrator::render_passes`] for an integrator whose pass is long work in parts
    /// (`cbpt`'s steps): between two parts it asks `abandon`, and on `true` gives up the
    /// pass in progress and those after it. Returns the passes added to the film, the
    /// first ones of the range; a pass given up adds nothing. The others finish all.
    fn render_passes_or_abandon(
        &mut self,
        first: u32,
        count: u32,
        abandon: &dyn Fn() -> bool,
    ) -> Result<u32, IntegratorError> {
        let _ = abandon;
        self.render_passes(first, count).map(|()| count)
    }

    /// The film so far.
    fn sums(&mut self) -> Result<FilmSums, IntegratorError>;

    /// Replaces the film (to resume a render): later passes add to these sums.
    fn restore(&mut self, sums: &FilmSums) -> Result<(), IntegratorError>;

    /// What it counted so far.
    fn stats(&self) -> IntegratorStats;

    /// Settings that change the image besides scene, size, seed and tracer (depths,
    /// strategies …), as key/value pairs for file headers and checkpoints.
    fn settings(&self) -> Vec<(String, String)> {
        Vec::new()
    }

    /// Extra images to write beside the render, if the integrator was asked for any.
    fn extra_images(&mut self) -> Result<Vec<NamedImage>, IntegratorError> {
        Ok(Vec::new())
    }

    /// Moves to another frame of an animated scene: updates, in place, what the
    /// integrator renders from (its scene tables, its tracer's geometry, the camera),
    /// uploading only what changed. The film is kept ([`Integrator::restore`] clears
    /// it). The next passes render the posed scene exactly as an integrator made for it
    /// would. Integrators that cannot animate say so.
    fn set_frame(&mut self, frame: &SceneFrame<'_>) -> Result<(), IntegratorError> {
        let _ = frame;
        Err(IntegratorError::Usage(format!(
            "the {} integrator cannot render animated scenes yet",
            self.name()
        )))
    }

    /// The film where it lives on the GPU, for previews that show it from there; `None`
    /// for integrators that keep it on the host (watchers then take [`Integrator::sums`]).
    fn device_film(&self) -> Option<DeviceFilm> {
        None
    }
}

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
    /// Bidirectional path tracing on the CPU, every technique, balance heuristic ([`bpt`]).
    Bpt,
    /// Light tracing on the CPU ([`light_tracer`]).
    Light,
    /// Light-vertex-cache BPT on the GPU, uniform connections ([`lvc`]).
    LvcBdpt,
    /// CIS-LBDPT on the GPU: material sorting, resampled connections ([`lvc`]).
    CisLbdpt,
    /// Combinatorial BPT: CPU populations, GPU combination ([`cbpt`]).
    Cbpt,
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
        (
            IntegratorKind::Bpt,
            "bidirectional path tracing on the CPU: every (s, t) technique, balance heuristic",
        ),
        (
            IntegratorKind::Light,
            "light tracing on the CPU: light subpaths splatted to the camera",
        ),
        (
            IntegratorKind::LvcBdpt,
            "bidirectional path tracing on the GPU with a light vertex cache: N uniform connections",
        ),
        (
            IntegratorKind::CisLbdpt,
            "LVC-BDPT with material sorting and N connections resampled from M candidates",
        ),
        (
            IntegratorKind::Cbpt,
            "combinatorial BPT: path populations sampled on the CPU, every camera path \
             linked to every light path on the GPU in double-buffered batches",
        ),
    ];

    /// Whether the integrator renders animated scenes ([`Integrator::set_frame`]): all
    /// of them, listed so that a new kind decides.
    pub fn animates(self) -> bool {
        match self {
            Self::Primary
            | Self::Ao
            | Self::Shadow
            | Self::Reflection
            | Self::Path
            | Self::Pt
            | Self::Bpt
            | Self::Light
            | Self::LvcBdpt
            | Self::CisLbdpt
            | Self::Cbpt => true,
        }
    }

    /// The light-vertex-cache variant this integrator runs, for the cache integrators
    /// (`lvc-bdpt`, `cis-lbdpt`).
    pub fn lvc_variant(self) -> Option<lvc::Variant> {
        match self {
            Self::LvcBdpt => Some(lvc::Variant::LvcBdpt),
            Self::CisLbdpt => Some(lvc::Variant::CisLbdpt),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary",
            Self::Ao => "ao",
            Self::Shadow => "shadow",
            Self::Reflection => "reflection",
            Self::Path => "path",
            Self::Pt => "pt",
            Self::Bpt => "bpt",
            Self::Light => "light",
            Self::LvcBdpt => "lvc-bdpt",
            Self::CisLbdpt => "cis-lbdpt",
            Self::Cbpt => "cbpt",
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

/// Refuses film sums that do not belong to a `width × height` film of
/// `samples_per_pass` samples per pass (restoring them would mix two images).
pub(crate) fn check_film_size(
    sums: &FilmSums,
    width: u32,
    height: u32,
    samples_per_pass: u32,
) -> Result<(), IntegratorError> {
    let expected = width as usize * height as usize;
    let sq_ok = sums.sum_sq.as_ref().is_none_or(|q| q.len() == expected);
    if (sums.width, sums.height) != (width, height) || sums.sum.len() != expected || !sq_ok {
        return Err(IntegratorError::Usage(format!(
            "film sums of {}x{} do not fit a {width}x{height} film",
            sums.width, sums.height
        )));
    }
    if sums.samples_per_pass != samples_per_pass {
        return Err(IntegratorError::Usage(format!(
            "film sums of {} samples per pass do not fit an integrator of {samples_per_pass}",
            sums.samples_per_pass
        )));
    }
    Ok(())
}
