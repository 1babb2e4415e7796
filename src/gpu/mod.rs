//! Vulkan compute core.
