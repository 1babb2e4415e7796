//! Convergence measurements: error-vs-time curves of estimators against a reference
//! (`vkvcm converge`, `vkvcm-bench equal-time`); the reference and its own error estimate
//! from two halves are in src/render/reference.rs.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::{anyhow, bail, Result};
use serde::{Deserialize, Serialize};

use super::{Algorithm, Budget, Connect, RenderOutput, RenderSettings, Renderer, Sampler};
use crate::gpu::Gpu;
use crate::image::{compare, Image, Metrics};
use crate::scene::Scene;

/// The `K` checkpoint times of a render of `total` seconds, spaced by factors of two and
/// ending at `total`: `total * 2^-(K-1), ..., total / 2, total`.
pub fn checkpoint_times(total: f64, checkpoints: usize) -> Result<Vec<f64>> {
    if !(total > 0.0 && total.is_finite()) {
        bail!("the render time must be a positive number of seconds (got {total})");
    }
    if !(1..=40).contains(&checkpoints) {
        bail!("checkpoints must be between 1 and 40 (got {checkpoints})");
    }
    Ok((0..checkpoints).map(|i| total * 0.5f64.powi((checkpoints - 1 - i) as i32)).collect())
}

/// An estimator with its connection strategy, sampler and light subpaths per iteration,
/// named `algo` (its defaults), then `:path` / `:cache:N` (`render --connect`; bpt, vcm),
/// then `:independent` / `:sobol` (`render --sampler`), then `@N` for N light subpaths per
/// iteration (`render --light-paths`; the light-subpath estimators), e.g. `bpt:cache:2`,
/// `pt:independent`, `vcm:path:sobol` or `vcm@65536`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    pub algorithm: Algorithm,
    pub connect: Connect,
    pub sampler: Sampler,
    /// `None`: one per pixel.
    pub light_paths: Option<u32>,
}

impl Variant {
    pub fn parse(s: &str) -> Result<Variant> {
        let (name, light_paths) = match s.rsplit_once('@') {
            Some((name, n)) => {
                let n: u32 = n.parse().map_err(|_| anyhow!("{s:?}: {n:?} is not a light-path count"))?;
                (name, Some(n))
            }
            None => (s, None),
        };
        // algo[:connection strategy][:sampler]: a sampler is the last part.
        let (rest, sampler) = match name.rsplit_once(':') {
            Some((rest, c)) => match <Sampler as clap::ValueEnum>::from_str(c, false) {
                Ok(sampler) => (rest, Some(sampler)),
                Err(_) => (name, None),
            },
            None => (name, None),
        };
        let (a, c) = match rest.split_once(':') {
            Some((a, c)) => (a, Some(c)),
            None => (rest, None),
        };
        let algorithm =
            Algorithm::from_name(&a.to_ascii_lowercase()).ok_or_else(|| anyhow!("{s:?}: unknown estimator {a:?}"))?;
        let requested = match c {
            None => None,
            Some(c) => Some(
                Connect::parse(c)
                    .ok_or_else(|| anyhow!("{s:?}: {c:?} is not path or cache:N (N >= 1), nor sobol or independent"))?,
            ),
        };
        let connect = algorithm.info().connect(requested).map_err(|e| anyhow!("{s:?}: {e}"))?;
        let sampler = sampler.unwrap_or(algorithm.info().sampler(None));
        let v = Variant { algorithm, connect, sampler, light_paths };
        // The estimator's own check of the light-path count (a 1x1 frame: sizes do not matter).
        algorithm.info().check(&v.settings(1, 1, Budget::Iterations(1))).map_err(|e| anyhow!("{s:?}: {e}"))?;
        Ok(v)
    }

    /// `algo`, then `:path` / `:cache:N` for a strategy other than its default, then
    /// `:sobol` / `:independent` for a sampler other than its default, then `@N` with a
    /// light-path count.
    pub fn name(&self) -> String {
        let mut name = self.algorithm.name().to_string();
        if self.connect != self.algorithm.default_connect() {
            name += &format!(":{}", self.connect.name());
        }
        if self.sampler != self.algorithm.info().sampler(None) {
            name += &format!(":{}", self.sampler.name());
        }
        if let Some(n) = self.light_paths {
            name += &format!("@{n}");
        }
        name
    }

    /// Render settings of this variant (its strategy and light-path count; the rest
    /// defaults).
    pub fn settings(&self, width: u32, height: u32, budget: Budget) -> RenderSettings {
        let mut s = RenderSettings::new(self.algorithm, width, height, budget);
        s.connect = self.connect;
        s.sampler = Some(self.sampler);
        s.light_paths = self.light_paths;
        s
    }
}

/// The reference's own error estimate read back from EXR metadata (absent fields: `None`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReferenceError {
    pub rmse: Option<f64>,
    pub rel_mse: Option<f64>,
}

