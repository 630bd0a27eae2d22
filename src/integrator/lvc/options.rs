//! Settings of the light-vertex-cache integrators.

use crate::integrator::IntegratorError;

/// Which method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Variant {
    /// LVC-BDPT (Davidovič et al. 2014, the thesis's baseline "LVC-BDPTmk"): N cache
    /// vertices drawn uniformly per camera vertex, no material sorting.
    LvcBdpt,
    /// CIS-LBDPT (thesis ch. 4): material sorting (where it pays) and N connections
    /// resampled from M candidates in proportion to their unoccluded contribution.
    CisLbdpt,
}

impl Variant {
    pub fn name(self) -> &'static str {
        match self {
            Self::LvcBdpt => "lvc-bdpt",
            Self::CisLbdpt => "cis-lbdpt",
        }
    }
}

/// How CIS-LBDPT draws its N connections from the M candidates' distribution (each
/// candidate in proportion to its unoccluded contribution). Both are unbiased
/// resampled importance sampling with replacement: a candidate drawn c times counts c
/// times, with the same weight (Talbot et al. 2005).
///
/// The thesis says only "we then sample N vertices from this distribution" (§4.4.3).
/// Systematic draws are the default because they measured better: on an NVIDIA H200 at
/// equal time they lowered `cis-lbdpt`'s error against independent draws in 17 of 19
/// paired runs on `fixture` and in 12 of 18 on `lamps` (5 higher, one tie;
/// docs/PERFORMANCE.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Resampling {
    /// N independent draws: each candidate's count is binomial.
    Independent,
    /// Systematic: one uniform u, draw k at (u + k) / N of the candidates' cumulative
    /// distribution, so a candidate of probability w is drawn floor(N w) or ceil(N w)
    /// times. Its expected count is still N w, so the estimate stays unbiased, and the
    /// counts vary far less than independent draws' (a candidate with N w >= 1 is
    /// always drawn).
    #[default]
    Systematic,
}

impl Resampling {
    pub fn name(self) -> &'static str {
        match self {
            Self::Independent => "independent",
            Self::Systematic => "systematic",
        }
    }
}

impl std::str::FromStr for Resampling {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "independent" => Ok(Self::Independent),
            "systematic" => Ok(Self::Systematic),
            _ => Err(format!("'{s}': resampling is independent or systematic")),
        }
    }
}

/// Which technique families contribute (all by default; tests render one family alone
/// by turning the others off, which also removes them from the MIS weights).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Families {
    /// s = 0: camera subpaths that hit an emitter.
    pub emitter_hit: bool,
    /// s = 1: direct lighting.
    pub light_sample: bool,
    /// s, t ≥ 2: connections to the light vertex cache.
    pub connection: bool,
    /// t = 1: light tracing.
    pub light_trace: bool,
}

impl Default for Families {
    fn default() -> Self {
        Self {
            emitter_hit: true,
            light_sample: true,
            connection: true,
            light_trace: true,
        }
    }
}

/// The most candidates (M) per camera vertex: `camera_connect.comp` packs a draw's
/// candidate into four bits, and keeps M candidates of 24 bytes per invocation in shared
/// memory (24 KiB a workgroup at 16).
pub const MAX_CANDIDATES: u32 = 16;
/// The most connections (N) per camera vertex (each is a shadow ray per path).
pub const MAX_CONNECTIONS: u32 = 16;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LvcOptions {
    pub variant: Variant,
    pub seed: u64,
    /// Mitsuba's max_depth (< 0: unbounded).
    pub max_depth: i32,
    /// Russian roulette from this vertex on.
    pub rr_depth: u32,
    /// N: connections (shadow rays) per camera vertex.
    pub connections: u32,
    /// M: candidates per camera vertex that N are resampled from (CIS-LBDPT).
    pub candidates: u32,
    /// How the N are drawn from the M (CIS-LBDPT).
    pub resampling: Resampling,
    /// Streams the camera pass's three kernels run on: 3, or 1 (all on the main stream;
    /// the same image bit for bit).
    pub streams: u32,
    /// Sort paths by material key before every material evaluation (the same image).
    pub sort: bool,
    /// N_L, light paths per pass: `None` = one per pixel (bounded by memory).
    pub light_paths: Option<u32>,
    /// The most passes one chunk holds (the render's spp, or fewer).
    pub spp: u32,
    /// Upper bound on the paths of a wavefront (bounds memory).
    pub max_paths_per_chunk: u32,
    pub families: Families,
    /// Keep one image per technique ([`crate::integrator::Integrator::extra_images`]).
    pub technique_images: bool,
    /// Start with a cache of this many slots instead of the prepass's estimate (tests
    /// of the growth path).
    pub initial_cache: Option<u32>,
}

