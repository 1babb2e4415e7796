//! VK_EXT_debug_utils names and labels, so that a capture in RenderDoc or Nsight shows
//! what each object is: every buffer is named by its plan name, every pipeline by its
//! kernel, and every dispatch is inside a label "pass: kernel". Where the loader or driver
//! lacks the extension, nothing is named. The counts let tests check that names were set.

use std::ffi::CString;
use std::sync::atomic::{AtomicU64, Ordering};

use ash::vk;

/// Whether the instance can enable VK_EXT_debug_utils (the loader implements it for every
/// driver that has it, lavapipe included).
pub fn available(entry: &ash::Entry) -> bool {
    // SAFETY: plain enumeration call.
    let exts = unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
    exts.iter().any(|e| e.extension_name_as_c_str().ok() == Some(ash::ext::debug_utils::NAME))
}

pub struct DebugNames {
    loader: Option<ash::ext::debug_utils::Device>,
    names: AtomicU64,
    labels: AtomicU64,
}

impl DebugNames {
    /// Names objects of `device` when the instance enabled the extension (`enabled`).
    pub fn new(instance: &ash::Instance, device: &ash::Device, enabled: bool) -> DebugNames {
        let loader = enabled.then(|| ash::ext::debug_utils::Device::new(instance, device));
        DebugNames { loader, names: AtomicU64::new(0), labels: AtomicU64::new(0) }
    }

    /// Names `handle` `name` (a name with a NUL in it is cut there).
    pub fn name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(l) = &self.loader else { return };
        let name = CString::new(name.split('\0').next().unwrap_or_default()).unwrap_or_default();
        let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
        // SAFETY: the handle is a live object of this device.
        if unsafe { l.set_debug_utils_object_name(&info) }.is_ok() {
            self.names.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Opens the label "`pass`: `kernel`" in `cmd`, closed by [`DebugNames::end_label`].
    pub fn begin_label(&self, cmd: vk::CommandBuffer, pass: &str, kernel: &str) {
        let Some(l) = &self.loader else { return };
        let label = format!("{pass}: {kernel}");
        let label = CString::new(label.split('\0').next().unwrap_or_default()).unwrap_or_default();
        // SAFETY: `cmd` is recording.
        unsafe { l.cmd_begin_debug_utils_label(cmd, &vk::DebugUtilsLabelEXT::default().label_name(&label)) };
        self.labels.fetch_add(1, Ordering::Relaxed);
    }

    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        let Some(l) = &self.loader else { return };
        // SAFETY: `cmd` is recording, inside a label begun by begin_label.
        unsafe { l.cmd_end_debug_utils_label(cmd) };
    }

    /// Objects named and labels opened so far; `None` without the extension.
    pub fn counts(&self) -> Option<(u64, u64)> {
        self.loader.as_ref().map(|_| (self.names.load(Ordering::Relaxed), self.labels.load(Ordering::Relaxed)))
    }
}
