//! Textures: the textures of a material (glTF 2.0 section 3.8, "Texture Data":
//! textures, images, samplers), its `KHR_texture_transform`, and the image decoding (PNG
//! and JPEG, from files in the scene's folder, `data:` URIs or buffer views).

use super::accessors::view_slice;
use super::extensions::{ext_f32, EXT_TEXTURE_WEBP, KHR_TEXTURE_TRANSFORM};
use super::{sources, Importer};
use crate::scene::{Filter, TextureImage, TextureRef, Wrap};
use anyhow::{anyhow, bail, Context, Result};
use gltf::texture::{MagFilter, WrappingMode};
use serde_json::Value;

/// Images wider or taller than this are refused (the largest texture size common GPUs
/// support).
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Images of more texels than this (16384 x 16384: 1 GiB as RGBA8) are refused.
pub const MAX_IMAGE_TEXELS: u64 = 1 << 28;

/// Texture extensions that give a texture's image in a format other than PNG/JPEG
/// (`textures[i].extensions.<name>.source`); those of [`DECODED_IMAGE_FORMATS`] are
/// read. For the others, a texture that has such a source and a core `source` uses the
/// core one (the extensions' fallback rule); one with only the extension's source is
/// ignored (warning).
pub(super) const IMAGE_FORMAT_EXTENSIONS: &[&str] =
    &["KHR_texture_basisu", "EXT_texture_webp", "EXT_texture_avif", "MSFT_texture_dds"];

/// Image-format extensions that are decoded: a texture's image is their `source`.
pub(super) const DECODED_IMAGE_FORMATS: &[&str] = &[EXT_TEXTURE_WEBP];

/// The image index of a texture's decoded image-format extension ([`DECODED_IMAGE_FORMATS`])
/// in its JSON `extensions`, if it has one; `ctx` names the texture in errors.
fn extension_source(ext: Option<&serde_json::Map<String, Value>>, ctx: &str) -> Result<Option<usize>> {
    let Some((name, v)) = ext.and_then(|e| DECODED_IMAGE_FORMATS.iter().find_map(|n| Some((*n, e.get(*n)?)))) else {
        return Ok(None);
    };
    let source = v.get("source").and_then(Value::as_u64).and_then(|s| usize::try_from(s).ok());
    source.map(Some).ok_or_else(|| anyhow!("{ctx}: extensions.{name}.source must be an image index"))
}

/// The name of the first image-format extension (of [`IMAGE_FORMAT_EXTENSIONS`]) of a
/// texture, from its JSON `extensions`, if any.
pub(super) fn image_format_extension(ext: Option<&serde_json::Map<String, Value>>) -> Option<&'static str> {
    let ext = ext?;
    IMAGE_FORMAT_EXTENSIONS.iter().copied().find(|e| ext.contains_key(*e))
}

