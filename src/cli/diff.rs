//! `vkvcm diff a.exr b.exr`: error metrics of `a` against `b` (the reference), and an
//! optional false-colour error image.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;

use super::render::check_writable;
use vkvcm::image;
use vkvcm::render::converge::ReferenceError;

#[derive(Args)]
pub struct DiffArgs {
    /// The image to measure (EXR).
    pub a: PathBuf,
    /// The reference (EXR).
    pub b: PathBuf,
    /// Write a false-colour image of the per-pixel error luminance |a - b| (PNG).
    #[arg(long, visible_alias = "false-color")]
    pub false_colour: Option<PathBuf>,
    /// Error luminance shown at the top of the colour ramp (default: the 99th percentile
    /// of the image's error).
    #[arg(long)]
    pub scale: Option<f32>,
    /// Only check that the two files hold the same pixels bit for bit, in every channel
    /// (colour and the sums a render saves to resume), ignoring attributes such as the
    /// render time; exits with an error when any value differs.
    #[arg(long, conflicts_with_all = ["false_colour", "scale"])]
    pub exact: bool,
}

pub fn diff_cmd(a: DiffArgs) -> Result<()> {
    if let Some(s) = a.scale {
        if !(s > 0.0 && s.is_finite()) {
            bail!("--scale must be a positive number (got {s})");
        }
    }
    if a.exact {
        return exact_cmd(&a);
    }
    if let Some(p) = &a.false_colour {
        check_writable(p)?;
    }
    let (ia, _) = image::read_exr(&a.a)?;
    let (ib, meta_b) = image::read_exr(&a.b)?;
    if !ia.same_size(&ib) {
        bail!(
            "cannot compare {} ({}x{}) with {} ({}x{}): the sizes differ",
            a.a.display(),
            ia.width,
            ia.height,
            a.b.display(),
            ib.width,
            ib.height
        );
    }
    let m = image::compare(&ia, &ib).with_context(|| format!("comparing {} with {}", a.a.display(), a.b.display()))?;
    println!("{} against {} (the reference), {}x{}", a.a.display(), a.b.display(), ia.width, ia.height);
    println!("rmse          {:.6e}", m.rmse);
    println!("rel_mse       {:.6e}", m.rel_mse);
    println!("mean_abs_bias {:.6e}", m.mean_abs_bias);
    println!("max_abs       {:.6e}", m.max_abs);
    let own = ReferenceError::from_metadata(&meta_b);
    if let Some(e) = own.rmse {
        let rel = own.rel_mse.map(|v| format!(", rel_mse {v:.6e}")).unwrap_or_default();
        println!("the reference's own error estimate: rmse {e:.6e}{rel}");
    }
    let non_finite = ia.non_finite_count() + ib.non_finite_count();
    if non_finite > 0 {
        eprintln!("warning: {non_finite} pixel(s) are NaN or infinite (shown magenta in the false-colour image)");
    }
    if let Some(p) = &a.false_colour {
        let img = match a.scale {
            Some(s) => image::false_color_error_scaled(&ia, &ib, s),
            None => image::false_color_error(&ia, &ib),
        };
        image::write_png(p, &img, 1.0)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

/// `--exact`: every channel of `a` equal to `b`'s bit for bit.
fn exact_cmd(a: &DiffArgs) -> Result<()> {
    let (ia, ea, _) = image::read_exr_channels(&a.a)?;
    let (ib, eb, _) = image::read_exr_channels(&a.b)?;
    let (sa, sb) = (a.a.display(), a.b.display());
    if !ia.same_size(&ib) {
        bail!("{sa} is {}x{}, {sb} is {}x{}: not identical", ia.width, ia.height, ib.width, ib.height);
    }
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
    let mut channels: Vec<(String, Vec<u32>, Vec<u32>)> = ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(c, n)| {
            let plane = |img: &image::Image| bits(&img.data.iter().map(|p| p[c]).collect::<Vec<f32>>());
            (n.to_string(), plane(&ia), plane(&ib))
        })
        .collect();
    let names = |e: &[image::ExtraChannel]| {
        let mut v: Vec<String> = e.iter().map(|(n, _)| n.clone()).collect();
        v.sort();
        v
    };
    if names(&ea) != names(&eb) {
        bail!("{sa} has channels {:?}, {sb} has {:?}: not identical", names(&ea), names(&eb));
    }
    for (name, va) in ea {
        let vb = eb.iter().find(|(n, _)| *n == name).map(|(_, v)| v.bits()).unwrap_or_default();
        channels.push((name, va.bits(), vb));
    }
    let mut differing = Vec::new();
    for (name, va, vb) in &channels {
        let n = va.iter().zip(vb).filter(|(x, y)| x != y).count();
        if n > 0 {
            differing.push(format!("{name}: {n} of {} values", va.len()));
        }
    }
    if !differing.is_empty() {
        bail!("{sa} and {sb} differ: {}", differing.join(", "));
    }
    println!("{sa} and {sb}: bit-identical ({} channels of {}x{})", channels.len(), ia.width, ia.height);
    Ok(())
}
