//! The balance heuristic of Veach's bidirectional techniques, computed recursively from
//! two quantities per subpath vertex (`dVCM`, `dVC`: the vertex-connection part of
//! Georgiev's "Implementing Vertex Connection and Merging", 2012, as SmallVCM's
//! `vertexcm.hxx` has it), so that a connection's weight costs O(1) whatever the path
//! length. [`crate::bidir::oracle`] computes the same weights by brute force from
//! explicit products of densities; `tests/suite/bidir_mis.rs` holds the two equal.
//!
//! # The path and its techniques
//!
//! A path of k segments runs from x₀ (on a light) to x_k (the pinhole). Technique
//! (s, t), s + t = k + 1, samples x₀…x_{s−1} by the light subpath and x_k…x_s by the
//! camera subpath and connects x_{s−1} to x_s (s = 0: the camera subpath hits an
//! emitter; t = 1: light tracing; s = 1, t ≥ 2: next-event estimation with a fresh
//! light sample). p→ᵢ is the area density of xᵢ under light sampling, p←ᵢ under camera
//! sampling; the technique's density is p_s = Π_{i<s} p→ᵢ Π_{i≥s} p←ᵢ, except that s = 1
//! (t ≥ 2) chooses x₀ with next-event estimation's density ("direct") instead of the
//! emission sample's. Techniques are weighted by the balance heuristic over *sample
//! counts* (Veach 1997, §9.2.4): w_s = n_s p_s / Σ_j n_j p_j, where n_j is how many
//! samples of technique j one pixel estimate takes ([`TechniqueCounts`]).
//!
//! # The recursion
//!
//! With R_j = n_j p_j / (n_s p_s), 1 / w_s = 1 + Σ_{j<s} R_j + Σ_{j>s} R_j. The light
//! side's sum is p←_{s−1} · A_{s−1} / n_s with A₀ = n₀ / p→₀ and
//! Aᵢ = (n'ᵢ + p←_{i−1} A_{i−1}) / p→ᵢ (n'ᵢ the count of technique s' = i); split at
//! each vertex into the part that does not depend on the next vertex (`d_vcm` = 1/p→ᵢ,
//! its count applied where it is used) and the part that needs the reverse
//! solid-angle density at xᵢ towards x_{i−1} (`d_vc`), A = n' d_vcm + ω← d_vc. The
//! camera side is the mirror image. Area densities p = ω |cos θ| / d² share their
//! distances with the vertex they convert to, so the updates carry cosines and one d²
//! ([`SubpathMis::arrive`], [`SubpathMis::scatter`]).
//!
//! **Delta lobes.** A vertex that scattered through a delta lobe (mirror, smooth
//! dielectric) cannot end a connection: the techniques with it as an endpoint drop out
//! (`d_vcm` = 0 past it), and its forward and reverse "densities" — the discrete
//! probability of the lobe, equal in both directions (mirror: the layer's probability;
//! dielectric: Fresnel reflectance is the same from both sides) — cancel, leaving the
//! cosine ratio that converts one delta parametrisation into the other (SmallVCM; pbrt-v4
//! drops that ratio, which keeps the weights summing to 1 but is not the balance
//! heuristic). A point light (delta position) cannot be hit: technique s = 0 drops out.
//!
//! **Russian roulette is not in these densities.** `pt` and the bidirectional walks
//! use Mitsuba's roulette, q = min(max β · η², 0.95) from `rr_depth`, whose survival
//! probability depends on the subpath's throughput. The reverse density of a vertex would
//! then need the throughput of the *other* subpath up to it — not a per-vertex quantity,
//! so no O(1) recursion can hold it — and folding in only the known forward q makes the
//! weights of a path's techniques stop summing to 1 (a biased image: two techniques of
//! equal density and survival q get 2q/(1+q) < 1). Roulette is instead an unbiased
//! thinning on top of the balance heuristic of the roulette-free densities, exactly as
//! `pt` (and Mitsuba) leave q out of their MIS. A method whose survival probability is a
//! function of the vertex alone may fold it into the densities it passes here.
//!
//! # Seams for the GPU methods
//!
//! [`TechniqueCounts`] is where the light-vertex cache and CBPT enter: LVC-BDPT connects a
//! camera vertex to N of |C| cached vertices of M light paths (count N·M/|C| for
//! connections, SmallVCM's `mLightSubPathCount` for light tracing); CBPT combines each
//! camera path with N_L light paths (count N_L for s ≥ 1, t ≥ 2). A count of 0 removes a
//! technique from the weights (the `light` integrator keeps only t = 1).