impl Importer<'_> {
    /// The [`TextureRef`] of a material's `baseColorTexture` `info`; `label` names the
    /// material. `None` (with a warning) when the texture cannot be used: its image is
    /// only given by an unsupported extension (KHR_texture_basisu, EXT_texture_webp, ...),
    /// or it uses texture coordinates other than TEXCOORD_0/1. Errors: a malformed
    /// `KHR_texture_transform`, an image that cannot be read or decoded or is too large.
    pub(super) fn base_color_texture(&mut self, info: &gltf::texture::Info, label: &str) -> Result<Option<TextureRef>> {
        let transform = info.extension_value(KHR_TEXTURE_TRANSFORM);
        self.texture_ref(info.texture(), info.tex_coord(), transform, label, "baseColorTexture")
    }

    /// The material's `pbrMetallicRoughness.metallicRoughnessTexture`, as
    /// `base_color_texture` reads a base-colour texture (its texels are linear: the
    /// kernels read it so, glsl/textures.glsl `surface_tint`).
    pub(super) fn metallic_roughness_texture(
        &mut self,
        info: &gltf::texture::Info,
        label: &str,
    ) -> Result<Option<TextureRef>> {
        let transform = info.extension_value(KHR_TEXTURE_TRANSFORM);
        self.texture_ref(info.texture(), info.tex_coord(), transform, label, "metallicRoughnessTexture")
    }

    /// A material's texture `info` in `slot` (an extension's, e.g.
    /// `KHR_materials_transmission.transmissionTexture`), as `base_color_texture` reads a
    /// base-colour texture.
    pub(super) fn info_texture(
        &mut self,
        info: &gltf::texture::Info,
        label: &str,
        slot: &str,
    ) -> Result<Option<TextureRef>> {
        let transform = info.extension_value(KHR_TEXTURE_TRANSFORM);
        self.texture_ref(info.texture(), info.tex_coord(), transform, label, slot)
    }

    /// The material's `emissiveTexture`, as `base_color_texture` reads a base-colour texture.
    pub(super) fn emissive_texture(&mut self, info: &gltf::texture::Info, label: &str) -> Result<Option<TextureRef>> {
        let transform = info.extension_value(KHR_TEXTURE_TRANSFORM);
        self.texture_ref(info.texture(), info.tex_coord(), transform, label, "emissiveTexture")
    }

    /// The material's `normalTexture` (with its `scale`, glTF 2.0 section 5.19.4), as
    /// `base_color_texture` reads a base-colour texture.
    pub(super) fn normal_texture(
        &mut self,
        info: &gltf::material::NormalTexture,
        label: &str,
    ) -> Result<Option<(TextureRef, f32)>> {
        let transform = info.extension_value(KHR_TEXTURE_TRANSFORM);
        let t = self.texture_ref(info.texture(), info.tex_coord(), transform, label, "normalTexture")?;
        Ok(t.map(|t| (t, info.scale())))
    }

    /// A texture named by an extension's raw textureInfo JSON `info` (`index`, `texCoord`,
    /// `extensions.KHR_texture_transform`) for the material `label`'s `slot`, read as
    /// `base_color_texture` reads a base-colour texture.
    pub(super) fn json_texture(&mut self, info: &Value, label: &str, slot: &str) -> Result<Option<TextureRef>> {
        let index = info.get("index").and_then(Value::as_u64);
        let texture = index.and_then(|i| self.doc.textures().nth(i as usize));
        let Some(texture) = texture else {
            anyhow::bail!("{label}: {slot}.index must name one of the file's textures, is {:?}", info.get("index"));
        };
        let tex_coord = match info.get("texCoord") {
            None => 0,
            Some(k) => k
                .as_u64()
                .and_then(|k| u32::try_from(k).ok())
                .ok_or_else(|| anyhow::anyhow!("{label}: {slot}.texCoord must be a non-negative integer, is {k}"))?,
        };
        let transform = info.get("extensions").and_then(|e| e.get(KHR_TEXTURE_TRANSFORM));
        self.texture_ref(texture, tex_coord, transform, label, slot)
    }

    /// The texture reference of `texture` read through texture coordinate set `tex_coord`
    /// with an optional KHR_texture_transform payload, for the material `label`'s `slot`
    /// (`baseColorTexture`, `normalTexture`, ...); `None` (with a warning) when it cannot
    /// apply.
    fn texture_ref(
        &mut self,
        texture: gltf::Texture,
        tex_coord: u32,
        transform: Option<&Value>,
        label: &str,
        slot: &str,
    ) -> Result<Option<TextureRef>> {
        let ti = texture.index();
        let ctx = format!("{label} {slot} (texture {ti})");
        let json = &self.doc.as_json().textures[ti];
        // A supported image-format extension's source comes first (the core `source` is
        // its fallback for viewers without it).
        let decoded = extension_source(json.extensions.as_ref().map(|e| &e.others), &ctx)?;
        // Without `allow_empty_texture`, gltf's `Texture::source` unwraps the image index;
        // an extension-only texture has none (document.rs lets it through validation).
        if decoded.is_none() && json.source.value() == u32::MAX as usize {
            let ext = image_format_extension(json.extensions.as_ref().map(|e| &e.others)).unwrap_or("an extension");
            self.warnings.warn(
                format!("texture images given only by {ext} are not supported (the texture is ignored; the constant factor is used)"),
                ctx,
            );
            return Ok(None);
        }

        let (transform, tex_coord_override) = match transform {
            Some(v) => texture_transform(v, &format!("{ctx} extensions.{KHR_TEXTURE_TRANSFORM}"))?,
            None => (TextureRef::IDENTITY, None),
        };
        // KHR_texture_transform: "texCoord: Overrides the textureInfo texCoord value if
        // supplied".
        let tex_coord = tex_coord_override.unwrap_or(tex_coord);
        if tex_coord > 1 {
            self.warnings.warn(
                format!("{slot} on TEXCOORD_{tex_coord}: only TEXCOORD_0 and TEXCOORD_1 are read (the texture is ignored; the constant factor is used)"),
                ctx,
            );
            return Ok(None);
        }

        // glTF 2.0 section 5.26 (sampler): wrapS/wrapT default to REPEAT; a texture
        // without a sampler uses "repeat wrapping and auto filtering".
        let sampler = texture.sampler();
        let wrap = |w: WrappingMode| match w {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        // No mip-maps: the pixel samples of a path tracer average the texture over each
        // pixel's footprint, so the mip-map minification filters become bilinear, and only
        // a NEAREST magnification filter asks for nearest-texel lookups.
        let filter = match sampler.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        };

        let image = decoded.unwrap_or_else(|| texture.source().index());
        let image = self.doc.images().nth(image).ok_or_else(|| anyhow!("{ctx}: image {image} does not exist"))?;
        let image = self.texture_image(&image).with_context(|| ctx.clone())?;
        Ok(Some(TextureRef {
            image,
            wrap_s: wrap(sampler.wrap_s()),
            wrap_t: wrap(sampler.wrap_t()),
            filter,
            tex_coord,
            transform,
        }))
    }

    /// Index in `scene.images` of glTF image `image`, decoded on first use (several
    /// textures may share one image).
    fn texture_image(&mut self, image: &gltf::Image) -> Result<u32> {
        let ii = image.index();
        if let Some(i) = self.image_cache[ii] {
            return Ok(i);
        }
        let json = &self.doc.as_json().images[ii];
        let name = match (&json.name, &json.uri) {
            (Some(n), _) => n.clone(),
            (None, Some(uri)) if !uri.starts_with("data:") => uri.clone(),
            _ => format!("image{ii}"),
        };
        let label = match &json.name {
            Some(n) => format!("image {ii} '{n}'"),
            None => format!("image {ii}"),
        };
        let mime = json.mime_type.as_ref().map(|m| m.0.as_str());
        let bytes: Vec<u8> = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                let view = self.doc.views().nth(view.value()).ok_or_else(|| anyhow!("{label}: no buffer view"))?;
                view_slice(&self.buffers, &view).with_context(|| label.clone())?.to_vec()
            }
            (None, Some(uri)) => sources::load_uri(uri, self.base_dir, "image").with_context(|| label.clone())?,
            (None, None) => bail!("{label} has neither a uri nor a bufferView"),
        };
        let (width, height, texels) = decode_image(&bytes, mime).with_context(|| label.clone())?;
        let i = self.scene.images.len() as u32;
        self.scene.images.push(TextureImage { name, width, height, texels });
        self.image_cache[ii] = Some(i);
        Ok(i)
    }
}

