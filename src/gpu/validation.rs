//! VK_LAYER_KHRONOS_validation messages, collected so that a test (or `vkvcm` run with
//! `VKVCM_VALIDATION=1`) can fail on any of them.

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result};
use ash::vk;

/// A shared list of validation messages. Clone it before dropping the `Gpu` to also see
/// what the layer reports at device destruction (leaked objects).
#[derive(Clone, Debug, Default)]
pub struct Messages(Arc<Mutex<Vec<String>>>);

impl Messages {
    pub fn list(&self) -> Vec<String> {
        self.0.lock().map(|v| v.clone()).unwrap_or_default()
    }

    fn push(&self, m: String) {
        if let Ok(mut v) = self.0.lock() {
            v.push(m);
        }
    }
}

pub(crate) struct Validation {
    loader: ash::ext::debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
    messages: Box<Messages>,
}

unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the boxed `Messages` owned by `Validation`, alive while the
    // messenger exists; `data` is valid for the duration of the call.
    unsafe {
        let msgs = &*(user as *const Messages);
        let text = if data.is_null() || (*data).p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
        };
        msgs.push(format!("[{severity:?}] {text}"));
    }
    vk::FALSE
}

impl Validation {
    pub(crate) fn new(entry: &ash::Entry, instance: &ash::Instance) -> Result<Self> {
        let loader = ash::ext::debug_utils::Instance::new(entry, instance);
        let messages = Box::new(Messages::default());
        let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(callback))
            .user_data(&*messages as *const Messages as *mut c_void);
        // SAFETY: the user data box outlives the messenger (destroyed in Drop first).
        let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
            .context("cannot create the validation messenger")?;
        Ok(Validation { loader, messenger, messages })
    }

    pub(crate) fn messages(&self) -> Messages {
        (*self.messages).clone()
    }
}

impl Drop for Validation {
    fn drop(&mut self) {
        // SAFETY: created in `new`, destroyed once.
        unsafe { self.loader.destroy_debug_utils_messenger(self.messenger, None) };
    }
}
