//! The SPIR-V of every kernel in `glsl/`, compiled by `build.rs` and embedded here.

/// One embedded compute kernel.
#[derive(Clone, Copy, Debug)]
pub struct Kernel {
    /// Identifier derived from the file path below `glsl/` (plus `__variant`).
    pub name: &'static str,
    /// SPIR-V bytes (a multiple of four; copied into aligned words on pipeline creation).
    pub spirv: &'static [u8],
    /// For a kernel that takes buffers by address: the same kernel taking them as
    /// descriptors (glsl/common/address.glsl; src/vk/pipeline.rs picks one per dispatch).
    pub descriptor_twin: Option<&'static [u8]>,
}

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Looks a kernel up by its identifier.
pub fn by_name(name: &str) -> Option<Kernel> {
    ALL.iter().copied().find(|k| k.name == name)
}
