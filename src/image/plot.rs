//! Log-log line plots (error vs. time) as PNG, drawn with the `plotters` crate into a pixel
//! buffer. Text uses DejaVu Sans embedded in the binary (assets/fonts/, with its license)
//! through plotters' `ab_glyph` renderer, so no system font library is needed.

use std::path::Path;
use std::sync::Once;

use ::image::ImageEncoder;
use anyhow::{anyhow, bail, Result};
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::atomic::write_atomic;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";
/// Pixels right of the chart for the legend.
const LEGEND_WIDTH: u32 = 200;

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is a constant of the build: it parses or the build is broken.
        if plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_err() {
            panic!("the embedded DejaVu Sans font does not parse");
        }
    });
}

/// One curve: a name for the legend and (x, y) points in drawing order.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// A log-log plot of several curves.
#[derive(Clone, Debug)]
pub struct LogLogPlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// A dashed horizontal line at this y with its legend label (e.g. a noise floor).
    pub floor: Option<(f64, String)>,
    pub width: u32,
    pub height: u32,
}

/// Line colours (Okabe-Ito, distinguishable with colour-vision deficiencies).
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

fn positive(v: f64) -> bool {
    v > 0.0 && v.is_finite()
}

/// Range of the positive finite values, widened by a margin of `pad` decades each side
/// (and to a full decade when all values are equal).
fn log_range(values: impl Iterator<Item = f64>, pad: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values.filter(|&v| positive(v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if hi == 0.0 {
        return None;
    }
    if hi / lo < 10f64.powf(0.5) {
        let mid = (hi * lo).sqrt();
        lo = mid / 10f64.powf(0.25);
        hi = mid * 10f64.powf(0.25);
    }
    let f = 10f64.powf(pad);
    Some((lo / f, hi * f))
}

/// Draws `plot` as an RGB image and returns its pixels (row-major, 3 bytes per pixel).
/// Points with a non-positive or non-finite coordinate are left out (log axes).
pub fn render_loglog(plot: &LogLogPlot) -> Result<Vec<u8>> {
    register_font();
    let (w, h) = (plot.width, plot.height);
    if w < 400 || h < 200 {
        bail!("plot size {w}x{h} is too small (at least 400x200)");
    }
    let xs = plot.series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let Some((x0, x1)) = log_range(xs, 0.05) else { bail!("nothing to plot: no positive x value") };
    let ys = plot.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)).chain(plot.floor.iter().map(|f| f.0));
    let Some((y0, y1)) = log_range(ys, 0.1) else { bail!("nothing to plot: no positive y value") };

    let mut buf = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let err = |e: DrawingAreaErrorKind<_>| anyhow!("plot: {e}");
        root.fill(&WHITE).map_err(err)?;
        let (root, legend) = root.split_horizontally(w - LEGEND_WIDTH);
        let mut chart =
            ChartBuilder::on(&root)
                .caption(&plot.title, (FAMILY, 22))
                .margin(14)
                .x_label_area_size(48)
                .y_label_area_size(72)
                .build_cartesian_2d(
                    (x0..x1)
                        .log_scale()
                        .with_key_points(log_ticks(x0, x1, &[1.0, 2.0, 5.0]))
                        .with_light_points(log_ticks(x0, x1, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])),
                    (y0..y1)
                        .log_scale()
                        .with_key_points(log_ticks(y0, y1, &[1.0, 2.0, 5.0]))
                        .with_light_points(log_ticks(y0, y1, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])),
                )
                .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(&plot.x_label)
            .y_desc(&plot.y_label)
            .label_style((FAMILY, 15))
            .axis_desc_style((FAMILY, 17))
            .x_label_formatter(&|v| format_tick(*v))
            .y_label_formatter(&|v| format_tick(*v))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(205, 205, 205))
            .draw()
            .map_err(err)?;
        for (i, s) in plot.series.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| positive(p.0) && positive(p.1)).collect();
            let style = colour.stroke_width(2);
            chart.draw_series(LineSeries::new(pts.clone(), style)).map_err(err)?;
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(err)?;
        }
        if let Some((y, _)) = &plot.floor {
            if positive(*y) {
                let grey = RGBColor(90, 90, 90);
                chart
                    .draw_series(DashedLineSeries::new(vec![(x0, *y), (x1, *y)], 8, 6, grey.stroke_width(2)))
                    .map_err(err)?;
            }
        }
        // The legend, right of the chart (inside it would hide some curve or other).
        let mut y = 60;
        for (i, s) in plot.series.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            legend.draw(&PathElement::new(vec![(8, y), (34, y)], colour.stroke_width(2))).map_err(err)?;
            legend.draw(&Circle::new((21, y), 3, colour.filled())).map_err(err)?;
            legend.draw(&Text::new(s.name.clone(), (42, y - 7), (FAMILY, 16))).map_err(err)?;
            y += 26;
        }
        if let Some((_, label)) = &plot.floor {
            let grey = RGBColor(90, 90, 90);
            for x in [8, 22] {
                legend.draw(&PathElement::new(vec![(x, y), (x + 8, y)], grey.stroke_width(2))).map_err(err)?;
            }
            // Wrap a long label onto lines of about 18 characters.
            let mut lines: Vec<String> = vec![String::new()];
            for word in label.split_whitespace() {
                let cur = lines.last_mut().expect("one line at least");
                if !cur.is_empty() && cur.len() + word.len() > 18 {
                    lines.push(word.to_string());
                } else {
                    if !cur.is_empty() {
                        cur.push(' ');
                    }
                    cur.push_str(word);
                }
            }
            for (k, line) in lines.into_iter().enumerate() {
                legend.draw(&Text::new(line, (42, y - 7 + 19 * k as i32), (FAMILY, 16))).map_err(err)?;
            }
        }
        root.present().map_err(err)?;
    }
    Ok(buf)
}

