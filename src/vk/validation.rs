//! Validation-layer message collection.
//!
//! Every message is logged; errors and warnings are counted, kept, and turned into test
//! failures by the test harness. A message can be suppressed only by its VUID, with the
//! reason written beside it in [`SUPPRESSED`].

use std::ffi::CStr;
use std::sync::Mutex;

use ash::vk;

/// (VUID or message-id name, why it is suppressed). Empty: nothing is suppressed yet.
pub const SUPPRESSED: &[(&str, &str)] = &[];

/// One message the debug messenger reported.
#[derive(Clone, Debug)]
pub struct ValidationMessage {
    pub severity: &'static str,
    pub id_name: String,
    pub text: String,
}

/// Collected messages of one instance. Shared with the debug callback.
#[derive(Default, Debug)]
pub struct ValidationLog {
    messages: Mutex<Vec<ValidationMessage>>,
}

impl ValidationLog {
    /// Errors and warnings reported so far (loader chatter excluded).
    pub fn messages(&self) -> Vec<ValidationMessage> {
        self.messages.lock().unwrap().clone()
    }

    pub fn count(&self) -> usize {
        self.messages.lock().unwrap().len()
    }

    /// Removes and returns the collected messages.
    pub fn take(&self) -> Vec<ValidationMessage> {
        std::mem::take(&mut *self.messages.lock().unwrap())
    }

    fn push(&self, message: ValidationMessage) {
        self.messages.lock().unwrap().push(message);
    }
}

fn cstr_or_empty(ptr: *const std::ffi::c_char) -> String {
    if ptr.is_null() {
        String::new()
    } else {
        // SAFETY: the layer passes NUL-terminated strings valid for the callback's duration.
        unsafe { CStr::from_ptr(ptr) }
            .to_string_lossy()
            .into_owned()
    }
}

/// The debug-utils callback. `user_data` points at the instance's [`ValidationLog`].
pub(crate) unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut std::ffi::c_void,
) -> vk::Bool32 {
    if data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: non-null, provided by the layer for the duration of the call.
    let data = unsafe { &*data };
    let id_name = cstr_or_empty(data.p_message_id_name);
    let text = cstr_or_empty(data.p_message);
    let is_problem = severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
            | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
    );
    // Loader chatter arrives as GENERAL messages (e.g. about manifest files); only
    // validation and performance messages, and GENERAL errors, count as problems.
    let counts = is_problem
        && (types.intersects(
            vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        ) || severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR));
    let suppressed = SUPPRESSED.iter().any(|(vuid, _)| id_name == *vuid);
    let label = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        "error"
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        "warning"
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::INFO) {
        "info"
    } else {
        "verbose"
    };
    if counts && !suppressed {
        log::error!("vulkan {label} [{id_name}]: {text}");
        if !user_data.is_null() {
            // SAFETY: the instance owns the log (boxed, pinned) and destroys the messenger
            // before dropping it.
            let log = unsafe { &*(user_data as *const ValidationLog) };
            log.push(ValidationMessage {
                severity: label,
                id_name,
                text,
            });
        }
    } else {
        log::debug!("vulkan {label} [{id_name}]: {text}");
    }
    vk::FALSE
}
