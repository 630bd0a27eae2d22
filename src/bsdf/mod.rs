//! BSDFs with a GLSL twin (`glsl/common/bsdf.glsl`): Lambertian, Oren–Nayar, perfect
//! mirror, specular dielectric, microfacet reflection and rough dielectric
//! (Blinn–Phong, Beckmann, GGX with Smith shadowing), layered materials of up to four
//! layers (thesis §4.4.1) and material keys (thesis §4.4.2).
//!
//! # Conventions
//!
//! - **Local shading frame**: every direction given to or returned by a BSDF is in the
//!   local frame whose +z is the *shading* normal ([`Frame`] converts). `wo` and `wi`
//!   both point **away** from the surface and are unit length. `wo` is the direction the
//!   path arrived from (towards the camera for camera paths, towards the light for light
//!   paths); `wi` is the direction that is sampled.
//! - **η**: a dielectric's `ior` is η = η_inside / η_outside, where "outside" is the
//!   +z side. For a direction on the −z side the relative index seen is 1/η, so `ior < 1`
//!   and "`wo` below the surface" describe the same optics. [`BsdfSample::eta`] is the
//!   relative index η_i/η_o across the sampled event (1 for reflection).
//! - **[`TransportMode`]** (pbrt-v4): `Radiance` for camera paths, `Importance` for
//!   light paths (adjoint transport). Refraction scales by 1/η'² (η' = `BsdfSample::eta`)
//!   in `Radiance` mode only, so f(wo, wi) / η_o² = f(wi, wo) / η_i² there, with η_o the
//!   index of the medium on `wo`'s side (Veach 1997, eq. 5.14); in `Importance` mode f is
//!   the adjoint: f_importance(wo, wi) = f_radiance(wi, wo). The shading-normal
//!   correction of the adjoint BSDF is [`shading_normal_correction`]: callers multiply
//!   `f · |wi·ns|` by it on light paths.
//! - `eval` returns f (the BSDF, not f·cos); `pdf` is per unit solid angle of `wi`;
//!   delta components (mirror, specular dielectric) have `eval = pdf = 0` and are only
//!   reached through `sample`, which then returns f and pdf as delta "weights" whose ratio
//!   is meaningful (f·|cos θi| / pdf is the path throughput factor).
//! - Reflection-only BSDFs are two-sided: for `wo` below the surface they act as if the
//!   frame were mirrored in z.
//! - Random numbers: `sample` takes `u = [uc, u1, u2]` in [0, 1): `uc` picks the layer and
//!   then (remapped) the reflect/refract choice, `(u1, u2)` the direction.
//!
//! The Rust code mirrors the GLSL statement by statement in `f32`, so that the CPU and
//! GPU agree to rounding (`tests/suite/bsdf_gpu.rs`).

pub mod chi2;
pub mod frame;
pub mod key;
pub mod lambert;
pub mod layered;
pub mod microfacet;
pub mod oren_nayar;
pub mod sampling;
pub mod specular;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

pub use frame::Frame;
pub use key::{material_key, try_material_key, MaterialKeyError, MaterialType};
pub use microfacet::Distribution;

/// Maximum layers of a [`BsdfParams`] stack (thesis §4.4.1).
pub const MAX_LAYERS: usize = 4;

/// Which quantity a path carries (pbrt-v4's `TransportMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum TransportMode {
    /// Camera paths: radiance flows from `wi` to `wo`.
    Radiance = 0,
    /// Light paths: importance flows from `wi` to `wo` (the adjoint BSDF).
    Importance = 1,
}

/// Lobe flags of a sampled event, the same bits as `BSDF_*` in `bsdf.glsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Pod, Zeroable)]
#[repr(transparent)]
pub struct BsdfFlags(pub u32);

impl BsdfFlags {
    pub const REFLECTION: Self = Self(1);
    pub const TRANSMISSION: Self = Self(2);
    pub const DIFFUSE: Self = Self(4);
    pub const GLOSSY: Self = Self(8);
    pub const SPECULAR: Self = Self(16);

    pub fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
    pub fn is_specular(self) -> bool {
        self.contains(Self::SPECULAR)
    }
    pub fn is_transmission(self) -> bool {
        self.contains(Self::TRANSMISSION)
    }
}