/// How many samples of each technique family one pixel estimate takes (n_j of the
/// balance heuristic). Technique (1, 1) — an emitter point connected straight to the
/// camera — has its own count: `bpt` leaves emitters seen directly to s = 0 (as pbrt and
/// SmallVCM do: light tracing them is noisy), the light tracer has nothing else.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TechniqueCounts {
    /// s = 0: the camera subpath hits an emitter.
    pub emitter_hit: f32,
    /// s = 1, t ≥ 2: next-event estimation.
    pub light_sample: f32,
    /// s ≥ 2, t ≥ 2: a light vertex connected to a camera vertex.
    pub connection: f32,
    /// t = 1, s ≥ 2: light tracing (the light subpaths splatted into each pixel).
    pub light_trace: f32,
    /// (s, t) = (1, 1): an emitter point connected to the camera.
    pub light_trace_emitter: f32,
}

impl TechniqueCounts {
    /// Standard BPT: per pixel and pass one camera subpath, one light subpath paired with
    /// it, and `light_paths` light subpaths splatted into the image.
    pub fn bpt(light_paths: f32) -> Self {
        Self {
            emitter_hit: 1.0,
            light_sample: 1.0,
            connection: 1.0,
            light_trace: light_paths,
            light_trace_emitter: 0.0,
        }
    }

    /// Light tracing alone, emitters seen directly included.
    pub fn light_tracer(light_paths: f32) -> Self {
        Self {
            emitter_hit: 0.0,
            light_sample: 0.0,
            connection: 0.0,
            light_trace: light_paths,
            light_trace_emitter: light_paths,
        }
    }

    /// The count of technique (s, t).
    pub fn of(&self, s: usize, t: usize) -> f32 {
        match (s, t) {
            (0, _) => self.emitter_hit,
            (1, 1) => self.light_trace_emitter,
            (_, 1) => self.light_trace,
            (1, _) => self.light_sample,
            _ => self.connection,
        }
    }

    /// The count of the `d_vcm` term of light-subpath vertex `i` ≥ 1: the technique whose
    /// camera subpath reaches down to xᵢ (s' = i, t' ≥ 2).
    pub fn light_vertex(&self, i: usize) -> f32 {
        if i == 1 {
            self.light_sample
        } else {
            self.connection
        }
    }

    /// The count of the `d_vcm` term of camera-subpath vertex `j` ≥ 1: the technique whose
    /// light subpath reaches up to it (t' = j). `on_emitter`: the term of an emitter hit
    /// at that vertex, whose light subpath is that one emitter point (s' = 1).
    pub fn camera_vertex(&self, j: usize, on_emitter: bool) -> f32 {
        match (j == 1, on_emitter) {
            (true, false) => self.light_trace,
            (true, true) => self.light_trace_emitter,
            (false, false) => self.connection,
            (false, true) => self.light_sample,
        }
    }
}

/// The densities of a light subpath's first vertex that its MIS quantities start from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionDensities {
    /// Area density with which next-event estimation would choose the point (discrete
    /// pmf for a point light).
    pub direct: f32,
    /// Area density with which the light subpath chose it.
    pub emit: f32,
    /// Solid-angle density of the emitted direction.
    pub direction: f32,
    /// cos θ of the emitted direction at the light (1 for a point light).
    pub cos: f32,
    /// A point light: nothing can hit it.
    pub delta_position: bool,
}

/// The recursive MIS quantities a subpath carries to its current vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubpathMis {
    /// 1 / p of the current vertex under its own subpath's sampling (with the cosine and
    /// distance of the last segment applied by [`SubpathMis::arrive`]); 0 when the vertex
    /// before it scattered through a delta lobe.
    pub d_vcm: f32,
    /// The rest of the partial sum, counts included, to be multiplied by the reverse
    /// solid-angle density at the current vertex.
    pub d_vc: f32,
}

impl SubpathMis {
    /// A camera subpath before its first segment; `pdf_dir` is the camera's solid-angle
    /// density of the ray.
    pub fn camera(pdf_dir: f32) -> Self {
        Self {
            d_vcm: 1.0 / pdf_dir,
            d_vc: 0.0,
        }
    }

    /// A light subpath before its first segment. `d_vcm` holds the ratio of the direct
    /// to the emission density of x₀, so that the count of s' = 1 applies at x₁.
    pub fn light(counts: &TechniqueCounts, e: &EmissionDensities) -> Self {
        let emitted = e.emit * e.direction;
        Self {
            d_vcm: e.direct / emitted,
            d_vc: if e.delta_position {
                0.0
            } else {
                counts.emitter_hit * e.cos / emitted
            },
        }
    }

    /// The subpath traced a segment of squared length `dist2` and arrived at a vertex
    /// where |cos θ| against the geometric normal is `cos_in`.
    pub fn arrive(&mut self, dist2: f32, cos_in: f32) {
        self.d_vcm *= dist2 / cos_in;
        self.d_vc /= cos_in;
    }

