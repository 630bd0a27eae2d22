//! The balance heuristic of combinatorial bidirectional path tracing (CBPT, Pajot et al.
//! 2011): populations of N_C camera paths and N_L light paths combined exhaustively, and
//! N_T light paths light-traced on the side.
//!
//! # Technique counts
//!
//! Per pass of `cbpt` every pixel gets n_cam camera paths (4: the stratified image
//! positions of §3.2), and each camera path meets the N_L light paths of its population
//! (§3.1), so per camera path a pixel estimate takes
//!
//! - 1 sample of s = 0 (the camera path hits an emitter, f_{c,−1});
//! - N_L of s = 1, t ≥ 2: the camera vertex linked to y₀ of each light path (y₀ is a
//!   point of the light table chosen as next-event estimation would choose it, so this is
//!   next-event estimation with N_L samples);
//! - N_L of s ≥ 2, t ≥ 2 (the connections f_{i,j}, j ≥ 1);
//! - M / n_cam of t = 1, where M is the pass's light-traced paths (N_T per step): each
//!   is a sample of every pixel, as `bpt`'s light subpaths are.
//!
//! With these counts in [`TechniqueCounts`], the recursive weights of [`super::mis`] are
//! CBPT's: "the MIS weights account for the N_L light paths every camera path is
//! combined with".
//!
//! # No light-traced direct lighting
//!
//! CBPT's light tracer "does not contribute to direct lighting, as it brings a lot of
//! variance for this type of light transport" (§3.1): technique (2, 1) — a light vertex
//! on a surface linked to the pinhole, a path light → surface → camera — is out, and
//! (1, 1) too, as in `bpt` (emitters seen directly are left to s = 0). A count that
//! depends on the path's length does not fit the recursion, which folds one count per
//! vertex into quantities shared by every longer path, so the length-2 paths are handled
//! where they arise (every other path keeps [`CombinatorialCounts::walk`]):
//!
//! - next-event estimation at the first camera vertex weighs with
//!   [`CombinatorialCounts::of_path`]`(2)` (its light-tracing term is (2, 1));
//! - an emitter hit at the second camera vertex: the camera subpath's `d_vc` there holds
//!   exactly the term of (2, 1) — it is zero at the first hit and the scattering there
//!   adds the count of t' = 1 times `d_vcm` — so it is dropped ([`emitter_hit`]);
//! - the light tracer skips light vertex 1 ([`CombinatorialCounts::traces_light_vertex`]).
//!
//! `tests/suite/cbpt_mis.rs` holds every weight equal to the brute-force oracle with the
//! counts of [`CombinatorialCounts::of_path`].

use super::connect::{Connector, Sample};
use super::mis::TechniqueCounts;
use super::vertex::Vertex;
use super::Counters;

/// CBPT's sampling rates (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CombinatorialCounts {
    /// N_L: light paths every camera path is combined with.
    pub light_paths: f32,
    /// Light-traced paths per camera path of a pixel: M / n_cam (0: no light tracing).
    pub light_traced: f32,
}

impl CombinatorialCounts {
    /// The counts every path of more than two segments is weighted with, and that the
    /// random walks fold into their MIS quantities.
    pub fn walk(&self) -> TechniqueCounts {
        TechniqueCounts {
            emitter_hit: 1.0,
            light_sample: self.light_paths,
            connection: self.light_paths,
            light_trace: self.light_traced,
            light_trace_emitter: 0.0,
        }
    }

    /// The counts of the techniques of a path of `segments` segments: light tracing
    /// leaves out direct lighting (two segments).
    pub fn of_path(&self, segments: usize) -> TechniqueCounts {
        let mut counts = self.walk();
        if segments == 2 {
            counts.light_trace = 0.0;
        }
        counts
    }

    /// Whether the light tracer connects light-subpath vertex `i` to the camera: paths
    /// of at least three segments (`i` ≥ 2), when there is light tracing at all.
    pub fn traces_light_vertex(&self, i: usize) -> bool {
        i >= 2 && self.light_traced > 0.0
    }
}

/// The emitter hit (s = 0) at camera vertex `j`, weighted with [`CombinatorialCounts`]:
/// `connector` holds [`CombinatorialCounts::walk`]; at `j` = 2 (a path of two segments)
/// the light-tracing term leaves the weight (see the module docs).
pub fn emitter_hit(
    connector: &Connector,
    camera: &[Vertex],
    j: usize,
    counters: &mut Counters,
) -> Option<Sample> {
    if j != 2 {
        return connector.emitter_hit(camera, j, counters);
    }
    let mut hit = camera[2];
    hit.mis.d_vc = 0.0;
    connector.emitter_hit(&[camera[0], camera[1], hit], 2, counters)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_follow_the_populations() {
        let c = CombinatorialCounts {
            light_paths: 15.0,
            light_traced: 3.5,
        };
        let w = c.walk();
        assert_eq!(
            (w.emitter_hit, w.light_sample, w.connection),
            (1.0, 15.0, 15.0)
        );
        assert_eq!((w.light_trace, w.light_trace_emitter), (3.5, 0.0));
        assert_eq!(c.of_path(3), w);
        assert_eq!(c.of_path(2).of(2, 1), 0.0);
        assert_eq!(c.of_path(2).of(1, 2), 15.0);
        assert!(!c.traces_light_vertex(1) && c.traces_light_vertex(2));
        let none = CombinatorialCounts {
            light_traced: 0.0,
            ..c
        };
        assert!(!none.traces_light_vertex(5));
    }
}
