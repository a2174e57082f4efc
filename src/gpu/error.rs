//! Errors of the Vulkan layer: a failed Vulkan call names the operation (pass, object) and its
//! result code. The library's [`crate::Error`] wraps them as [`crate::Error::Gpu`], so its core
//! variants hold no Vulkan type.

use ash::vk;

/// A Vulkan call failed.
#[derive(Debug, Clone, thiserror::Error)]
#[error("Vulkan: {what} failed: {result}")]
pub struct GpuError {
    /// The operation (names the pass or object).
    pub what: String,
    /// Vulkan result code.
    pub result: vk::Result,
}

/// Wraps a Vulkan result with the operation that produced it.
pub(crate) trait VkContext<T> {
    /// Names the failed operation.
    fn vk(self, what: &str) -> crate::Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, vk::Result> {
    fn vk(self, what: &str) -> crate::Result<T> {
        self.map_err(|result| {
            GpuError {
                what: what.to_string(),
                result,
            }
            .into()
        })
    }
}