/// The matrix of a `KHR_texture_transform` payload `v` and its `texCoord` override; `ctx`
/// names it in errors.
///
/// The extension's specification (section "Overview") defines
/// `matrix = translation * rotation * scale` and `uv' = (matrix * vec3(uv, 1)).xy` with
/// translation = [1 0 offset.x; 0 1 offset.y; 0 0 1] and scale = diag(scale.x, scale.y, 1).
/// For the rotation it gives the GLSL `mat3(cos r, sin r, 0, -sin r, cos r, 0, 0, 0, 1)`,
/// but its prose ("Rotate the UVs by this many radians counter-clockwise around the
/// origin", in UV space, whose v axis points down the image), its example ("offset [0, 1],
/// rotation pi/2, scale [0.5, 0.5]" uses "only the lower left quadrant of the source
/// image") and the Khronos glTF-Sample-Viewer (`source/gltf/material.js`) all use the
/// rotation whose rows are [cos r, sin r; -sin r, cos r], which is what this reads (the
/// GLSL's nine numbers read row by row). So, row by row:
///
///   u' = cos(r) sx u + sin(r) sy v + ox
///   v' = -sin(r) sx u + cos(r) sy v + oy
pub(super) fn texture_transform(v: &Value, ctx: &str) -> Result<([[f32; 3]; 2], Option<u32>)> {
    if !v.is_object() {
        bail!("{ctx} must be an object");
    }
    let pair = |field: &str, default: [f32; 2]| -> Result<[f32; 2]> {
        match v.get(field) {
            None => Ok(default),
            Some(Value::Array(a)) if a.len() == 2 => {
                let mut out = [0f32; 2];
                for (k, x) in a.iter().enumerate() {
                    out[k] = x
                        .as_f64()
                        .map(|x| x as f32)
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| anyhow!("{ctx}.{field}[{k}] must be a finite number"))?;
                }
                Ok(out)
            }
            Some(_) => bail!("{ctx}.{field} must be an array of 2 numbers"),
        }
    };
    let [ox, oy] = pair("offset", [0.0, 0.0])?;
    let [sx, sy] = pair("scale", [1.0, 1.0])?;
    let r = ext_f32(v, "rotation", 0.0, ctx)?;
    let tex_coord = match v.get("texCoord") {
        None => None,
        Some(t) => Some(
            t.as_u64()
                .filter(|&t| t <= u32::MAX as u64)
                .ok_or_else(|| anyhow!("{ctx}.texCoord must be a non-negative integer"))? as u32,
        ),
    };
    let (s, c) = r.sin_cos();
    Ok(([[c * sx, s * sy, ox], [-s * sx, c * sy, oy]], tex_coord))
}