impl LvcOptions {
    /// The variant's defaults: N = 5 (and M = 10), three streams; LVC-BDPT does not sort,
    /// CIS-LBDPT sorts where material evaluation diverges (`sort_pays`).
    pub fn new(variant: Variant, sort_pays: bool) -> Self {
        Self {
            variant,
            seed: 0,
            max_depth: -1,
            rr_depth: 5,
            connections: 5,
            candidates: 10,
            resampling: Resampling::default(),
            streams: 3,
            sort: variant == Variant::CisLbdpt && sort_pays,
            light_paths: None,
            spp: u32::MAX,
            max_paths_per_chunk: 1 << 18,
            families: Families::default(),
            technique_images: false,
            initial_cache: None,
        }
    }

    /// Refuses settings the kernels cannot take.
    pub fn check(&self) -> Result<(), IntegratorError> {
        let usage = |m: String| Err(IntegratorError::Usage(m));
        if !(1..=MAX_CONNECTIONS).contains(&self.connections) {
            return usage(format!(
                "--connections must be 1..={MAX_CONNECTIONS}, not {}",
                self.connections
            ));
        }
        if self.variant == Variant::CisLbdpt && !(1..=MAX_CANDIDATES).contains(&self.candidates) {
            return usage(format!(
                "--candidates must be 1..={MAX_CANDIDATES}, not {}",
                self.candidates
            ));
        }
        if !matches!(self.streams, 1 | 3) {
            return usage(format!("--streams must be 1 or 3, not {}", self.streams));
        }
        if self.light_paths == Some(0) {
            return usage("light paths per pass must be at least 1".into());
        }
        Ok(())
    }
}

/// What a render asks of the light-vertex-cache integrators beyond the common options
/// (`--connections`, `--candidates`, `--resampling`, `--streams`, `--sort` /
/// `--no-sort`); `None` takes the variant's default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct LvcSettings {
    pub connections: Option<u32>,
    pub candidates: Option<u32>,
    pub resampling: Option<Resampling>,
    pub streams: Option<u32>,
    pub sort: Option<bool>,
}

impl LvcSettings {
    /// The integrator's options for `variant` on a device where material sorting does
    /// or does not pay (`sort_pays`).
    pub fn options(&self, variant: Variant, sort_pays: bool) -> LvcOptions {
        let mut o = LvcOptions::new(variant, sort_pays);
        o.connections = self.connections.unwrap_or(o.connections);
        o.candidates = self.candidates.unwrap_or(o.candidates);
        o.resampling = self.resampling.unwrap_or(o.resampling);
        o.streams = self.streams.unwrap_or(o.streams);
        o.sort = self.sort.unwrap_or(o.sort);
        o
    }

    /// These settings with what decides the estimate (N, M and how the draws are made)
    /// taken from today's defaults where unset: what a checkpoint keeps, so that a build
    /// with other defaults continues it with the estimator it was started with. The
    /// streams and sorting stay as given: they never change the image, and sorting's
    /// default is the device's.
    pub fn with_estimator_pinned(self) -> Self {
        let defaults = LvcOptions::new(Variant::CisLbdpt, false);
        Self {
            connections: Some(self.connections.unwrap_or(defaults.connections)),
            candidates: Some(self.candidates.unwrap_or(defaults.candidates)),
            resampling: Some(self.resampling.unwrap_or(defaults.resampling)),
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pinning_fills_the_estimators_defaults_and_keeps_what_was_given() {
        let defaults = LvcOptions::new(Variant::CisLbdpt, false);
        let given = LvcSettings {
            connections: Some(3),
            streams: Some(1),
            ..LvcSettings::default()
        };
        let pinned = given.with_estimator_pinned();
        assert_eq!(pinned.connections, Some(3));
        assert_eq!(pinned.candidates, Some(defaults.candidates));
        assert_eq!(pinned.resampling, Some(defaults.resampling));
        assert_eq!((pinned.streams, pinned.sort), (Some(1), None));
        assert_eq!(pinned.with_estimator_pinned(), pinned);
        // The options it gives are the ones the unpinned settings give.
        for variant in [Variant::LvcBdpt, Variant::CisLbdpt] {
            for sort_pays in [false, true] {
                let (a, b) = (
                    given.options(variant, sort_pays),
                    pinned.options(variant, sort_pays),
                );
                assert_eq!(
                    (a.connections, a.candidates, a.resampling, a.streams, a.sort),
                    (b.connections, b.candidates, b.resampling, b.streams, b.sort)
                );
            }
        }
    }
}
