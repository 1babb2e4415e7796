//! `vkvcm denoise IN.exr -o OUT.exr`: Intel Open Image Denoise's ray-tracing filter on a
//! render, guided by its albedo and normal AOVs where the EXR has them (`render --aov
//! albedo,normal`). It runs OIDN's own command-line program, `oidnDenoise`, on PFM files
//! in a temporary folder: the OIDN library is not on Debian 12 and the `oidn` crate needs
//! it installed; the `pyoidn` wheel on PyPI ships the library with `oidnDenoise`, which
//! scripts/setup-oidn.sh installs (docs/denoising.md).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};
use clap::Args;

use super::exit::{Class, ClassifyExt};
use vkvcm::image::{self, ExrCompression, Image};
use vkvcm::render::aov::{ALBEDO_CHANNELS, NORMAL_CHANNELS};

/// Where scripts/setup-oidn.sh puts OIDN's program.
pub const SETUP_OIDN_DENOISE: &str = "/opt/vkvcm/pyoidn/pyoidn/oidn/bin/oidnDenoise";

#[derive(Args, Clone, Debug)]
pub struct DenoiseArgs {
    /// A render's EXR (R, G, B; with albedo.R/G/B and N.X/Y/Z when rendered with --aov).
    pub input: PathBuf,
    /// The denoised EXR (R, G, B, the input's AOV layers and its attributes but not the
    /// resume data). Default: IN_denoised.exr.
    #[arg(long, short = 'o', value_parser = super::parse_exr_path)]
    pub output: Option<PathBuf>,
    /// Denoise the colour alone even where the EXR has albedo and normal layers.
    #[arg(long)]
    pub no_aux: bool,
    /// OIDN's `oidnDenoise` program. Default: $VKVCM_OIDN_DENOISE, else `oidnDenoise` on
    /// the PATH, else where scripts/setup-oidn.sh installs it.
    #[arg(long, value_name = "PATH")]
    pub oidn: Option<PathBuf>,
}

/// The `oidnDenoise` program to run: `given`, $VKVCM_OIDN_DENOISE, the PATH's, or the
/// set-up's; `None` when there is none.
pub fn find_oidn_denoise(given: Option<&Path>) -> Option<PathBuf> {
    if let Some(p) = given {
        return Some(p.to_path_buf());
    }
    if let Some(p) = std::env::var_os("VKVCM_OIDN_DENOISE") {
        return Some(PathBuf::from(p));
    }
    let on_path = std::env::var_os("PATH")
        .and_then(|paths| std::env::split_paths(&paths).map(|d| d.join("oidnDenoise")).find(|p| p.is_file()));
    on_path.or_else(|| Some(PathBuf::from(SETUP_OIDN_DENOISE)).filter(|p| p.is_file()))
}