/// Decodes a PNG or JPEG image (the formats glTF 2.0 allows, section 3.8.2; WebP for
/// EXT_texture_webp) to RGBA8
/// texels, row by row from the top-left corner; `mime` is the image's `mimeType`. The
/// format is recognised from the data's signature, else from `mime`. Images larger than
/// [`MAX_IMAGE_SIDE`] on a side or [`MAX_IMAGE_TEXELS`] in all are refused before their
/// texels are decoded.
pub(super) fn decode_image(bytes: &[u8], mime: Option<&str>) -> Result<(u32, u32, Vec<[u8; 4]>)> {
    use image::{ImageFormat, ImageReader, Limits};
    use std::io::Cursor;
    let format = image::guess_format(bytes).ok().or_else(|| mime.and_then(ImageFormat::from_mime_type));
    let format = match format {
        Some(f @ (ImageFormat::Png | ImageFormat::Jpeg | ImageFormat::WebP)) => f,
        Some(f) => bail!(
            "{} images are not supported as textures (glTF images are PNG or JPEG; WebP with EXT_texture_webp)",
            f.extensions_str().first().copied().unwrap_or("?").to_uppercase()
        ),
        None => bail!(
            "the data is not a PNG or JPEG image, nor WebP ({} bytes{})",
            bytes.len(),
            mime.map(|m| format!(", mimeType {m}")).unwrap_or_default()
        ),
    };
    let kind = match format {
        ImageFormat::Png => "PNG",
        ImageFormat::Jpeg => "JPEG",
        _ => "WebP",
    };
    let (w, h) = ImageReader::with_format(Cursor::new(bytes), format)
        .into_dimensions()
        .map_err(|e| anyhow!("cannot decode the {kind} image: {e}"))?;
    if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE || (w as u64) * (h as u64) > MAX_IMAGE_TEXELS {
        bail!(
            "the {kind} image is {w} x {h} texels (supported: 1 to {MAX_IMAGE_SIDE} on a side, at most {MAX_IMAGE_TEXELS} texels)"
        );
    }
    let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    // 16-bit RGBA is the widest decoded format (8 bytes per texel).
    limits.max_alloc = Some(8 * MAX_IMAGE_TEXELS);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| anyhow!("cannot decode the {kind} image: {e}"))?;
    let rgba = img.into_rgba8();
    let (w, h) = rgba.dimensions();
    let texels = rgba.into_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    Ok((w, h, texels))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn texture_transform_matrix() {
        let (m, t) = texture_transform(&json!({}), "x").unwrap();
        assert_eq!(m, TextureRef::IDENTITY);
        assert_eq!(t, None);
        // The specification's example: offset [0, 1], rotation pi/2, scale 0.5 maps the
        // unit square onto the lower left quadrant [0, 0.5] x [0.5, 1].
        let (m, _) = texture_transform(
            &json!({"offset": [0, 1], "rotation": std::f64::consts::FRAC_PI_2, "scale": [0.5, 0.5]}),
            "x",
        )
        .unwrap();
        let apply = |u: f32, v: f32| [m[0][0] * u + m[0][1] * v + m[0][2], m[1][0] * u + m[1][1] * v + m[1][2]];
        let close = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6;
        assert!(close(apply(0.0, 0.0), [0.0, 1.0]));
        assert!(close(apply(1.0, 0.0), [0.0, 0.5]));
        assert!(close(apply(0.0, 1.0), [0.5, 1.0]));
        assert!(close(apply(1.0, 1.0), [0.5, 0.5]));
        let (_, t) = texture_transform(&json!({"texCoord": 1}), "x").unwrap();
        assert_eq!(t, Some(1));
        for bad in
            [json!({"offset": [1]}), json!({"scale": "x"}), json!({"rotation": "x"}), json!({"texCoord": -1}), json!(3)]
        {
            assert!(texture_transform(&bad, "x").is_err(), "{bad}");
        }
    }

    #[test]
    fn image_limits_and_formats() {
        assert!(decode_image(b"not an image", None)
            .unwrap_err()
            .to_string()
            .contains("not a PNG or JPEG image, nor WebP"));
        let e = decode_image(b"#?RADIANCE\n", Some("image/png")).unwrap_err().to_string();
        assert!(e.contains("HDR images are not supported"), "{e}");
        // A PNG header declaring 20000 x 1 texels: refused before decoding.
        let img = image::RgbaImage::new(20000, 1);
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
        let e = decode_image(&png, None).unwrap_err().to_string();
        assert!(e.contains("20000 x 1 texels"), "{e}");
    }
}