impl std::ops::BitOr for BsdfFlags {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// A sampled direction with its BSDF value and pdf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// f(wo, wi) (for delta lobes: the delta's weight, to be divided by `pdf`).
    pub f: Vec3,
    /// Sampled direction, local frame, pointing away from the surface.
    pub wi: Vec3,
    /// Solid-angle pdf of `wi` (for delta lobes: the discrete probability of the lobe).
    pub pdf: f32,
    pub flags: BsdfFlags,
    /// Relative index η_i/η_o of the event (1 for reflection).
    pub eta: f32,
    /// Index of the layer that was sampled.
    pub layer: u32,
}

/// Layer kinds (`BsdfLayer::kind`), the same values as `BSDF_KIND_*` in `bsdf.glsl`.
pub mod kind {
    pub const LAMBERT: u32 = 0;
    pub const OREN_NAYAR: u32 = 1;
    pub const MIRROR: u32 = 2;
    pub const DIELECTRIC: u32 = 3;
    pub const MICROFACET_REFLECTION: u32 = 4;
    pub const MICROFACET_DIELECTRIC: u32 = 5;
    /// Number of kinds.
    pub const COUNT: u32 = 6;
}

/// One layer of the flat GPU record (32 bytes; `BsdfLayer` in `bsdf.glsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct BsdfLayer {
    /// rgb: albedo / tint / Schlick F0; a: the layer's weight in the mixture.
    pub tint_weight: [f32; 4],
    /// One of [`kind`].
    pub kind: u32,
    /// [`Distribution`] as u32 (microfacet kinds only).
    pub distribution: u32,
    /// Oren–Nayar σ (radians); microfacet α (Beckmann, GGX) or exponent (Blinn–Phong).
    pub roughness: f32,
    /// η = η_inside / η_outside (dielectric kinds only).
    pub ior: f32,
}

/// A stack of up to [`MAX_LAYERS`] layers: the flat GPU record (144 bytes; `BsdfParams`
/// in `bsdf.glsl`). See [`layered`] for how the layers combine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct BsdfParams {
    pub layers: [BsdfLayer; MAX_LAYERS],
    /// Layers in use (1..=4).
    pub count: u32,
    pub pad: [u32; 3],
}

/// A single BSDF, the typed form of a [`BsdfLayer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    Lambert {
        albedo: Vec3,
    },
    /// Oren–Nayar (qualitative model of pbrt-v3), σ in radians.
    OrenNayar {
        albedo: Vec3,
        sigma: f32,
    },
    /// Perfect specular reflection with reflectance `tint`.
    Mirror {
        tint: Vec3,
    },
    /// Smooth dielectric: Fresnel-weighted specular reflection and transmission.
    Dielectric {
        tint: Vec3,
        eta: f32,
    },
    /// Microfacet reflection with Schlick Fresnel of normal-incidence reflectance `f0`.
    MicrofacetReflection {
        f0: Vec3,
        distribution: Distribution,
        roughness: f32,
    },
    /// Rough dielectric (Walter et al. 2007): microfacet reflection and transmission;
    /// of η exactly 1, no interface: the smooth dielectric's straight line through.
    MicrofacetDielectric {
        tint: Vec3,
        distribution: Distribution,
        roughness: f32,
        eta: f32,
    },
}

impl Bsdf {
    /// The flat layer record with mixture weight `weight`.
    pub fn layer(&self, weight: f32) -> BsdfLayer {
        let (rgb, kind, distribution, roughness, ior) = match *self {
            Bsdf::Lambert { albedo } => (albedo, kind::LAMBERT, 0, 0.0, 1.0),
            Bsdf::OrenNayar { albedo, sigma } => (albedo, kind::OREN_NAYAR, 0, sigma, 1.0),
            Bsdf::Mirror { tint } => (tint, kind::MIRROR, 0, 0.0, 1.0),
            Bsdf::Dielectric { tint, eta } => (tint, kind::DIELECTRIC, 0, 0.0, eta),
            Bsdf::MicrofacetReflection {
                f0,
                distribution,
                roughness,
            } => (
                f0,
                kind::MICROFACET_REFLECTION,
                distribution as u32,
                roughness,
                1.0,
            ),
            Bsdf::MicrofacetDielectric {
                tint,
                distribution,
                roughness,
                eta,
            } => (
                tint,
                kind::MICROFACET_DIELECTRIC,
                distribution as u32,
                roughness,
                eta,
            ),
        };
        BsdfLayer {
            tint_weight: [rgb.x, rgb.y, rgb.z, weight],
            kind,
            distribution,
            roughness,
            ior,
        }
    }

