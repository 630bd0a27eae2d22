//! The Vulkan instance: loader, optional validation layer, debug messenger.

use std::ffi::CStr;
use std::sync::Arc;

use ash::{ext, vk};

use super::error::{CallContext, Result, VkError};
use super::validation::{debug_callback, ValidationLog};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create the instance.
#[derive(Clone, Copy, Debug, Default)]
pub struct InstanceDesc {
    /// Enable `VK_LAYER_KHRONOS_validation`; its errors and warnings are collected.
    pub validation: bool,
    /// Also enable synchronization validation (implies `validation`).
    pub sync_validation: bool,
}

impl InstanceDesc {
    /// Reads `SPLITRAY_VALIDATION` (`1`, or `sync` for synchronization validation too)
    /// on top of what the caller asked for.
    pub fn with_env(mut self) -> Self {
        match std::env::var("SPLITRAY_VALIDATION").as_deref() {
            Ok("sync") => {
                self.validation = true;
                self.sync_validation = true;
            }
            Ok("1") | Ok("true") | Ok("on") => self.validation = true,
            _ => {}
        }
        self
    }
}

/// Owns the loader entry, the instance and (with validation) the debug messenger.
pub struct Instance {
    /// Keeps libvulkan loaded for as long as the instance lives.
    pub(crate) entry: ash::Entry,
    pub(crate) raw: ash::Instance,
    debug_utils: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Boxed so the debug callback's user-data pointer stays valid.
    log: Box<ValidationLog>,
    pub(crate) validation: bool,
}

impl std::fmt::Debug for Instance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Instance")
            .field("validation", &self.validation)
            .finish()
    }
}

/// Whether the validation layer is installed (for `splitray info`).
pub fn validation_layer_available() -> bool {
    // SAFETY: loading libvulkan runs its initialisers; this is the documented way in.
    let Ok(entry) = (unsafe { ash::Entry::load() }) else {
        return false;
    };
    // SAFETY: a plain global query on a loaded entry.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
    layers
        .iter()
        .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER))
}

impl Instance {
    pub fn new(desc: InstanceDesc) -> Result<Arc<Self>> {
        Self::with_extensions(desc, &[])
    }

    /// [`Instance::new`] with `required` instance extensions enabled too (a window
    /// system's surface extensions); a loader that lacks one is an error naming it.
    pub fn with_extensions(desc: InstanceDesc, required: &[&CStr]) -> Result<Arc<Self>> {
        let desc = desc.with_env();
        let validation = desc.validation || desc.sync_validation;
        // SAFETY: loading libvulkan runs its initialisers; this is the documented way in.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::Loader(e.to_string()))?;
        if validation && !validation_layer_available() {
            return Err(VkError::ValidationUnavailable);
        }

        let app_info = vk::ApplicationInfo::default()
            .application_name(c"splitray")
            .application_version(vk::make_api_version(0, 0, 1, 0))
            .engine_name(c"splitray")
            .api_version(vk::API_VERSION_1_3);
        let layers = if validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let (extensions, has_debug_utils) = instance_extensions(&entry, required)?;
        let log = Box::new(ValidationLog::default());
        let mut messenger_info = messenger_info(&log);
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);

        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation && has_debug_utils {
            // Chained at creation so messages from vkCreateInstance itself are caught.
            create_info = create_info.push_next(&mut messenger_info);
        }
        if desc.sync_validation {
            create_info = create_info.push_next(&mut validation_features);
        }
        // SAFETY: every pointer in create_info outlives the call.
        let raw = unsafe { entry.create_instance(&create_info, None) }.call("vkCreateInstance")?;

        let debug_utils = if validation && has_debug_utils {
            let loader = ext::debug_utils::Instance::new(&entry, &raw);
            // SAFETY: valid instance; the log outlives the messenger (destroyed in Drop).
            let messenger = unsafe { loader.create_debug_utils_messenger(&messenger_info, None) }
                .call("vkCreateDebugUtilsMessengerEXT");
            match messenger {
                Ok(messenger) => Some((loader, messenger)),
                Err(e) => {
                    // SAFETY: nothing was made on the instance; no `Instance` owns it yet.
                    unsafe { raw.destroy_instance(None) };
                    return Err(e);
                }
            }
        } else {
            None
        };
        Ok(Arc::new(Self {
            entry,
            raw,
            debug_utils,
            log,
            validation,
        }))
    }

    /// Whether debug utils (labels, object names) are available.
    pub(crate) fn has_debug_utils(&self) -> bool {
        self.debug_utils.is_some()
    }

    /// Validation errors and warnings collected so far.
    pub fn validation_log(&self) -> &ValidationLog {
        &self.log
    }

    pub fn validation_enabled(&self) -> bool {
        self.validation
    }
}

/// The instance extensions to enable: debug utils where the loader offers it (whether it
/// does comes back too), and every one of `required`, which the loader must offer.
fn instance_extensions(
    entry: &ash::Entry,
    required: &[&CStr],
) -> Result<(Vec<*const std::ffi::c_char>, bool)> {
    // SAFETY: global query.
    let available = unsafe { entry.enumerate_instance_extension_properties(None) }
        .call("vkEnumerateInstanceExtensionProperties")?;
    let offered = |name: &CStr| {
        available
            .iter()
            .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name))
    };
    let has_debug_utils = offered(ext::debug_utils::NAME);
    let mut extensions = Vec::new();
    if has_debug_utils {
        extensions.push(ext::debug_utils::NAME.as_ptr());
    }
    for name in required {
        if !offered(name) {
            return Err(VkError::Usage(format!(
                "the Vulkan loader offers no {}: this system's Vulkan cannot present \
                 to its window system",
                name.to_string_lossy()
            )));
        }
        extensions.push(name.as_ptr());
    }
    Ok((extensions, has_debug_utils))
}

/// The validation messenger's settings: errors, warnings and infos of every type, to
/// `debug_callback` with `log` as its user data (`log` must outlive the messenger).
fn messenger_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::INFO,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(log as *const ValidationLog as *mut std::ffi::c_void)
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: the instance is no longer used; child objects were destroyed by their
        // owners (each holds an Arc<Instance>).
        unsafe {
            if let Some((loader, messenger)) = self.debug_utils.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}
