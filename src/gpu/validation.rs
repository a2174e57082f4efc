//! The Vulkan validation layer's messages, collected so that a test or a command can fail on
//! any (validation errors fail the test suite).

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::Mutex;

/// The Khronos validation layer.
pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Validation messages collected by the debug messenger.
#[derive(Debug, Default)]
pub struct ValidationLog {
    pub(super) errors: Mutex<Vec<String>>,
}

impl ValidationLog {
    /// Validation errors (and warnings) seen so far.
    pub fn messages(&self) -> Vec<String> {
        self.errors.lock().map(|e| e.clone()).unwrap_or_default()
    }
}

/// The debug messenger's callback: `user` is the [`ValidationLog`] it appends to.
pub(super) unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    let msg = unsafe { (*data).message_as_c_str() }
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    let log = unsafe { &*(user as *const ValidationLog) };
    if severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
            | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
    ) {
        eprintln!("vulkan validation: {msg}");
        if let Ok(mut e) = log.errors.lock() {
            e.push(msg);
        }
    }
    vk::FALSE
}
