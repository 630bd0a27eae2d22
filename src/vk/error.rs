//! The error type of the Vulkan layer.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("cannot load the Vulkan library (is libvulkan1 installed?): {0}")]
    Loader(String),
    #[error("{call} failed: {result}")]
    Call {
        call: &'static str,
        result: vk::Result,
    },
    #[error("no Vulkan device is available{0}")]
    NoDevice(String),
    #[error("device '{device}' lacks {what}, which splitray requires")]
    MissingFeature { device: String, what: String },
    /// Carries how the device was named: `--device 7` or `SPLITRAY_DEVICE=7`.
    #[error("{0}: no such device (see `splitray info`)")]
    UnknownDevice(String),
    /// The message carries the cause, not also a `source` (a chain would repeat it).
    #[error("GPU memory allocation failed for '{name}': {error}")]
    Alloc {
        name: String,
        error: gpu_allocator::AllocationError,
    },
    #[error(
        "buffer '{name}' needs {size} bytes ({size_h}), more than one buffer can hold on \
         this device: {limit} bytes ({limit_h}, its {which})",
        size_h = fmt_bytes(*.size),
        limit_h = fmt_bytes(*.limit)
    )]
    BufferTooLarge {
        name: String,
        size: u64,
        limit: u64,
        /// The device limit that binds: maxBufferSize or maxMemoryAllocationSize.
        which: &'static str,
    },
    #[error("kernel '{0}' has malformed SPIR-V")]
    BadSpirv(&'static str),
    #[error("the validation layer VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)")]
    ValidationUnavailable,
    #[error("{0}")]
    Usage(String),
}

pub type Result<T, E = VkError> = std::result::Result<T, E>;

/// A byte count for people: `512 B`, `96.0 MiB`, `2.00 GiB`.
pub fn fmt_bytes(bytes: u64) -> String {
    const KIB: f64 = 1024.0;
    let b = bytes as f64;
    if b < KIB {
        format!("{bytes} B")
    } else if b < KIB * KIB {
        format!("{:.1} KiB", b / KIB)
    } else if b < KIB * KIB * KIB {
        format!("{:.1} MiB", b / (KIB * KIB))
    } else {
        format!("{:.2} GiB", b / (KIB * KIB * KIB))
    }
}

/// Maps a raw `vk::Result` error into [`VkError::Call`] naming the entry point.
pub(crate) trait CallContext<T> {
    fn call(self, call: &'static str) -> Result<T>;
}

impl<T> CallContext<T> for std::result::Result<T, vk::Result> {
    fn call(self, call: &'static str) -> Result<T> {
        self.map_err(|result| VkError::Call { call, result })
    }
}
