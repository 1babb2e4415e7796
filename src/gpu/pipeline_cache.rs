//! The driver's VkPipelineCache, kept in the kernel cache's folder (src/gpu/kernel_cache.rs)
//! from one process to the next, one file per device and driver. Every compute pipeline
//! is created through it ([`PipelineCache::handle`]); where the driver caches its compiled
//! pipelines, a later process creates them without compiling them again.
//!
//! The file is read when the `Gpu` is opened. Its data is handed to the driver only if the
//! entry is intact (its digest, src/gpu/kernel_cache.rs) and the pipeline-cache header the
//! driver wrote at its start names this device ([`header_matches`]); otherwise the cache
//! starts empty. It is written back after a renderer has created its kernels and when the
//! `Gpu` is dropped, merged with what another process wrote there since this one read it.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use ash::vk;

use super::kernel_cache::{digest, CacheDir, Key, KeyBuilder};

/// A pipeline-cache file larger than this is not loaded, so the cache starts empty and the
/// file is replaced by this process's pipelines: the file, which gathers every kernel
/// variant ever built on this device, stays bounded.
pub const MAX_PIPELINE_CACHE_BYTES: usize = 256 << 20;

/// Bytes of `VkPipelineCacheHeaderVersionOne`.
const HEADER_BYTES: usize = 16 + vk::UUID_SIZE;

/// The pipeline cache of one `Gpu`.
pub(crate) struct PipelineCache {
    handle: vk::PipelineCache,
    /// Where it is kept, and under which key; `None` without a kernel cache.
    file: Option<(CacheDir, Key, String)>,
    /// Pipelines created through it since it was last saved.
    created: AtomicUsize,
    /// The digest of the file's payload as this process last read or wrote it (to tell
    /// whether another process wrote it since, and then merge); serialises saving.
    on_disk: Mutex<Option<[u8; 32]>>,
    /// Bytes of data it was created from (0: it started empty).
    loaded_bytes: usize,
    /// The device's properties, which the data's header must match.
    props: vk::PhysicalDeviceProperties,
}

impl PipelineCache {
    /// Creates the pipeline cache of `device`, from its file in `dir` where that holds an
    /// intact cache of this device and driver. Never fails: without a usable file it
    /// starts empty, and if the driver cannot create even an empty one, pipelines are
    /// created without a cache (a null handle).
    pub(crate) fn open(device: &ash::Device, props: &vk::PhysicalDeviceProperties, dir: Option<CacheDir>) -> Self {
        let file = dir.map(|d| {
            let key = device_key(props);
            let name = format!("pipelines-{}.bin", key.hex());
            (d, key, name)
        });
        let usable = |data: &Vec<u8>| data.len() <= MAX_PIPELINE_CACHE_BYTES && header_matches(data, props);
        let data = file.as_ref().and_then(|(d, key, name)| d.read(name, key)).filter(usable);
        let loaded = data.and_then(|data| Some((create(device, &data)?, data)));
        let (handle, loaded_bytes, on_disk) = match loaded {
            Some((handle, data)) => (handle, data.len(), Some(digest(&data))),
            None => (create(device, &[]).unwrap_or(vk::PipelineCache::null()), 0, None),
        };
        PipelineCache {
            handle,
            file,
            props: *props,
            created: AtomicUsize::new(0),
            on_disk: Mutex::new(on_disk),
            loaded_bytes,
        }
    }

    /// The cache to create pipelines with (null: none).
    pub(crate) fn handle(&self) -> vk::PipelineCache {
        self.handle
    }

    /// Counts a pipeline created through [`PipelineCache::handle`], for the next save.
    pub(crate) fn note_created(&self) {
        self.created.fetch_add(1, Ordering::Relaxed);
    }

    /// Bytes of pipeline-cache data read from disk when it was created (0: none).
    pub(crate) fn loaded_bytes(&self) -> usize {
        self.loaded_bytes
    }

    /// Writes the cache to its file if pipelines were created since the last save: merged
    /// with the file's current content when another process changed it since this one
    /// read or wrote it. Failures cost at most one warning (src/gpu/kernel_cache.rs).
    pub(crate) fn save(&self, device: &ash::Device) {
        let Some((dir, key, name)) = &self.file else { return };
        if self.handle == vk::PipelineCache::null() {
            return;
        }
        let Ok(mut on_disk) = self.on_disk.lock() else { return };
        if self.created.swap(0, Ordering::Relaxed) == 0 {
            return;
        }
        let theirs =
            dir.read(name, key).filter(|d| d.len() <= MAX_PIPELINE_CACHE_BYTES && header_matches(d, &self.props));
        let changed_by_another = theirs.as_deref().map(digest).is_some_and(|d| Some(d) != *on_disk);
        let merged = match theirs {
            Some(t) if changed_by_another => merged_with(device, self.handle, &t),
            _ => None,
        };
        // SAFETY: a valid cache; reading its data needs no external synchronisation.
        let Some(data) = merged.or_else(|| unsafe { device.get_pipeline_cache_data(self.handle) }.ok()) else {
            return;
        };
        let data_digest = digest(&data);
        if *on_disk == Some(data_digest) || data.len() > MAX_PIPELINE_CACHE_BYTES {
            return;
        }
        if dir.write(name, key, &data) {
            *on_disk = Some(data_digest);
        }
    }

