//! OpenEXR output and input.
//!
//! The writer is ours (not the `exr` crate's high-level writer) because the file must be a
//! pure function of the image and the metadata: the `exr` crate keeps custom attributes in
//! a `HashMap` whose iteration order changes from process to process, which would reorder
//! the header. Here the header is laid out by hand (required attributes in alphabetical
//! order, then the metadata sorted by key), pixels are scan-line blocks in increasing y,
//! and ZIP blocks are compressed with the `exr` crate's own (deterministic) ZIP encoder.
//! Reading uses the `exr` crate and accepts any file with R, G and B channels of any
//! sample type.

use super::atomic::write_atomic;
use super::Image;
use anyhow::{anyhow, bail, Result};
use std::path::Path;

/// Pixel compression of written EXR files. Both are lossless and deterministic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ExrCompression {
    /// No compression: largest files, fastest to write.
    None,
    /// ZIP (zlib) over blocks of 16 scan lines, OpenEXR's usual default. Blocks that would
    /// not get smaller are stored raw, as the format allows.
    #[default]
    Zip,
}

impl ExrCompression {
    fn code(self) -> u8 {
        match self {
            ExrCompression::None => 0, // NO_COMPRESSION
            ExrCompression::Zip => 3,  // ZIP_COMPRESSION (16 lines)
        }
    }

    fn lines_per_block(self) -> usize {
        match self {
            ExrCompression::None => 1,
            ExrCompression::Zip => 16,
        }
    }
}

/// Writes `img` as a linear float32 RGB EXR with ZIP compression (see [`write_exr_with`]).
pub fn write_exr(path: &Path, img: &Image, meta: &[(String, String)]) -> Result<()> {
    write_exr_with(path, img, meta, ExrCompression::Zip)
}

/// Writes `img` as a single-part scan-line EXR with float32 channels R, G, B and each
/// `(key, value)` of `meta` as a header attribute of type `string`.
///
/// - Keys are written sorted (the order of `meta` does not matter) and must be unique,
///   non-empty, at most 255 bytes, without NUL, and not a standard EXR attribute name
///   (`owner`, `comments`, `channels`, ...); namespace them, e.g. `vkvcm:seed`.
/// - The bytes depend only on the image, the metadata and the compression: no time stamps,
///   no random data. The same input always gives the same file.
/// - The write is atomic: a temporary file in the same directory is filled, synced and
///   renamed over `path`.
///
/// Errors (one line, naming `path`) when the directory does not exist or is not
/// writable, the image is empty, or the metadata is invalid.
pub fn write_exr_with(path: &Path, img: &Image, meta: &[(String, String)], compression: ExrCompression) -> Result<()> {
    write_exr_channels(path, img, &[], meta, compression)
}

/// The samples of a channel beside R, G and B (`data[y * width + x]`): float32, or
/// uint32 for values that must come back exactly (the film's fixed-point sums,
/// src/render/saved.rs).
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    F32(Vec<f32>),
    U32(Vec<u32>),
}