impl ReferenceError {
    /// Reads `vkvcm:reference_rmse` and `vkvcm:reference_rel_mse`; unparsable values count
    /// as absent.
    pub fn from_metadata(meta: &[(String, String)]) -> Self {
        let get = |k: &str| {
            meta.iter()
                .find(|(key, _)| key == k)
                .and_then(|(_, v)| v.trim().parse::<f64>().ok())
                .filter(|v| v.is_finite())
        };
        ReferenceError { rmse: get("vkvcm:reference_rmse"), rel_mse: get("vkvcm:reference_rel_mse") }
    }
}

/// A [`Renderer`] whose first iteration, which pays the driver's shader compilation, has
/// been rendered and discarded (film, iteration count and seconds reset to zero), so that
/// time budgets measure rendering only. (The film's rejected-sample counter and the
/// kernel profile keep that iteration's share.)
pub fn warm_renderer(gpu: &Arc<Gpu>, scene: &Scene, settings: &RenderSettings) -> Result<Renderer> {
    let mut r = Renderer::new(gpu, scene, settings)?;
    r.run(Budget::Iterations(1), None, &mut |_| {})?;
    let pixels = settings.frame.width as usize * settings.frame.height as usize;
    r.resume(&super::film::FilmSums::zero(pixels), &super::shard::IterationSet::new(), 0.0)?;
    Ok(r)
}

fn output_image(out: &RenderOutput) -> Image {
    Image { width: out.width, height: out.height, data: out.pixels.clone() }
}

/// One row of `vkvcm converge`'s CSV: an estimator's error at one checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConvergeRow {
    pub estimator: String,
    /// 1-based checkpoint index.
    pub checkpoint: usize,
    pub iterations: u64,
    /// Render seconds so far (read-backs and metrics excluded).
    pub seconds: f64,
    pub rmse: f64,
    pub rel_mse: f64,
    pub mean_abs_bias: f64,
    pub max_abs: f64,
    /// The reference's own error estimate (empty when the reference carries none).
    pub reference_rmse: Option<f64>,
    pub reference_rel_mse: Option<f64>,
}

/// The rows as CSV text with a header line (columns in [`ConvergeRow`]'s field order).
pub fn csv_string(rows: &[ConvergeRow]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    if rows.is_empty() {
        w.write_record([
            "estimator",
            "checkpoint",
            "iterations",
            "seconds",
            "rmse",
            "rel_mse",
            "mean_abs_bias",
            "max_abs",
            "reference_rmse",
            "reference_rel_mse",
        ])?;
    }
    for r in rows {
        w.serialize(r)?;
    }
    let bytes = w.into_inner().map_err(|e| anyhow::anyhow!("CSV: {e}"))?;
    Ok(String::from_utf8(bytes)?)
}

/// The rows of [`csv_string`]'s text (`vkvcm converge --rows`).
pub fn read_csv(text: &str) -> Result<Vec<ConvergeRow>> {
    let mut r = csv::Reader::from_reader(text.as_bytes());
    r.deserialize().map(|row| row.map_err(|e| anyhow!("CSV: {e}"))).collect()
}

/// The image [`converge_one`] measures against, and its own error estimate.
#[derive(Clone, Copy, Debug)]
pub struct Target<'a> {
    pub image: &'a Image,
    pub error: ReferenceError,
}

/// What [`converge_one`] reports after each checkpoint.
pub struct Checkpoint<'a> {
    pub row: &'a ConvergeRow,
    pub of: usize,
}

