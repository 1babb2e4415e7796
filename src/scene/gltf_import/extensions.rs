//! The glTF extensions the importer understands, the policy for the others, and readers
//! for the JSON payloads of vkvcm's own extensions.

use super::warnings::Warnings;
use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use gltf::json;
use serde_json::Value;

/// Extension names understood by the importer.
pub const EXT_SPHERES: &str = "VKVCM_spheres";
pub const EXT_MATERIALS_PHONG: &str = "VKVCM_materials_phong";
pub const EXT_BACKGROUND: &str = "VKVCM_background";
pub const EXT_ENVIRONMENT: &str = "VKVCM_environment";
/// Integer vertex attributes (positions, normals, morph-target displacements).
pub const KHR_MESH_QUANTIZATION: &str = "KHR_mesh_quantization";
/// Per-node instance transforms (src/scene/gltf_import/instancing.rs).
pub const EXT_MESH_GPU_INSTANCING: &str = "EXT_mesh_gpu_instancing";
/// A clear coat layer over a material (src/scene/gltf_import/materials.rs).
pub const KHR_MATERIALS_CLEARCOAT: &str = "KHR_materials_clearcoat";
/// A sheen layer over a material (src/scene/gltf_import/materials.rs).
pub const KHR_MATERIALS_SHEEN: &str = "KHR_materials_sheen";
/// A thin-film iridescence over a material (src/scene/gltf_import/materials.rs).
pub const KHR_MATERIALS_IRIDESCENCE: &str = "KHR_materials_iridescence";
/// An anisotropic GGX lobe (src/scene/gltf_import/materials.rs).
pub const KHR_MATERIALS_ANISOTROPY: &str = "KHR_materials_anisotropy";
/// Lambertian transmission through an opaque material (src/scene/gltf_import/materials.rs).
pub const KHR_MATERIALS_DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";
/// A per-channel IOR of transmissive glass (src/scene/gltf_import/materials.rs).
pub const KHR_MATERIALS_DISPERSION: &str = "KHR_materials_dispersion";
/// Offset, rotation and scale of texture coordinates (read on `baseColorTexture`).
pub const KHR_TEXTURE_TRANSFORM: &str = "KHR_texture_transform";

/// WebP texture images (`textures[i].extensions.EXT_texture_webp.source`).
pub const EXT_TEXTURE_WEBP: &str = "EXT_texture_webp";

/// All extensions the importer interprets; any other one in `extensionsUsed` or
/// `extensionsRequired` is reported as a warning.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_volume",
    KHR_MATERIALS_CLEARCOAT,
    KHR_MATERIALS_SHEEN,
    KHR_MATERIALS_IRIDESCENCE,
    KHR_MATERIALS_ANISOTROPY,
    KHR_MATERIALS_DIFFUSE_TRANSMISSION,
    KHR_MATERIALS_DISPERSION,
    KHR_MESH_QUANTIZATION,
    KHR_TEXTURE_TRANSFORM,
    EXT_MESH_GPU_INSTANCING,
    super::meshopt_views::EXT_MESHOPT_COMPRESSION,
    EXT_TEXTURE_WEBP,
    EXT_SPHERES,
    EXT_MATERIALS_PHONG,
    EXT_BACKGROUND,
    EXT_ENVIRONMENT,
];

/// Compression extensions that vkvcm does not decode, each with what it compresses and a
/// tool that writes the file without it (the message of a file that requires one).
/// Draco: no well-kept Rust decoder (docs/scene-format.md, "glTF extensions").
pub const REFUSED_COMPRESSION: &[(&str, &str)] = &[
    (
        "KHR_draco_mesh_compression",
        "Draco-compressed meshes are not decoded: decompress the file with `gltf-transform cp IN OUT` (glTF-Transform decodes Draco as it reads)",
    ),
    (
        "KHR_texture_basisu",
        "KTX2 / Basis Universal textures are not decoded: convert them to PNG or JPEG (e.g. with KTX-Software's `ktx extract`; glTF-Transform cannot decode KTX2)",
    ),
];