impl Samples {
    pub fn len(&self) -> usize {
        match self {
            Samples::F32(v) => v.len(),
            Samples::U32(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Each sample's 32 bits (a float's bit pattern): what bit-for-bit comparisons compare.
    pub fn bits(&self) -> Vec<u32> {
        match self {
            Samples::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
            Samples::U32(v) => v.clone(),
        }
    }

    /// The samples as float32 (a uint32 above 2^24 rounds).
    pub fn to_f32(&self) -> Vec<f32> {
        match self {
            Samples::F32(v) => v.clone(),
            Samples::U32(v) => v.iter().map(|&x| x as f32).collect(),
        }
    }

    /// The EXR pixel type code: UINT 0, FLOAT 2.
    fn pixel_type(&self) -> i32 {
        match self {
            Samples::F32(_) => 2,
            Samples::U32(_) => 0,
        }
    }

    fn push_le(&self, range: std::ops::Range<usize>, raw: &mut Vec<u8>) {
        match self {
            Samples::F32(v) => v[range].iter().for_each(|x| raw.extend_from_slice(&x.to_le_bytes())),
            Samples::U32(v) => v[range].iter().for_each(|x| raw.extend_from_slice(&x.to_le_bytes())),
        }
    }
}

/// A named channel beside R, G and B, for example `("moment2.R", Samples::F32(..))`.
pub type ExtraChannel = (String, Samples);

/// `(key, value)` string attributes, sorted by key.
pub type Metadata = Vec<(String, String)>;

/// [`write_exr_with`] with `extra` float32 or uint32 channels in the same part (channel names must
/// be unique, 1 to 255 bytes without NUL, not R, G or B, with one value per pixel).
/// Channels are stored in name order, as OpenEXR requires.
pub fn write_exr_channels(
    path: &Path,
    img: &Image,
    extra: &[ExtraChannel],
    meta: &[(String, String)],
    compression: ExrCompression,
) -> Result<()> {
    let bytes =
        encode_exr(img, extra, meta, compression).map_err(|e| anyhow!("cannot write EXR {}: {e:#}", path.display()))?;
    write_atomic(path, "EXR", |w| Ok(w.write_all(&bytes)?))
}

/// Reads the R, G and B channels (any of half, float or uint samples) of the first layer
/// that has all three, and every `string` attribute of the file that is not a standard EXR
/// attribute, sorted by key. Other attribute types are ignored.
///
/// Errors name the file: missing file, not an EXR, no layer with R, G and B.
pub fn read_exr(path: &Path) -> Result<(Image, Vec<(String, String)>)> {
    let (img, _, meta) = read_exr_channels(path)?;
    Ok((img, meta))
}

/// [`read_exr`] that also returns the layer's other channels (sorted by name): uint32
/// channels exactly as stored, the others as float32.
pub fn read_exr_channels(path: &Path) -> Result<(Image, Vec<ExtraChannel>, Metadata)> {
    let bytes = std::fs::read(path).map_err(|e| anyhow!("cannot read EXR {}: {e}", path.display()))?;
    decode_exr_channels(&bytes, &path.display().to_string())
}

/// [`read_exr_channels`] of an EXR file's bytes; `shown` names it in errors.
pub fn decode_exr_channels(bytes: &[u8], shown: &str) -> Result<(Image, Vec<ExtraChannel>, Metadata)> {
    use ::exr::prelude::{ReadChannels, ReadLayers};
    let image = ::exr::image::read::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| anyhow!("cannot read EXR {shown}: {e}"))?;

    let mut meta: Vec<(String, String)> = Vec::new();
    let mut collect =
        |other: &std::collections::HashMap<::exr::meta::attribute::Text, ::exr::meta::attribute::AttributeValue>| {
            for (name, value) in other {
                if let ::exr::meta::attribute::AttributeValue::Text(text) = value {
                    meta.push((
                        String::from_utf8_lossy(name.bytes()).into_owned(),
                        String::from_utf8_lossy(text.bytes()).into_owned(),
                    ));
                }
            }
        };
    collect(&image.attributes.other);
    for layer in &image.layer_data {
        collect(&layer.attributes.other);
    }
    meta.sort();
    meta.dedup_by(|a, b| a.0 == b.0);

    let mut found = Vec::new();
    for layer in &image.layer_data {
        let list = &layer.channel_data.list;
        let find = |name: &str| list.iter().find(|c| c.name.eq(name));
        let (Some(r), Some(g), Some(b)) = (find("R"), find("G"), find("B")) else {
            found.extend(list.iter().map(|c| c.name.to_string()));
            continue;
        };
        let (w, h) = (layer.size.0, layer.size.1);
        let n = w * h;
        let planes = [r, g, b].map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>());
        if planes.iter().any(|p| p.len() != n) {
            bail!("cannot read EXR {shown}: subsampled R, G or B channels are not supported");
        }
        let data = (0..n).map(|i| [planes[0][i], planes[1][i], planes[2][i]]).collect();
        let width = u32::try_from(w).map_err(|_| anyhow!("cannot read EXR {shown}: too wide"))?;
        let height = u32::try_from(h).map_err(|_| anyhow!("cannot read EXR {shown}: too tall"))?;
        let mut extra = Vec::new();
        for c in list.iter().filter(|c| !(c.name.eq("R") || c.name.eq("G") || c.name.eq("B"))) {
            let values = match &c.sample_data {
                ::exr::image::FlatSamples::U32(v) => Samples::U32(v.clone()),
                other => Samples::F32(other.values_as_f32().collect()),
            };
            if values.len() != n {
                bail!("cannot read EXR {shown}: channel {} is subsampled (not supported)", c.name);
            }
            extra.push((c.name.to_string(), values));
        }
        extra.sort_by(|a, b| a.0.cmp(&b.0));
        return Ok((Image { width, height, data }, extra, meta));
    }
    bail!("cannot read EXR {shown}: no layer has channels R, G and B (channels found: {})", found.join(", "))
}