/// Renders with `settings.algorithm` (the size must match the reference's) and measures
/// the error against `reference` at each time of `times` (increasing, seconds of render
/// time). One [`Renderer`] does the whole run, warmed up by [`warm_renderer`]. A checkpoint whose time was already passed still renders one more iteration,
/// so iterations and seconds increase from row to row. Stops early (returning the rows so
/// far) when `cancel` is set.
pub fn converge_one(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    settings: &RenderSettings,
    reference: &Target,
    times: &[f64],
    cancel: Option<&AtomicBool>,
    on_checkpoint: &mut dyn FnMut(&Checkpoint),
) -> Result<Vec<ConvergeRow>> {
    let (w, h) = (settings.frame.width, settings.frame.height);
    if (w, h) != (reference.image.width, reference.image.height) {
        bail!("the render is {w}x{h} but the reference is {}x{}", reference.image.width, reference.image.height);
    }
    let mut r = warm_renderer(gpu, scene, settings)?;
    let mut rows = Vec::with_capacity(times.len());
    for (i, &t) in times.iter().enumerate() {
        if cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
            break;
        }
        // At least one iteration (Budget::Seconds always runs one).
        let left = (t - r.seconds()).max(1e-9);
        r.run(Budget::Seconds(left), cancel, &mut |_| {})?;
        let out = r.output()?;
        let m: Metrics = compare(&output_image(&out), reference.image)?;
        rows.push(ConvergeRow {
            estimator: settings.algorithm.name().to_string(),
            checkpoint: i + 1,
            iterations: out.iterations,
            seconds: out.seconds,
            rmse: m.rmse,
            rel_mse: m.rel_mse,
            mean_abs_bias: m.mean_abs_bias,
            max_abs: m.max_abs,
            reference_rmse: reference.error.rmse,
            reference_rel_mse: reference.error.rel_mse,
        });
        on_checkpoint(&Checkpoint { row: rows.last().expect("just pushed"), of: times.len() });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_halve_back_from_the_total() {
        assert_eq!(checkpoint_times(8.0, 4).unwrap(), vec![1.0, 2.0, 4.0, 8.0]);
        assert_eq!(checkpoint_times(3.0, 1).unwrap(), vec![3.0]);
        let t = checkpoint_times(30.0, 7).unwrap();
        assert_eq!(t.len(), 7);
        assert_eq!(*t.last().unwrap(), 30.0);
        assert!((t[0] - 30.0 / 64.0).abs() < 1e-12);
        assert!(t.windows(2).all(|p| (p[1] / p[0] - 2.0).abs() < 1e-12));
    }

    #[test]
    fn checkpoints_reject_bad_input() {
        for (t, k) in [(0.0, 3), (-1.0, 3), (f64::NAN, 3), (f64::INFINITY, 3), (1.0, 0), (1.0, 41)] {
            assert!(checkpoint_times(t, k).is_err(), "{t} {k}");
        }
    }

    fn row(est: &str, k: usize, reference_rmse: Option<f64>) -> ConvergeRow {
        ConvergeRow {
            estimator: est.into(),
            checkpoint: k,
            iterations: 12,
            seconds: 0.5,
            rmse: 0.125,
            rel_mse: 1e-3,
            mean_abs_bias: 0.0,
            max_abs: 2.5,
            reference_rmse,
            reference_rel_mse: reference_rmse.map(|v| v * v),
        }
    }

    #[test]
    fn csv_has_a_header_and_one_line_per_row() {
        let s = csv_string(&[row("pt", 1, Some(0.5)), row("bpt", 2, None)]).unwrap();
        let want = "estimator,checkpoint,iterations,seconds,rmse,rel_mse,mean_abs_bias,max_abs,reference_rmse,reference_rel_mse\n\
                    pt,1,12,0.5,0.125,0.001,0.0,2.5,0.5,0.25\n\
                    bpt,2,12,0.5,0.125,0.001,0.0,2.5,,\n";
        assert_eq!(s, want);
        // Empty: the header alone.
        assert_eq!(csv_string(&[]).unwrap(), want.lines().next().unwrap().to_string() + "\n");
    }

    #[test]
    fn reference_error_reads_metadata() {
        let meta = vec![
            ("vkvcm:reference_rmse".to_string(), "1.5e-3".to_string()),
            ("vkvcm:reference_rel_mse".to_string(), "oops".to_string()),
        ];
        assert_eq!(ReferenceError::from_metadata(&meta), ReferenceError { rmse: Some(1.5e-3), rel_mse: None });
        assert_eq!(ReferenceError::from_metadata(&[]), ReferenceError::default());
    }

    #[test]
    fn variant_names_parse_back() {
        for s in [
            "pt",
            "vcm",
            "bpt:path",
            "bpt:cache:1",
            "vcm:cache:4",
            "vcm@65536",
            "bpt:cache:2@100",
            "pt:independent",
            "vcm:path:independent",
            "bpt:cache:2:independent@100",
        ] {
            let v = Variant::parse(s).unwrap();
            assert_eq!(Variant::parse(&v.name()).unwrap(), v, "{s}");
        }
        assert_eq!(Variant::parse("bpt:cache:3").unwrap().connect, Connect::Cache(3));
        assert_eq!(Variant::parse("bpt").unwrap().connect, Algorithm::Bpt.default_connect());
        assert_eq!(Variant::parse("lt@1000").unwrap().light_paths, Some(1000));
        let v = Variant::parse("vcm:path:independent").unwrap();
        assert_eq!((v.connect, v.sampler), (Connect::Path, Sampler::Independent));
        assert_eq!(Variant::parse("vcm:sobol").unwrap().name(), "vcm", "sobol is vcm's default");
        for bad in [
            "xyz",
            "pt:cache:1",
            "bpt:cache:0",
            "bpt:cache",
            "bpt:cache:x",
            "bpt:other",
            "pt@100",
            "vcm@0",
            "vcm@x",
            "lt:sobol",
            "el:sobol",
            "pt:sobol:path",
        ] {
            assert!(Variant::parse(bad).is_err(), "{bad} accepted");
        }
    }
}
