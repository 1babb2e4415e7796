//! The exit status of `vkvcm`: one stable code per class of failure, so scripts can tell
//! a bad scene from a missing device or a frame too large (README.md, docs/usage.md).

use std::process::ExitCode;

/// A class of failure and its exit code. The codes are part of the command line's
/// interface: keep them stable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Any other failure: writing an output, a device lost mid-render, validation messages.
    Other = 1,
    /// Bad arguments (clap's own parse errors exit 2 too), an unreadable --reference.
    Usage = 2,
    /// The scene (or its --env map) cannot be read or is invalid.
    Scene = 3,
    /// No usable Vulkan device: none found, --device matches none, or it cannot be opened.
    Device = 4,
    /// The frame does not fit the device: a plan of buffers too large, or out of memory.
    Memory = 5,
    /// Interrupted by SIGINT or SIGTERM (what was rendered is written): 128 + SIGINT.
    Interrupted = 130,
}

/// An error tagged with its class; `main` finds it in the error's chain.
#[derive(Debug, thiserror::Error)]
#[error("{1:#}")]
pub struct Classified(pub Class, pub anyhow::Error);

/// Extension to tag a result's error with its class.
pub trait ClassifyExt<T> {
    fn class(self, class: Class) -> anyhow::Result<T>;
}

impl<T, E: Into<anyhow::Error>> ClassifyExt<T> for Result<T, E> {
    fn class(self, class: Class) -> anyhow::Result<T> {
        self.map_err(|e| {
            let e: anyhow::Error = e.into();
            // The innermost class wins: a render step that failed for lack of memory stays
            // a memory failure.
            if e.downcast_ref::<Classified>().is_some() {
                e
            } else {
                Classified(class, e).into()
            }
        })
    }
}

/// `r`, with an error that says the device ran out of memory (src/gpu/buffer.rs's and
/// vk_error_text's words) tagged as a memory failure: for the allocation of a render's
/// buffers, whose plan fitted the heap but not what is free of it.
pub fn memory_if_out_of_memory<T>(r: anyhow::Result<T>) -> anyhow::Result<T> {
    match r {
        Err(e) if ["out of device memory", "out of host memory"].iter().any(|w| format!("{e:#}").contains(w)) => {
            Err(e).class(Class::Memory)
        }
        r => r,
    }
}

/// The class of `e`: its tag, else out of memory where Vulkan said so, else `Other`.
pub fn class_of(e: &anyhow::Error) -> Class {
    if let Some(c) = e.downcast_ref::<Classified>() {
        return c.0;
    }
    for cause in e.chain() {
        if let Some(r) = cause.downcast_ref::<ash::vk::Result>() {
            if matches!(*r, ash::vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | ash::vk::Result::ERROR_OUT_OF_HOST_MEMORY) {
                return Class::Memory;
            }
        }
    }
    Class::Other
}

/// The process's exit code for `class`.
pub fn code(class: Class) -> ExitCode {
    ExitCode::from(class as u8)
}