    /// The typed form of a layer record (`None` for an unknown kind or distribution).
    pub fn from_layer(l: &BsdfLayer) -> Option<Bsdf> {
        let rgb = Vec3::new(l.tint_weight[0], l.tint_weight[1], l.tint_weight[2]);
        let distribution = Distribution::from_u32(l.distribution);
        Some(match l.kind {
            kind::LAMBERT => Bsdf::Lambert { albedo: rgb },
            kind::OREN_NAYAR => Bsdf::OrenNayar {
                albedo: rgb,
                sigma: l.roughness,
            },
            kind::MIRROR => Bsdf::Mirror { tint: rgb },
            kind::DIELECTRIC => Bsdf::Dielectric {
                tint: rgb,
                eta: l.ior,
            },
            kind::MICROFACET_REFLECTION => Bsdf::MicrofacetReflection {
                f0: rgb,
                distribution: distribution?,
                roughness: l.roughness,
            },
            kind::MICROFACET_DIELECTRIC => Bsdf::MicrofacetDielectric {
                tint: rgb,
                distribution: distribution?,
                roughness: l.roughness,
                eta: l.ior,
            },
            _ => return None,
        })
    }

    /// A one-layer stack of weight 1.
    pub fn params(&self) -> BsdfParams {
        BsdfParams::new(&[self.layer(1.0)])
    }

    /// Whether every lobe is a Dirac delta (eval and pdf are then always 0): a rough
    /// dielectric of η exactly 1 is one too (see [`microfacet`]).
    pub fn is_delta(&self) -> bool {
        match *self {
            Bsdf::Mirror { .. } | Bsdf::Dielectric { .. } => true,
            Bsdf::MicrofacetDielectric { eta, .. } => eta == 1.0,
            _ => false,
        }
    }

    /// f(wo, wi), local frame (0 for delta BSDFs).
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        match *self {
            Bsdf::Lambert { albedo } => lambert::eval(albedo, wo, wi),
            Bsdf::OrenNayar { albedo, sigma } => oren_nayar::eval(albedo, sigma, wo, wi),
            Bsdf::Mirror { .. } | Bsdf::Dielectric { .. } => Vec3::ZERO,
            Bsdf::MicrofacetReflection {
                f0,
                distribution,
                roughness,
            } => microfacet::reflection_eval(f0, distribution, roughness, wo, wi),
            Bsdf::MicrofacetDielectric {
                tint,
                distribution,
                roughness,
                eta,
            } => microfacet::dielectric_eval(tint, distribution, roughness, eta, wo, wi, mode),
        }
    }

    /// Solid-angle pdf of sampling `wi` given `wo` (0 for delta BSDFs).
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> f32 {
        match *self {
            Bsdf::Lambert { .. } | Bsdf::OrenNayar { .. } => lambert::pdf(wo, wi),
            Bsdf::Mirror { .. } | Bsdf::Dielectric { .. } => 0.0,
            Bsdf::MicrofacetReflection {
                distribution,
                roughness,
                ..
            } => microfacet::reflection_pdf(distribution, roughness, wo, wi),
            Bsdf::MicrofacetDielectric {
                distribution,
                roughness,
                eta,
                ..
            } => microfacet::dielectric_pdf(distribution, roughness, eta, wo, wi),
        }
    }

    /// Samples `wi` given `wo` with random numbers `u` in [0, 1) (see the module docs);
    /// `None` when no direction is produced (the sample then carries no energy).
    pub fn sample(&self, wo: Vec3, u: [f32; 3], mode: TransportMode) -> Option<BsdfSample> {
        let s = self.sample_direction(wo, u, mode)?;
        if s.flags.is_specular() {
            return Some(s);
        }
        // Non-delta lobes: f and pdf from eval and pdf, so they agree by construction.
        let f = self.eval(wo, s.wi, mode);
        let pdf = self.pdf(wo, s.wi, mode);
        (pdf > 0.0).then_some(BsdfSample { f, pdf, ..s })
    }

    /// The sampling step alone: for delta lobes a complete sample, for the others only
    /// `wi`, `flags` and `eta` (`f` and `pdf` are left 0 for the caller to evaluate).
    pub fn sample_direction(
        &self,
        wo: Vec3,
        u: [f32; 3],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        Some(match *self {
            Bsdf::Lambert { .. } | Bsdf::OrenNayar { .. } => {
                let wi = lambert::sample_wi(wo, u[1], u[2])?;
                BsdfSample {
                    f: Vec3::ZERO,
                    wi,
                    pdf: 0.0,
                    flags: BsdfFlags::REFLECTION | BsdfFlags::DIFFUSE,
                    eta: 1.0,
                    layer: 0,
                }
            }
            Bsdf::Mirror { tint } => specular::mirror_sample(tint, wo)?,
            Bsdf::Dielectric { tint, eta } => {
                specular::dielectric_sample(tint, eta, wo, u[0], mode)?
            }
            // No interface: straight through, the smooth dielectric of η 1 (see
            // [`microfacet`]).
            Bsdf::MicrofacetDielectric { tint, eta, .. } if eta == 1.0 => {
                specular::dielectric_sample(tint, eta, wo, u[0], mode)?
            }
            Bsdf::MicrofacetReflection {
                distribution,
                roughness,
                ..
            } => microfacet::reflection_sample_wi(distribution, roughness, wo, u[1], u[2])?,
            Bsdf::MicrofacetDielectric {
                distribution,
                roughness,
                eta,
                ..
            } => microfacet::dielectric_sample_wi(distribution, roughness, eta, wo, u)?,
        })
    }
}