    /// Saves the cache ([`PipelineCache::save`]) and destroys it.
    ///
    /// # Safety
    /// No pipeline creation may be in flight or follow.
    pub(crate) unsafe fn destroy(&self, device: &ash::Device) {
        self.save(device);
        // SAFETY: the caller guarantees no use; destroying a null handle is a no-op.
        unsafe { device.destroy_pipeline_cache(self.handle, None) };
    }
}

/// The key of a device's pipeline-cache file: what the driver's data depends on.
fn device_key(props: &vk::PhysicalDeviceProperties) -> Key {
    let mut k = KeyBuilder::new("pipelines");
    k.field("vendorID", props.vendor_id.to_le_bytes())
        .field("deviceID", props.device_id.to_le_bytes())
        .field("driverVersion", props.driver_version.to_le_bytes())
        .field("pipelineCacheUUID", props.pipeline_cache_uuid);
    k.finish()
}

/// Whether `data` starts with the `VkPipelineCacheHeaderVersionOne` of this device: header
/// size, header version one, vendorID, deviceID and pipelineCacheUUID, least significant
/// byte first as the specification stores them.
pub(crate) fn header_matches(data: &[u8], props: &vk::PhysicalDeviceProperties) -> bool {
    if data.len() < HEADER_BYTES {
        return false;
    }
    let word = |i: usize| u32::from_le_bytes([data[4 * i], data[4 * i + 1], data[4 * i + 2], data[4 * i + 3]]);
    let header_size = word(0) as usize;
    (HEADER_BYTES..=data.len()).contains(&header_size)
        && word(1) == vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32
        && word(2) == props.vendor_id
        && word(3) == props.device_id
        && data[16..HEADER_BYTES] == props.pipeline_cache_uuid
}

/// A pipeline cache created from `data` (empty: an empty cache); `None` if the driver
/// refuses it.
fn create(device: &ash::Device, data: &[u8]) -> Option<vk::PipelineCache> {
    let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
    // SAFETY: `data` is empty or checked by `header_matches` against this device.
    unsafe { device.create_pipeline_cache(&info, None) }.ok()
}

/// The data of a cache made of `theirs` (another process's file, intact, its header
/// checked by [`header_matches`]) merged with `ours`; `None` if the driver refuses it.
fn merged_with(device: &ash::Device, ours: vk::PipelineCache, theirs: &[u8]) -> Option<Vec<u8>> {
    let temp = create(device, theirs)?;
    // SAFETY: `temp` is this function's own (the externally synchronised destination);
    // `ours` is only read.
    let data = unsafe {
        let data = device.merge_pipeline_caches(temp, &[ours]).and_then(|()| device.get_pipeline_cache_data(temp));
        device.destroy_pipeline_cache(temp, None);
        data
    };
    data.ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn props() -> vk::PhysicalDeviceProperties {
        vk::PhysicalDeviceProperties {
            vendor_id: 0x10005,
            device_id: 7,
            pipeline_cache_uuid: *b"0123456789abcdef",
            ..Default::default()
        }
    }

    fn header(size: u32, version: u32, vendor: u32, device: u32, uuid: &[u8; 16]) -> Vec<u8> {
        let mut h = Vec::new();
        for w in [size, version, vendor, device] {
            h.extend_from_slice(&w.to_le_bytes());
        }
        h.extend_from_slice(uuid);
        h
    }

    #[test]
    fn the_header_must_name_this_device() {
        let p = props();
        let uuid = p.pipeline_cache_uuid;
        let good = header(32, 1, 0x10005, 7, &uuid);
        assert!(header_matches(&good, &p));
        let mut longer = good.clone();
        longer.extend_from_slice(&[0; 64]);
        assert!(header_matches(&longer, &p), "data after the header");
        assert!(!header_matches(&good[..31], &p), "truncated header");
        assert!(!header_matches(&header(31, 1, 0x10005, 7, &uuid), &p), "header size below 32");
        assert!(!header_matches(&header(64, 1, 0x10005, 7, &uuid), &p), "header size past the data");
        assert!(!header_matches(&header(32, 2, 0x10005, 7, &uuid), &p), "another header version");
        assert!(!header_matches(&header(32, 1, 0x10006, 7, &uuid), &p), "another vendor");
        assert!(!header_matches(&header(32, 1, 0x10005, 8, &uuid), &p), "another device");
        assert!(!header_matches(&header(32, 1, 0x10005, 7, b"0123456789abcdeX"), &p), "another UUID");
        assert!(!header_matches(&[], &p));
    }

    #[test]
    fn the_file_key_follows_the_driver() {
        let p = props();
        let other_driver = vk::PhysicalDeviceProperties { driver_version: 1, ..p };
        let other_uuid = vk::PhysicalDeviceProperties { pipeline_cache_uuid: [0; 16], ..p };
        assert_eq!(device_key(&p), device_key(&props()));
        assert_ne!(device_key(&p), device_key(&other_driver));
        assert_ne!(device_key(&p), device_key(&other_uuid));
    }
}