/// Applies the extension policy to `root`. glTF 2.0 (section 3.12): a loader that does not
/// support an extension listed in `extensionsRequired` must not load the asset, so those
/// are errors; unknown extensions that are only used become warnings (one per name).
/// Afterwards `extensionsRequired` keeps only the extensions the `gltf` crate knows, since
/// its validation refuses required extensions it does not know (vkvcm's own extensions are
/// read here, from the raw JSON). Returns whether the file uses `KHR_mesh_quantization`
/// (listed in `extensionsUsed` or `extensionsRequired`), which allows integer vertex
/// attributes.
pub(super) fn check_extensions(root: &mut json::Root, warnings: &mut Warnings) -> Result<bool> {
    let unsupported: Vec<&str> =
        root.extensions_required.iter().map(String::as_str).filter(|e| !SUPPORTED_EXTENSIONS.contains(e)).collect();
    // Compressed assets are common and have a one-command fix: name it.
    if let Some((ext, why)) = REFUSED_COMPRESSION.iter().find(|(e, _)| unsupported.contains(e)) {
        bail!("required extension {ext} is not supported: {why}");
    }
    if !unsupported.is_empty() {
        bail!(
            "unsupported required extension(s) {} (extensionsRequired; supported: {})",
            unsupported.join(", "),
            SUPPORTED_EXTENSIONS.join(", ")
        );
    }
    let mut seen = Vec::new();
    for ext in &root.extensions_used {
        if SUPPORTED_EXTENSIONS.contains(&ext.as_str()) || seen.contains(ext) {
            continue;
        }
        seen.push(ext.clone());
        warnings.warn(format!("extension {ext} is not supported and was ignored"), "");
    }
    let quantized = root.extensions_used.iter().chain(&root.extensions_required).any(|e| e == KHR_MESH_QUANTIZATION);
    root.extensions_required.retain(|e| json::extensions::ENABLED_EXTENSIONS.contains(&e.as_str()));
    Ok(quantized)
}

/// The 3-vector `v[field]` of an extension payload, `default` when absent; `ctx` is the
/// JSON path of `v` used in errors.
pub(super) fn ext_vec3(v: &Value, field: &str, default: Vec3, ctx: &str) -> Result<Vec3> {
    match v.get(field) {
        None => Ok(default),
        Some(Value::Array(a)) if a.len() == 3 => {
            let mut out = [0f32; 3];
            for (k, x) in a.iter().enumerate() {
                out[k] = x
                    .as_f64()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| anyhow!("{ctx}.{field}[{k}] must be a finite number"))?
                    as f32;
            }
            Ok(Vec3::from_array(out))
        }
        Some(_) => bail!("{ctx}.{field} must be an array of 3 numbers"),
    }
}

/// Material `m`'s extension `name` (None when absent) and the path of it used in errors,
/// `"{label}: {name}"`; an error when it is not a JSON object.
pub(super) fn material_extension<'a>(
    m: &'a gltf::Material,
    name: &str,
    label: &str,
) -> Result<Option<(&'a Value, String)>> {
    let Some(v) = m.extensions().and_then(|e| e.get(name)) else { return Ok(None) };
    let ctx = format!("{label}: {name}");
    if !v.is_object() {
        bail!("{ctx} must be an object");
    }
    Ok(Some((v, ctx)))
}

/// The finite number `v[field]` of an extension payload, `default` when absent; `ctx` is
/// the JSON path of `v` used in errors.
pub(super) fn ext_f32(v: &Value, field: &str, default: f32, ctx: &str) -> Result<f32> {
    match v.get(field) {
        None => Ok(default),
        Some(x) => {
            Ok(x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| anyhow!("{ctx}.{field} must be a finite number"))?
                as f32)
        }
    }
}

/// `v` if no component is negative, else an error naming `what`.
pub(super) fn non_negative(v: Vec3, what: &str) -> Result<Vec3> {
    if v.min_element() < 0.0 {
        bail!("{what} must not be negative, is {v}");
    }
    Ok(v)
}
