//! The integrators' pipelines: one per kernel of `glsl/integrator/lvc/`, and `pt`'s
//! material-key and gather kernels (which take `pt`'s push constants).

use super::gpu::LvcPush;
use super::options::{LvcOptions, Variant, MAX_CANDIDATES};
use crate::bsdf::kernel_constants;
use crate::integrator::pt::gpu::PtParams;
use crate::shaders::{self, Kernel};
use crate::vk::{self, ComputePipeline, Gpu};

pub const WORKGROUP: u32 = 64;

pub struct Kernels {
    pub light_generate: ComputePipeline,
    pub light_shade: ComputePipeline,
    pub light_store: ComputePipeline,
    pub light_index: ComputePipeline,
    pub light_connect: ComputePipeline,
    pub splat: ComputePipeline,
    pub camera_generate: ComputePipeline,
    pub camera_vertex: ComputePipeline,
    pub camera_direct: ComputePipeline,
    /// Uniform connections (LVC-BDPT) or resampled ones (CIS-LBDPT): only the variant's
    /// is built (a driver that compiles at pipeline creation pays for one).
    pub camera_connect: ComputePipeline,
    pub camera_bounce: ComputePipeline,
    /// Its tally summed per subgroup where the device has subgroup arithmetic, else by
    /// one atomic per invocation ([`AccumulateTally`]).
    pub camera_accumulate: ComputePipeline,
    pub finish: ComputePipeline,
    /// `pt`'s: the material key of each live path's hit and the identity order.
    /// `pt`'s: survivors' rays and ids to the front of the other list.
    pub gather: ComputePipeline,
}

impl Kernels {
    /// The kernels of `options`' variant for a scene whose BSDFs use `bsdf_kinds`
    /// ([`crate::bsdf::layer_kinds`]; the other kinds are compiled out); CIS-LBDPT's
    /// connection kernel holds exactly `options.candidates` candidates per camera vertex.
    pub fn new(gpu: &Gpu, options: &LvcOptions, bsdf_kinds: u32) -> vk::Result<Self> {
        Self::with_tally(gpu, options, bsdf_kinds, AccumulateTally::for_device(gpu))
    }

    /// [`Kernels::new`] with the accumulation's tally made as `tally` says (tests build
    /// both).
    pub fn with_tally(
        gpu: &Gpu,
        options: &LvcOptions,
        bsdf_kinds: u32,
        tally: AccumulateTally,
    ) -> vk::Result<Self> {
        let with_constants = |kernel: Kernel, bindings, constants: &[u32]| {
            vk::compute_pipeline(
                gpu,
                kernel,
                bindings,
                size_of::<LvcPush>() as u32,
                constants,
            )
        };
        // Constant 1 is camera_connect's alone.
        let lvc = |kernel: Kernel, bindings| {
            with_constants(
                kernel,
                bindings,
                &kernel_constants(WORKGROUP, 1, bsdf_kinds),
            )
        };
        let pt = |kernel: Kernel, bindings| {
            vk::compute_pipeline(
                gpu,
                kernel,
                bindings,
                size_of::<PtParams>() as u32,
                &[WORKGROUP],
            )
        };
        Ok(Self {
            light_generate: lvc(shaders::INTEGRATOR_LVC_LIGHT_GENERATE, 7)?,
            light_shade: lvc(shaders::INTEGRATOR_LVC_LIGHT_SHADE, 15)?,
            light_store: lvc(shaders::INTEGRATOR_LVC_LIGHT_STORE, 4)?,
            light_index: lvc(shaders::INTEGRATOR_LVC_LIGHT_INDEX, 3)?,
            light_connect: lvc(shaders::INTEGRATOR_LVC_LIGHT_CONNECT, 6)?,
            splat: lvc(shaders::INTEGRATOR_LVC_SPLAT, 5)?,
            camera_generate: lvc(shaders::INTEGRATOR_LVC_CAMERA_GENERATE, 5)?,
            camera_vertex: lvc(shaders::INTEGRATOR_LVC_CAMERA_VERTEX, 13)?,
            camera_direct: lvc(shaders::INTEGRATOR_LVC_CAMERA_DIRECT, 10)?,
            camera_connect: {
                let (kernel, constants) = camera_connect(options, bsdf_kinds);
                with_constants(kernel, 11, &constants)?
            },
            camera_bounce: lvc(shaders::INTEGRATOR_LVC_CAMERA_BOUNCE, 9)?,
            camera_accumulate: lvc(tally.kernel(), 8)?,
            finish: lvc(shaders::INTEGRATOR_LVC_FINISH, 5)?,
            gather: pt(shaders::INTEGRATOR_PT_GATHER, 5)?,
        })
    }
}

/// The variant's connection kernel and its specialization constants: uniform, or
/// resampled with shared memory for the run's M candidates per invocation (constant 1,
/// `CANDIDATE_CAPACITY`); both with the scene's BSDF kinds (constant 2).
fn camera_connect(options: &LvcOptions, bsdf_kinds: u32) -> (Kernel, [u32; 3]) {
    let (kernel, capacity) = match options.variant {
        Variant::LvcBdpt => (shaders::INTEGRATOR_LVC_CAMERA_CONNECT, 1),
        Variant::CisLbdpt => (
            shaders::INTEGRATOR_LVC_CAMERA_CONNECT__RESAMPLED,
            options.candidates.clamp(1, MAX_CANDIDATES),
        ),
    };
    (kernel, kernel_constants(WORKGROUP, capacity, bsdf_kinds))
}

/// How `camera_accumulate` sums its visibility tally.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccumulateTally {
    /// subgroupAdd, then one atomic per subgroup.
    Subgroup,
    /// One atomic per invocation with something to count.
    Atomic,
}

impl AccumulateTally {
    pub fn for_device(gpu: &Gpu) -> Self {
        if gpu.info().capabilities.subgroup_arithmetic {
            Self::Subgroup
        } else {
            Self::Atomic
        }
    }

    pub fn kernel(self) -> Kernel {
        match self {
            Self::Subgroup => shaders::INTEGRATOR_LVC_CAMERA_ACCUMULATE__SUBGROUP,
            Self::Atomic => shaders::INTEGRATOR_LVC_CAMERA_ACCUMULATE,
        }
    }
}

/// `pt`'s push constants for its sort-key and gather kernels, which read only the live
/// count.
pub fn pt_params(active_count: u32) -> PtParams {
    PtParams {
        active_count,
        ..Default::default()
    }
}