/// Encodes `img` and `meta` into the bytes of an EXR file (what [`write_exr_with`] writes).
pub(crate) fn encode_exr(
    img: &Image,
    extra: &[ExtraChannel],
    meta: &[(String, String)],
    compression: ExrCompression,
) -> Result<Vec<u8>> {
    let (w, h) = (img.width as usize, img.height as usize);
    if w == 0 || h == 0 {
        bail!("image is empty ({}x{})", img.width, img.height);
    }
    if img.width > i32::MAX as u32 || img.height > i32::MAX as u32 {
        bail!("image is too large for EXR ({}x{})", img.width, img.height);
    }
    if img.data.len() != w * h {
        bail!("image data has {} pixels, expected {}x{}", img.data.len(), img.width, img.height);
    }
    let channels = sorted_channels(img, extra)?;
    let channel_names: Vec<(&str, i32)> = channels
        .iter()
        .map(|c| match c.1 {
            Channel::Rgb(_) => (c.0, 2),
            Channel::Extra(i) => (c.0, extra[i].1.pixel_type()),
        })
        .collect();
    let meta = sorted_metadata(meta)?;

    let mut out = Vec::with_capacity(4096);
    write_header(&mut out, img, &channel_names, &meta, compression);
    let lines = compression.lines_per_block();
    let chunks = h.div_ceil(lines);
    let table = out.len();
    out.resize(table + 8 * chunks, 0);
    let payloads = encode_chunks(img, extra, &channels, compression)?;
    for (chunk, payload) in payloads.iter().enumerate() {
        let offset = out.len() as u64;
        out[table + 8 * chunk..table + 8 * chunk + 8].copy_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&((chunk * lines) as i32).to_le_bytes());
        out.extend_from_slice(&(payload.len() as i32).to_le_bytes());
        out.extend_from_slice(payload);
    }
    Ok(out)
}

/// The channels to write in name order (OpenEXR requires it): R, G and B of `img`, then
/// the `extra` ones, each checked.
fn sorted_channels<'a>(img: &Image, extra: &'a [ExtraChannel]) -> Result<Vec<(&'a str, Channel)>> {
    let mut channels: Vec<(&str, Channel)> =
        vec![("B", Channel::Rgb(2)), ("G", Channel::Rgb(1)), ("R", Channel::Rgb(0))];
    for (i, (name, data)) in extra.iter().enumerate() {
        if name.is_empty() || name.len() > 255 || !name.bytes().all(|b| b.is_ascii_graphic()) {
            bail!("invalid channel name {name:?}: must be 1 to 255 printable ASCII characters");
        }
        if data.len() != img.data.len() {
            bail!("channel {name:?} has {} values, expected {}x{}", data.len(), img.width, img.height);
        }
        channels.push((name.as_str(), Channel::Extra(i)));
    }
    channels.sort_by(|a, b| a.0.cmp(b.0));
    if let Some(d) = channels.windows(2).find(|p| p[0].0 == p[1].0) {
        bail!("duplicate channel {:?}", d[0].0);
    }
    Ok(channels)
}