/// Draws `plot` and writes it as a PNG (atomically; errors name `path`).
pub fn write_loglog_png(path: &Path, plot: &LogLogPlot) -> Result<()> {
    let rgb = render_loglog(plot).map_err(|e| anyhow!("cannot write plot {}: {e:#}", path.display()))?;
    let mut bytes = Vec::new();
    ::image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&rgb, plot.width, plot.height, ::image::ExtendedColorType::Rgb8)
        .map_err(|e| anyhow!("cannot write plot {}: {e}", path.display()))?;
    write_atomic(path, "PNG", |w| Ok(w.write_all(&bytes)?))
}

/// The values m * 10^k in [lo, hi] for each mantissa m of `mantissas` (e.g. 1, 2, 5): tick
/// positions of a log axis. plotters' own choice labels only part of a range that starts
/// inside a decade.
fn log_ticks(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let mut v = Vec::new();
    for k in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
        for m in mantissas {
            let t = m * 10f64.powi(k);
            if t >= lo && t <= hi {
                v.push(t);
            }
        }
    }
    v
}

/// Tick labels: 0.01, 0.1, 1, 10, 100 plainly, other magnitudes as 1e-4.
fn format_tick(v: f64) -> String {
    let a = v.abs();
    if (1e-2..1e3).contains(&a) {
        let s = format!("{v:.2}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks() {
        assert_eq!(format_tick(1.0), "1");
        assert_eq!(format_tick(0.5), "0.5");
        assert_eq!(format_tick(20.0), "20");
        assert_eq!(format_tick(1e-4), "1e-4");
        assert_eq!(format_tick(3e4), "3e4");
    }

    #[test]
    fn log_ticks_cover_partial_decades() {
        assert_eq!(log_ticks(0.03, 0.7, &[1.0, 2.0, 5.0]), vec![0.05, 0.1, 0.2, 0.5]);
        assert_eq!(log_ticks(1.0, 10.0, &[1.0]), vec![1.0, 10.0]);
    }

    #[test]
    fn draws_curves_and_text() {
        let plot = LogLogPlot {
            title: "t".into(),
            x_label: "seconds".into(),
            y_label: "RMSE".into(),
            series: vec![Series { name: "pt".into(), points: vec![(0.1, 1.0), (1.0, 0.3), (10.0, 0.1)] }],
            floor: Some((0.05, "floor".into())),
            width: 400,
            height: 300,
        };
        let px = render_loglog(&plot).unwrap();
        assert_eq!(px.len(), 400 * 300 * 3);
        // The first palette colour (the curve) is drawn somewhere.
        let c = PALETTE[0];
        assert!(px.chunks_exact(3).any(|p| p == [c.0, c.1, c.2]));
        let empty = LogLogPlot { series: vec![], floor: None, ..plot };
        assert!(render_loglog(&empty).is_err());
    }
}
