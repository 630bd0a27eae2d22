//! Bidirectional path tracing on the CPU: the machinery every bidirectional method of
//! splitray shares and is checked against (the integrators are `integrator::bpt`).
//!
//! - [`scene`]: `pt`'s scene tables and the CPU BVH, with `pt`'s conventions (one-sided
//!   emitters, shading normals flipped to the geometric side, ray offsets);
//! - [`camera`]: the pinhole as a vertex — importance W_e, direction density, projection;
//! - [`lights`]: light sampling with the light table's semantics (by power, then area);
//! - [`vertex`]: one vertex type for both subpaths;
//! - [`walk`]: the camera and light random walks (Mitsuba's depth and roulette);
//! - [`connect`]: one technique (s, t) evaluated — contribution and MIS weight;
//! - [`techniques`]: all techniques of a pair of subpaths;
//! - [`mis`]: the recursive balance heuristic (dVCM/dVC) and its technique counts;
//! - [`combinatorial`]: CBPT's counts (populations of camera and light paths combined
//!   exhaustively, light tracing without direct lighting);
//! - [`oracle`], [`densities`]: the brute-force balance heuristic from explicit
//!   densities, and those densities read off real subpaths;
//! - [`random`]: the counter-based random numbers of `glsl/common/random.glsl`.
//!
//! Indexing: a complete path of k segments is x₀ (light) … x_k (pinhole); technique
//! (s, t) has s light vertices and t camera vertices, s + t = k + 1. Light subpath
//! vertex i is xᵢ, camera subpath vertex j is x_{k−j}.

pub mod camera;
pub mod combinatorial;
pub mod connect;
pub mod densities;
pub mod lights;
pub mod mis;
pub mod oracle;
pub mod random;
pub mod scene;
pub mod techniques;
pub mod vertex;
pub mod walk;

pub use camera::PinholeCamera;
pub use connect::{Connector, Sample};
pub use mis::{SubpathMis, TechniqueCounts};
pub use scene::CpuScene;
pub use vertex::{Vertex, VertexKind};
pub use walk::WalkSettings;

/// `x > 0`, false for NaN: densities, distances and throughputs must be strictly
/// positive (and not NaN) for a sample to count.
pub(crate) fn positive(x: f32) -> bool {
    x > 0.0
}

/// What the bidirectional integrators count (reported by `--stats`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub camera_paths: u64,
    pub light_paths: u64,
    /// Subpath vertices past the pinhole and the light.
    pub vertices: u64,
    /// Rays cast: walk segments and visibility tests.
    pub rays: u64,
    /// Visibility tests of connections, next-event and light-tracing samples.
    pub connections: u64,
    /// Techniques evaluated (CBPT's basic contributions f_{i,j}, §6.2): every (s, t)
    /// whose endpoints could be connected and whose contribution and weight were
    /// computed, visible or not.
    pub basic_contributions: u64,
    /// Contributions dropped because they were NaN or infinite.
    pub non_finite: u64,
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Self) {
        self.camera_paths += o.camera_paths;
        self.light_paths += o.light_paths;
        self.vertices += o.vertices;
        self.rays += o.rays;
        self.connections += o.connections;
        self.basic_contributions += o.basic_contributions;
        self.non_finite += o.non_finite;
    }
}