    /// The subpath scatters at its current vertex: `count_here` is the count of the
    /// vertex's `d_vcm` term ([`TechniqueCounts::light_vertex`] /
    /// [`TechniqueCounts::camera_vertex`]), `cos_out` |cos θ| of the sampled direction
    /// against the geometric normal, `pdf_fwd` the solid-angle density of the sampled
    /// direction, `pdf_rev` that of the reverse (towards the previous vertex, arriving
    /// along the sampled direction); `delta`: the sampled lobe is a Dirac delta.
    pub fn scatter(
        &mut self,
        count_here: f32,
        cos_out: f32,
        pdf_fwd: f32,
        pdf_rev: f32,
        delta: bool,
    ) {
        if delta {
            self.d_vc *= cos_out;
            self.d_vcm = 0.0;
        } else {
            self.d_vc = cos_out / pdf_fwd * (self.d_vc * pdf_rev + count_here * self.d_vcm);
            self.d_vcm = 1.0 / pdf_fwd;
        }
    }

    /// The partial sum of a connection endpoint: `count_here · d_vcm + pdf_rev · d_vc`,
    /// with `pdf_rev` the solid-angle density at this vertex towards its predecessor,
    /// arriving from the other endpoint. Multiplied by the other side's area density of
    /// this vertex and divided by the technique's count, it is Σ R_j on this side.
    pub fn partial(&self, count_here: f32, pdf_rev: f32) -> f32 {
        count_here * self.d_vcm + pdf_rev * self.d_vc
    }
}

fn balance(others: f32) -> f32 {
    1.0 / (1.0 + others)
}

/// Weight of a connection (s ≥ 2, t ≥ 2): `light_rev` is the area density of the light
/// endpoint y under sampling from the camera endpoint z, `light_partial` y's
/// [`SubpathMis::partial`], `camera_fwd` the area density of z under sampling from y,
/// `camera_partial` z's.
pub fn connection_weight(
    counts: &TechniqueCounts,
    light_rev: f32,
    light_partial: f32,
    camera_fwd: f32,
    camera_partial: f32,
) -> f32 {
    balance((light_rev * light_partial + camera_fwd * camera_partial) / counts.connection)
}

/// Weight of an emitter hit (s = 0) at camera vertex `j`: `direct` and `emit` are the
/// area densities with which next-event estimation and light subpaths choose the point,
/// `emit_dir` the emission density towards the camera subpath's previous vertex.
pub fn emitter_hit_weight(
    counts: &TechniqueCounts,
    j: usize,
    camera: &SubpathMis,
    direct: f32,
    emit: f32,
    emit_dir: f32,
) -> f32 {
    // The d_vcm term is the technique with one light vertex: (1, 1) when the camera
    // sees the emitter directly (the emission sample's density), else next-event
    // estimation (the direct density).
    let one_vertex = if j == 1 { emit } else { direct };
    let others =
        one_vertex * counts.camera_vertex(j, true) * camera.d_vcm + emit * emit_dir * camera.d_vc;
    balance(others / counts.emitter_hit)
}

/// Weight of next-event estimation (s = 1) at camera vertex `j`: `light_rev` is the
/// area density of the light point under sampling from the camera vertex (0 for a point
/// light), `direct`/`emit` its two position densities, `camera_fwd` the area density of
/// the camera vertex under emission from the light point, `camera_partial` the camera
/// vertex's [`SubpathMis::partial`].
pub fn light_sample_weight(
    counts: &TechniqueCounts,
    light_rev: f32,
    direct: f32,
    emit: f32,
    camera_fwd: f32,
    camera_partial: f32,
) -> f32 {
    let others = counts.emitter_hit * light_rev + emit * camera_fwd * camera_partial;
    balance(others / (counts.light_sample * direct))
}

/// Weight of light tracing (t = 1, s ≥ 2): `camera_area` is the camera's area density of
/// the light vertex, `light_partial` its [`SubpathMis::partial`].
pub fn light_trace_weight(counts: &TechniqueCounts, camera_area: f32, light_partial: f32) -> f32 {
    balance(camera_area * light_partial / counts.light_trace)
}

/// Weight of technique (1, 1), an emitter point connected to the camera: `camera_area`
/// is the camera's area density of the point, `emit` the light subpath's.
pub fn light_trace_emitter_weight(
    counts: &TechniqueCounts,
    camera_area: f32,
    emit: f32,
    delta_position: bool,
) -> f32 {
    let hit = if delta_position {
        0.0
    } else {
        counts.emitter_hit * camera_area / emit
    };
    balance(hit / counts.light_trace_emitter)
}