/// The layer kinds `bsdfs` use, bit k for [`kind`] k: the specialization constant
/// `BSDF_KINDS` of `bsdf.glsl`, which compiles the other kinds out of a kernel.
pub fn layer_kinds(bsdfs: &[BsdfParams]) -> u32 {
    bsdfs
        .iter()
        .flat_map(|p| &p.layers[..(p.count as usize).min(MAX_LAYERS)])
        .fold(0, |kinds, layer| {
            kinds | 1u32.checked_shl(layer.kind).unwrap_or(0)
        })
}

/// The specialization constants of a kernel that includes `bsdf.glsl`: 0 its workgroup
/// size (`grid.glsl`), 1 the kernel's own constant (`constant_1`; a kernel that declares
/// none ignores it) and 2 `BSDF_KINDS`, the layer kinds compiled in ([`layer_kinds`]).
pub fn kernel_constants(workgroup: u32, constant_1: u32, bsdf_kinds: u32) -> [u32; 3] {
    [workgroup, constant_1, bsdf_kinds]
}

impl BsdfParams {
    /// A stack of the given layers (panics on 0 or more than [`MAX_LAYERS`]).
    pub fn new(layers: &[BsdfLayer]) -> Self {
        assert!(
            (1..=MAX_LAYERS).contains(&layers.len()),
            "a BSDF stack has 1 to {MAX_LAYERS} layers, not {}",
            layers.len()
        );
        let mut p = BsdfParams {
            count: layers.len() as u32,
            ..Default::default()
        };
        p.layers[..layers.len()].copy_from_slice(layers);
        p
    }

    /// A stack of typed BSDFs with their mixture weights.
    pub fn layered(layers: &[(Bsdf, f32)]) -> Self {
        let flat: Vec<BsdfLayer> = layers.iter().map(|(b, w)| b.layer(*w)).collect();
        Self::new(&flat)
    }

    /// The layers in use.
    pub fn active(&self) -> &[BsdfLayer] {
        &self.layers[..(self.count as usize).min(MAX_LAYERS)]
    }

    /// f(wo, wi) of the stack: Σ_k w_k f_k (see [`layered`]).
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        layered::eval(self, wo, wi, mode)
    }

    /// pdf of the stack: Σ_k p_k pdf_k with p_k = w_k / Σ w (see [`layered`]).
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        layered::pdf(self, wo, wi, mode)
    }

    /// Samples one layer, then a direction from it (see [`layered`]).
    pub fn sample(&self, wo: Vec3, u: [f32; 3], mode: TransportMode) -> Option<BsdfSample> {
        layered::sample(self, wo, u, mode)
    }
}

/// The shading-normal correction factor of the adjoint BSDF (Veach 1997, §5.3):
/// 1 for [`TransportMode::Radiance`]; for [`TransportMode::Importance`]
/// |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|). All arguments in world space (any common
/// frame): `ns` shading and `ng` geometric normal, `wo`, `wi` as for the BSDF. Returns 0
/// when a denominator vanishes.
pub fn shading_normal_correction(
    wo: Vec3,
    wi: Vec3,
    ns: Vec3,
    ng: Vec3,
    mode: TransportMode,
) -> f32 {
    if mode == TransportMode::Radiance {
        return 1.0;
    }
    let num = wo.dot(ns).abs() * wi.dot(ng).abs();
    let denom = wo.dot(ng).abs() * wi.dot(ns).abs();
    if denom == 0.0 {
        0.0
    } else {
        num / denom
    }
}
