//! Layered materials (thesis §4.4.1): a stack of up to four BSDFs at a shading point,
//! one layer chosen per sample.
//!
//! Following the thesis, which takes its layered system from Pharr and Humphreys
//! (pbrt-v3's `BSDF`, a list of `BxDF`s), the stack is a *weighted mixture*: each layer k
//! has a weight w_k ≥ 0 and
//!
//! - f(wo, wi) = Σ_k w_k f_k(wo, wi) (delta layers contribute 0),
//! - layer k is sampled with probability p_k = w_k / Σ_j w_j,
//! - pdf(wo, wi) = Σ_k p_k pdf_k(wo, wi),
//! - a sample from a non-delta layer returns the full mixture f and pdf at the sampled
//!   `wi` (pbrt-v3's one-sample MIS over components); a sample from a delta layer k
//!   returns w_k f_k and p_k pdf_k, the other layers being of measure zero there.
//!
//! With all weights 1 this is exactly pbrt-v3's `BSDF` (sum of the BxDFs, uniform
//! component choice). The one deviation is the weights: pbrt-v3 has none (a plain sum
//! can reflect more than it receives); with Σ w_k ≤ 1 and energy-conserving layers the
//! stack conserves energy, and the selection follows the weights rather than being
//! uniform. This is a mixture, not a physically stacked (interreflecting) layer model
//! such as Jakob et al. 2014, exactly as in the thesis.
//!
//! The random number `uc` chooses the layer and is then remapped to [0, 1) for the
//! layer's own discrete choice (reflect or refract).

use super::sampling::ONE_MINUS_EPSILON;
use super::{Bsdf, BsdfParams, BsdfSample, TransportMode};
use glam::Vec3;

fn weight(l: &super::BsdfLayer) -> f32 {
    l.tint_weight[3].max(0.0)
}

fn total_weight(p: &BsdfParams) -> f32 {
    p.active().iter().map(weight).sum()
}

pub fn eval(p: &BsdfParams, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
    let mut f = Vec3::ZERO;
    for l in p.active() {
        let w = weight(l);
        if w > 0.0 {
            if let Some(b) = Bsdf::from_layer(l) {
                f += b.eval(wo, wi, mode) * w;
            }
        }
    }
    f
}

pub fn pdf(p: &BsdfParams, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
    let total = total_weight(p);
    if total <= 0.0 {
        return 0.0;
    }
    let mut pdf = 0.0;
    for l in p.active() {
        let w = weight(l);
        if w > 0.0 {
            if let Some(b) = Bsdf::from_layer(l) {
                pdf += b.pdf(wo, wi, mode) * (w / total);
            }
        }
    }
    pdf
}

/// The layer that `uc` selects, its probability and the remapped `uc`.
pub fn choose_layer(p: &BsdfParams, uc: f32) -> Option<(usize, f32, f32)> {
    let total = total_weight(p);
    if total <= 0.0 {
        return None;
    }
    let layers = p.active();
    let last = layers.iter().rposition(|l| weight(l) > 0.0)?;
    let mut cdf = 0.0f32;
    for (k, l) in layers.iter().enumerate() {
        let pk = weight(l) / total;
        if pk <= 0.0 {
            continue;
        }
        if uc < cdf + pk || k == last {
            let remapped = ((uc - cdf) / pk).clamp(0.0, ONE_MINUS_EPSILON);
            return Some((k, pk, remapped));
        }
        cdf += pk;
    }
    None
}

pub fn sample(p: &BsdfParams, wo: Vec3, u: [f32; 3], mode: TransportMode) -> Option<BsdfSample> {
    let (k, pk, uc) = choose_layer(p, u[0])?;
    let layer = &p.layers[k];
    let b = Bsdf::from_layer(layer)?;
    let s = b.sample_direction(wo, [uc, u[1], u[2]], mode)?;
    if s.flags.is_specular() {
        return Some(BsdfSample {
            f: s.f * weight(layer),
            pdf: s.pdf * pk,
            layer: k as u32,
            ..s
        });
    }
    let f = eval(p, wo, s.wi, mode);
    let pdf = pdf(p, wo, s.wi, mode);
    (pdf > 0.0).then_some(BsdfSample {
        f,
        pdf,
        layer: k as u32,
        ..s
    })
}