/// The metadata in key order, checked: valid keys, none standard or repeated.
fn sorted_metadata(meta: &[(String, String)]) -> Result<Vec<&(String, String)>> {
    let mut meta: Vec<&(String, String)> = meta.iter().collect();
    meta.sort();
    for (i, (key, value)) in meta.iter().map(|kv| (&kv.0, &kv.1)).enumerate() {
        if key.is_empty() || key.len() > 255 || key.contains('\0') {
            bail!("invalid metadata key {key:?}: must be 1 to 255 bytes without NUL");
        }
        if ::exr::meta::header::standard_names::ALL.contains(&key.as_bytes()) {
            bail!("invalid metadata key {key:?}: it is a standard EXR attribute; use a prefix such as \"vkvcm:\"");
        }
        if i > 0 && meta[i - 1].0 == *key {
            bail!("duplicate metadata key {key:?}");
        }
        if value.len() > i32::MAX as usize {
            bail!("metadata value of {key:?} is too long");
        }
    }
    Ok(meta)
}

/// Appends the magic number, the version and the header (the required attributes, then
/// `meta` as string attributes) to `out`.
fn write_header(
    out: &mut Vec<u8>,
    img: &Image,
    channel_names: &[(&str, i32)],
    meta: &[&(String, String)],
    compression: ExrCompression,
) {
    let long_names = meta.iter().any(|kv| kv.0.len() > 31) || channel_names.iter().any(|n| n.0.len() > 31);
    out.extend_from_slice(&20000630i32.to_le_bytes()); // magic number
    let version: u32 = 2 | if long_names { 0x400 } else { 0 };
    out.extend_from_slice(&version.to_le_bytes());

    let mut chlist = Vec::new();
    for (name, pixel_type) in channel_names {
        chlist.extend_from_slice(name.as_bytes());
        chlist.push(0);
        chlist.extend_from_slice(&pixel_type.to_le_bytes()); // UINT 0, FLOAT 2
        chlist.extend_from_slice(&[0, 0, 0, 0]); // pLinear, reserved
        chlist.extend_from_slice(&1i32.to_le_bytes()); // x sampling
        chlist.extend_from_slice(&1i32.to_le_bytes()); // y sampling
    }
    chlist.push(0);
    let mut window = Vec::new();
    for v in [0, 0, img.width as i32 - 1, img.height as i32 - 1] {
        window.extend_from_slice(&v.to_le_bytes());
    }
    let one = 1.0f32.to_le_bytes();
    let zero2 = [0u8; 8];

    attribute(out, "channels", "chlist", &chlist);
    attribute(out, "compression", "compression", &[compression.code()]);
    attribute(out, "dataWindow", "box2i", &window);
    attribute(out, "displayWindow", "box2i", &window);
    attribute(out, "lineOrder", "lineOrder", &[0]); // INCREASING_Y
    attribute(out, "pixelAspectRatio", "float", &one);
    attribute(out, "screenWindowCenter", "v2f", &zero2);
    attribute(out, "screenWindowWidth", "float", &one);
    for (key, value) in meta.iter().map(|kv| (&kv.0, &kv.1)) {
        attribute(out, key, "string", value.as_bytes());
    }
    out.push(0); // end of header
}