pub fn denoise_cmd(a: DenoiseArgs) -> Result<()> {
    let program = find_oidn_denoise(a.oidn.as_deref())
        .context(
            "Intel Open Image Denoise's oidnDenoise was not found (--oidn, $VKVCM_OIDN_DENOISE, PATH): \
             scripts/setup-oidn.sh installs it",
        )
        .class(Class::Usage)?;
    if !program.is_file() {
        return Err(anyhow::anyhow!(
            "{} does not exist (scripts/setup-oidn.sh installs OIDN's oidnDenoise)",
            program.display()
        ))
        .class(Class::Usage);
    }
    let (img, extra, meta) = image::read_exr_channels(&a.input).class(Class::Usage)?;
    let layer = |names: [&str; 3]| -> Option<Vec<[f32; 3]>> {
        let c: Vec<Vec<f32>> =
            names.iter().map(|n| extra.iter().find(|e| e.0 == *n).map(|e| e.1.to_f32())).collect::<Option<_>>()?;
        Some((0..img.data.len()).map(|i| [c[0][i], c[1][i], c[2][i]]).collect())
    };
    let (albedo, normal) = if a.no_aux { (None, None) } else { (layer(ALBEDO_CHANNELS), layer(NORMAL_CHANNELS)) };
    let dir = tempfile::tempdir().context("a temporary folder for OIDN's files")?;
    let pfm = |name: &str, data: &[[f32; 3]]| -> Result<PathBuf> {
        let p = dir.path().join(name);
        write_pfm(&p, img.width, img.height, data)?;
        Ok(p)
    };
    let mut cmd = Command::new(&program);
    cmd.arg("--hdr").arg(pfm("color.pfm", &img.data)?);
    // OIDN takes a normal layer only beside an albedo layer.
    let guides = match (&albedo, &normal) {
        (Some(al), Some(n)) => {
            cmd.arg("--alb").arg(pfm("albedo.pfm", al)?).arg("--nrm").arg(pfm("normal.pfm", n)?);
            "albedo, normal"
        }
        (Some(al), None) => {
            cmd.arg("--alb").arg(pfm("albedo.pfm", al)?);
            "albedo"
        }
        _ => "none",
    };
    let out_pfm = dir.path().join("output.pfm");
    cmd.arg("-o").arg(&out_pfm).arg("-v").arg("1");
    let run = cmd.output().with_context(|| format!("running {}", program.display()))?;
    if !run.status.success() {
        bail!("{} failed ({}): {}", program.display(), run.status, String::from_utf8_lossy(&run.stderr).trim());
    }
    let denoised = read_pfm(&out_pfm, img.width, img.height).context("reading OIDN's output")?;
    let output = a.output.clone().unwrap_or_else(|| default_output(&a.input));
    // The resume data (moment2, vkvcm:format) would describe the noisy image: left out.
    let kept: Vec<image::ExtraChannel> = extra.into_iter().filter(|e| !e.0.starts_with("moment2.")).collect();
    let mut meta: Vec<(String, String)> = meta.into_iter().filter(|(k, _)| k != "vkvcm:format").collect();
    meta.push(("vkvcm:denoised".into(), format!("Intel Open Image Denoise (RT filter, hdr), guides: {guides}")));
    let out = Image { width: img.width, height: img.height, data: denoised };
    image::write_exr_channels(&output, &out, &kept, &meta, ExrCompression::Zip)?;
    println!("{}: denoised by OIDN (guides: {guides}) -> {}", a.input.display(), output.display());
    Ok(())
}

fn default_output(input: &Path) -> PathBuf {
    let stem = input.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    input.with_file_name(format!("{stem}_denoised.exr"))
}

// PFM (Portable Float Map), the format oidnDenoise reads and writes: a text header
// "PF\n<w> <h>\n<scale>\n" (a negative scale: little-endian), then RGB float32 rows from
// the bottom up. Written here in a few lines: no well-kept crate reads and writes it.

fn write_pfm(path: &Path, w: u32, h: u32, data: &[[f32; 3]]) -> Result<()> {
    let mut bytes = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for row in data.chunks_exact(w as usize).rev() {
        for v in row.iter().flatten() {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    let mut f = std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
    f.write_all(&bytes)?;
    Ok(())
}

fn read_pfm(path: &Path, w: u32, h: u32) -> Result<Vec<[f32; 3]>> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    // Three text lines, each ended by a newline (as oidnDenoise writes them).
    let mut lines = Vec::new();
    let mut start = 0;
    while lines.len() < 3 {
        let Some(end) = bytes[start..].iter().position(|b| *b == b'\n') else { break };
        lines.push(String::from_utf8_lossy(&bytes[start..start + end]).trim().to_string());
        start += end + 1;
    }
    let expected = format!("{w} {h}");
    if lines.len() != 3 || lines[0] != "PF" || lines[1] != expected {
        bail!("{} is not a {w}x{h} colour PFM (header {lines:?})", path.display());
    }
    let little = lines[2].trim().parse::<f32>().map(|s| s < 0.0).unwrap_or(true);
    let body = &bytes[start..];
    let n = (w * h) as usize;
    if body.len() < 12 * n {
        bail!("{} is short: {} bytes of pixels, expected {}", path.display(), body.len(), 12 * n);
    }
    let value = |i: usize| {
        let b = [body[4 * i], body[4 * i + 1], body[4 * i + 2], body[4 * i + 3]];
        if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut out = vec![[0.0; 3]; n];
    for y in 0..h as usize {
        for x in 0..w as usize {
            let src = (h as usize - 1 - y) * w as usize + x;
            out[y * w as usize + x] = [0, 1, 2].map(|c| value(3 * src + c));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.pfm");
        let data: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 0.5 * i as f32, -1.0]).collect();
        write_pfm(&p, 3, 2, &data).unwrap();
        assert_eq!(read_pfm(&p, 3, 2).unwrap(), data);
        assert!(read_pfm(&p, 2, 3).is_err());
    }
}
