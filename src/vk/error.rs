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
    #[error("--device {0}: no such device (see `splitray info`)")]
    UnknownDevice(String),
    #[error("GPU memory allocation failed for '{name}': {source}")]
    Alloc {
        name: String,
        #[source]
        source: gpu_allocator::AllocationError,
    },
    #[error("buffer '{name}' is {size} bytes, more than this device's maxStorageBufferRange ({limit} bytes)")]
    BufferTooLarge { name: String, size: u64, limit: u64 },
    #[error("kernel '{0}' has malformed SPIR-V")]
    BadSpirv(&'static str),
    #[error("the validation layer VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)")]
    ValidationUnavailable,
    #[error("{0}")]
    Usage(String),
}

pub type Result<T, E = VkError> = std::result::Result<T, E>;

/// Maps a raw `vk::Result` error into [`VkError::Call`] naming the entry point.
pub(crate) trait CallContext<T> {
    fn call(self, call: &'static str) -> Result<T>;
}

impl<T> CallContext<T> for std::result::Result<T, vk::Result> {
    fn call(self, call: &'static str) -> Result<T> {
        self.map_err(|result| VkError::Call { call, result })
    }
}