/// The payload of each chunk of scan lines, in order: the `channels` of `img` and `extra`
/// per line, compressed as `compression` says. Compressed in parallel (ZIP is the slow
/// part) and assembled in order, so the bytes do not depend on the thread count.
fn encode_chunks(
    img: &Image,
    extra: &[ExtraChannel],
    channels: &[(&str, Channel)],
    compression: ExrCompression,
) -> Result<Vec<Vec<u8>>> {
    let (w, h) = (img.width as usize, img.height as usize);
    let lines = compression.lines_per_block();
    let chunks = h.div_ceil(lines);
    let encode_chunk = |chunk: usize, header: Option<&::exr::meta::header::Header>| -> Result<Vec<u8>> {
        let y0 = chunk * lines;
        let n = lines.min(h - y0);
        let mut raw = Vec::with_capacity(w * 4 * channels.len() * n);
        for y in y0..y0 + n {
            let row = y * w..(y + 1) * w;
            for (_, c) in channels {
                match *c {
                    Channel::Rgb(c) => {
                        img.data[row.clone()].iter().for_each(|p| raw.extend_from_slice(&p[c].to_le_bytes()))
                    }
                    Channel::Extra(i) => extra[i].1.push_le(row.clone(), &mut raw),
                }
            }
        }
        match header {
            None => Ok(raw),
            Some(header) => {
                let bounds = ::exr::meta::attribute::IntegerBounds::new((0, y0 as i32), (w, n));
                ::exr::compression::Compression::ZIP16
                    .compress_image_section_to_le(header, raw, bounds)
                    .map_err(|e| anyhow!("ZIP compression failed: {e}"))
            }
        }
    };
    let zip_header = match compression {
        ExrCompression::Zip => Some(zip_header(
            w,
            h,
            &channels
                .iter()
                .map(|c| match c.1 {
                    Channel::Rgb(_) => (c.0, false),
                    Channel::Extra(i) => (c.0, matches!(extra[i].1, Samples::U32(_))),
                })
                .collect::<Vec<_>>(),
        )),
        ExrCompression::None => None,
    };
    let threads = match compression {
        ExrCompression::None => 1,
        ExrCompression::Zip => std::thread::available_parallelism().map_or(1, |n| n.get()).min(chunks).min(16),
    };
    if threads <= 1 {
        return (0..chunks).map(|c| encode_chunk(c, zip_header.as_ref())).collect();
    }
    let per = chunks.div_ceil(threads);
    let parts: Vec<Result<Vec<Vec<u8>>>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let (encode_chunk, header) = (&encode_chunk, zip_header.as_ref());
                scope.spawn(move || (t * per..((t + 1) * per).min(chunks)).map(|c| encode_chunk(c, header)).collect())
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("EXR compression thread panicked")).collect()
    });
    let mut all = Vec::with_capacity(chunks);
    for part in parts {
        all.extend(part?);
    }
    Ok(all)
}

/// Where a written channel's values come from.
#[derive(Clone, Copy)]
enum Channel {
    Rgb(usize),
    Extra(usize),
}

/// Appends one header attribute: name, NUL, type name, NUL, i32 size, value.
fn attribute(out: &mut Vec<u8>, name: &str, ty: &str, value: &[u8]) {
    out.extend_from_slice(name.as_bytes());
    out.push(0);
    out.extend_from_slice(ty.as_bytes());
    out.push(0);
    out.extend_from_slice(&(value.len() as i32).to_le_bytes());
    out.extend_from_slice(value);
}

/// The `exr` crate header its ZIP encoder needs: channel list and block size only.
/// `names`: each channel's name and whether it is uint32.
fn zip_header(w: usize, h: usize, names: &[(&str, bool)]) -> ::exr::meta::header::Header {
    use ::exr::meta::attribute::{ChannelDescription, LineOrder, SampleType, Text};
    let ty = |u: bool| if u { SampleType::U32 } else { SampleType::F32 };
    let channels = names.iter().map(|(n, u)| ChannelDescription::named(Text::new_or_panic(*n), ty(*u))).collect();
    ::exr::meta::header::Header::new(Text::new_or_panic("rgb"), (w, h), channels).with_encoding(
        ::exr::compression::Compression::ZIP16,
        ::exr::meta::BlockDescription::ScanLines,
        LineOrder::Increasing,
    )
}
