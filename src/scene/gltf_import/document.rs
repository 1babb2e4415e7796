//! Parsing and validation of the glTF JSON, done before the `gltf` crate builds its
//! [`gltf::Document`] (which is then created without its own validation).

use super::extensions::check_extensions;
use super::sources::{read_container, MorphAttribute};
use super::warnings::Warnings;
use anyhow::{bail, Result};
use gltf::json;

/// A parsed and validated document.
pub(super) struct Parsed {
    pub root: json::Root,
    /// The GLB binary chunk, if any.
    pub blob: Option<Vec<u8>>,
    /// The file uses `KHR_mesh_quantization` (integer vertex attributes are allowed).
    pub quantized: bool,
    /// The morph-target displacements of texture coordinates and vertex colours that the
    /// importer applies (TEXCOORD_0, TEXCOORD_1, COLOR_0), each with a valid accessor.
    pub morph_attributes: Vec<MorphAttribute>,
}

/// The morph-target attributes beyond POSITION, NORMAL and TANGENT that are applied.
pub(super) fn is_applied_morph_attribute(name: &str) -> bool {
    matches!(name, "TEXCOORD_0" | "TEXCOORD_1" | "COLOR_0")
}

/// The validated JSON of `bytes` (`.gltf` or `.glb`) and the GLB binary chunk, if any.
pub(super) fn parse_document(bytes: &[u8], warnings: &mut Warnings) -> Result<Parsed> {
    let (mut root, blob, mut morph_attributes) = read_container(bytes)?;
    check_version(&root)?;
    for a in &morph_attributes {
        if !is_applied_morph_attribute(&a.name) {
            warnings.warn(
                "morph-target displacements of TEXCOORD_n (n > 1), COLOR_n (n > 0) and custom attributes are not applied",
                a.path(),
            );
        }
    }
    morph_attributes.retain(|a| is_applied_morph_attribute(&a.name));
    for a in &morph_attributes {
        match a.accessor {
            None => bail!("invalid glTF: {} must be an accessor index", a.path()),
            Some(i) if i >= root.accessors.len() => bail!(
                "invalid glTF: {} refers to accessor {i}, but there are {} accessors",
                a.path(),
                root.accessors.len()
            ),
            Some(_) => {}
        }
    }
    let quantized = check_extensions(&mut root, warnings)?;
    check_attribute_indices(&root)?;
    validate(&root, warnings)?;
    Ok(Parsed { root, blob, quantized, morph_attributes })
}

/// Refuses a file that is not glTF 2.x: glTF 1.0 is another format (materials as
/// techniques and shaders, other accessors), which parses as JSON but means something
/// else.
fn check_version(root: &json::Root) -> Result<()> {
    let v = root.asset.version.trim();
    if v.split('.').next() != Some("2") {
        bail!("glTF version {v:?} (asset.version): vkvcm reads glTF 2.0 files only; convert the file to glTF 2.0");
    }
    Ok(())
}

/// Refuses mesh attributes that refer to a missing accessor. gltf-json's primitive check
/// indexes the POSITION accessor without a bounds check, so this must run before
/// [`validate`].
fn check_attribute_indices(root: &json::Root) -> Result<()> {
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            for (sem, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let sem = match sem {
                        json::validation::Checked::Valid(s) => s.to_string(),
                        json::validation::Checked::Invalid => "?".to_string(),
                    };
                    bail!(
                        "invalid glTF: meshes[{mi}].primitives[{pi}].attributes[\"{sem}\"] refers to accessor {}, but there are {} accessors",
                        index.value(),
                        root.accessors.len()
                    );
                }
            }
        }
    }
    Ok(())
}

/// gltf-json's validation; the first 8 errors are reported together. A POSITION accessor
/// without min/max is required by the spec but not needed here: tolerated with a warning.
fn validate(root: &json::Root, warnings: &mut Warnings) -> Result<()> {
    use json::validation::{Error as VError, Validate};
    let mut errors = Vec::new();
    let mut missing_bounds = None;
    // Textures whose image is given only by an image-format extension (KHR_texture_basisu
    // and the like) have no `source`; textures.rs ignores them with a warning.
    let extension_only: Vec<String> = (root.textures.iter().enumerate())
        .filter(|(_, t)| super::textures::image_format_extension(t.extensions.as_ref().map(|e| &e.others)).is_some())
        .map(|(i, _)| format!("textures[{i}].source"))
        .collect();
    root.validate(root, json::Path::new, &mut |path, error| {
        let path = path().to_string();
        if matches!(error, VError::Missing) && extension_only.contains(&path) {
            return;
        }
        if matches!(error, VError::Missing)
            && path.contains("[\"POSITION\"]")
            && (path.ends_with(".min") || path.ends_with(".max"))
        {
            missing_bounds.get_or_insert(path);
            return;
        }
        let hint = match error {
            VError::IndexOutOfBounds => " (refers to an object that does not exist)",
            _ => "",
        };
        errors.push(format!("{path}: {error}{hint}"));
    });
    if let Some(path) = missing_bounds {
        warnings.warn("POSITION accessor without the required min/max (tolerated)", path);
    }
    if !errors.is_empty() {
        let shown = errors.iter().take(8).cloned().collect::<Vec<_>>().join("; ");
        let more = if errors.len() > 8 { format!(" (and {} more)", errors.len() - 8) } else { String::new() };
        bail!("invalid glTF: {shown}{more}");
    }
    Ok(())
}
