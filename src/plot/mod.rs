//! `dibench plot RUN_DIR`: figures from a compare run directory, written to `RUN_DIR/plots/`:
//! - `rmse_vs_time.png` / `.svg`: log-log RMSE against render time per strategy, mean over
//!   runs with the 95 % Student-t band, and a slope −½ guide (RMSE ∝ t^−½ for an unbiased
//!   estimator at constant cost per sample);
//! - `rmse_vs_spp.png` / `.svg`: the same against samples per pixel, with the slope over
//!   ln spp (the axis of QMC convergence rates, and of a `compare --spp` run);
//! - `variance.png`: per-pixel variance of the mean (`<strategy>.variance.exr`, mean of the RGB
//!   channels), log10 on one shared scale with a colour bar;
//! - `strip.png`: the equal-time images (run 0) side by side, clamped to [0, 1] and sRGB-encoded.
//!
//! Text uses the vendored DejaVu Sans (assets/fonts), so no system font library is needed.
//! The two image figures are PNG only: an SVG of them would be one rectangle per pixel.

use crate::error::{Error, Result};
use crate::film::Image;
use crate::harness::compare::ResultRow;
use crate::output::{read_exr, write_bytes};
use crate::stats::mean_ci;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn register_font() -> Result<()> {
    static ONCE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *ONCE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Usage("cannot load the embedded plot font".into()))
    }
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Output {
        path: path.into(),
        message: format!("cannot draw the plot: {e}"),
    }
}

/// The x axis of an RMSE chart.
#[derive(Clone, Copy, PartialEq)]
enum Axis {
    Time,
    Spp,
}

impl Axis {
    fn stem(self) -> &'static str {
        match self {
            Axis::Time => "rmse_vs_time",
            Axis::Spp => "rmse_vs_spp",
        }
    }
    fn x(self, r: &ResultRow) -> f64 {
        match self {
            Axis::Time => r.time_s,
            Axis::Spp => r.spp as f64,
        }
    }
}

/// One strategy's curve: per checkpoint, mean x (time or spp), mean RMSE and CI half-width
/// (if ≥ 2 runs).
struct Curve {
    label: String,
    points: Vec<(f64, f64, Option<f64>)>,
}

/// One curve per (strategy, sampler, integrand): the sampler is part of a run's identity, and
/// part of the label when the run used more than one or a non-default one.
fn curves(rows: &[ResultRow], axis: Axis) -> Vec<Curve> {
    let mut keys: Vec<(String, String, String)> = Vec::new();
    for r in rows {
        let k = (r.strategy.clone(), r.sampler.clone(), r.integrand.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let label_sampler = keys.iter().any(|k| k.1 != keys[0].1)
        || keys
            .iter()
            .any(|k| k.1 != crate::sampling::GENERATORS[0].name());
    keys.into_iter()
        .map(|(strategy, sampler, integrand)| {
            let mine: Vec<&ResultRow> = rows
                .iter()
                .filter(|r| {
                    r.strategy == strategy && r.sampler == sampler && r.integrand == integrand
                })
                .collect();
            let mut cps: Vec<u32> = mine.iter().map(|r| r.checkpoint).collect();
            cps.sort_unstable();
            cps.dedup();
            let points = cps
                .iter()
                .map(|&c| {
                    let at: Vec<&&ResultRow> = mine.iter().filter(|r| r.checkpoint == c).collect();
                    let t = at.iter().map(|r| axis.x(r)).sum::<f64>() / at.len() as f64;
                    let rmse: Vec<f64> = at.iter().map(|r| r.rmse).collect();
                    let ci = mean_ci(&rmse, crate::harness::summary::LEVEL);
                    (t, ci.mean, ci.half_width)
                })
                .collect();
            // The mean over runs of each run's log-log slope (`summary::convergence_slopes`).
            let mut runs: Vec<u32> = mine.iter().map(|r| r.run).collect();
            runs.sort_unstable();
            runs.dedup();
            let slopes: Vec<f64> = runs
                .iter()
                .filter_map(|&k| {
                    let of_run: Vec<ResultRow> = mine
                        .iter()
                        .filter(|r| r.run == k)
                        .map(|r| (*r).clone())
                        .collect();
                    let (time, spp) = crate::harness::summary::convergence_slopes(&of_run);
                    match axis {
                        Axis::Time => time,
                        Axis::Spp => spp,
                    }
                })
                .collect();
            let strategy = if label_sampler {
                format!("{strategy} [{sampler}]")
            } else {
                strategy
            };
            let name = if integrand == "direct" {
                strategy
            } else {
                format!("{strategy} ({integrand})")
            };
            let label = match slopes.len() {
                0 => name,
                n => format!("{name}, slope {:.2}", slopes.iter().sum::<f64>() / n as f64),
            };
            Curve { label, points }
        })
        .collect()
}

fn draw_rmse<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    curves: &[Curve],
    axis: Axis,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_err(Path::new(axis.stem()), e);
    root.fill(&WHITE).map_err(e)?;
    let all = curves.iter().flat_map(|c| c.points.iter());
    let (mut t0, mut t1, mut y0, mut y1) = (f64::MAX, 0.0f64, f64::MAX, 0.0f64);
    for &(t, y, _) in all {
        t0 = t0.min(t);
        t1 = t1.max(t);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !(t0 > 0.0 && y0 > 0.0 && t1 >= t0) {
        return Err(plot_err(Path::new(axis.stem()), "no positive data"));
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(
            match axis {
                Axis::Time => "RMSE against render time (mean, 95 % CI)",
                Axis::Spp => "RMSE against samples per pixel (mean, 95 % CI)",
            },
            ("sans-serif", 22),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (t0 / 1.3..t1 * 1.3).log_scale(),
            (y0 / 2.0..y1 * 2.0).log_scale(),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(match axis {
            Axis::Time => "time [s]",
            Axis::Spp => "samples per pixel",
        })
        .y_desc("RMSE")
        .x_labels(6)
        .y_labels(6)
        .light_line_style(WHITE)
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|x| format!("{x:.1e}"))
        .y_label_formatter(&|y| format!("{y:.1e}"))
        .draw()
        .map_err(e)?;
    for (i, c) in curves.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        // The band's lower edge is drawn at the bottom of the axis where mean − CI ≤ 0.
        let band: Vec<(f64, f64)> = c
            .points
            .iter()
            .filter_map(|&(t, y, h)| h.map(|h| (t, y + h)))
            .chain(
                c.points
                    .iter()
                    .rev()
                    .filter_map(|&(t, y, h)| h.map(|h| (t, (y - h).max(y0 / 2.0)))),
            )
            .collect();
        if band.len() >= 4 {
            chart
                .draw_series(std::iter::once(Polygon::new(
                    band,
                    colour.mix(0.2).filled(),
                )))
                .map_err(e)?;
        }
        chart
            .draw_series(LineSeries::new(
                c.points.iter().map(|&(t, y, _)| (t, y)),
                colour.stroke_width(2),
            ))
            .map_err(e)?
            .label(c.label.clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2)));
    }
    // Slope −½ guide through the lowest curve's first point.
    if let Some(&(ta, ya, _)) = curves
        .iter()
        .filter_map(|c| c.points.first())
        .min_by(|a, b| a.1.total_cmp(&b.1))
    {
        let guide = [(ta, ya * 0.7), (t1, ya * 0.7 * (ta / t1).sqrt())];
        chart
            .draw_series(DashedLineSeries::new(guide, 6, 4, BLACK.stroke_width(1)))
            .map_err(e)?
            .label("slope −½")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK));
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// Encodes an RGB8 buffer as PNG and writes it atomically.
fn write_png(path: &Path, (w, h): (u32, u32), rgb: &[u8]) -> Result<()> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| plot_err(path, e))?;
        writer
            .write_image_data(rgb)
            .map_err(|e| plot_err(path, e))?;
    }
    write_bytes(path, &bytes)
}

/// Renders a figure into an RGB buffer with `draw`, then writes it as PNG.
fn png_figure(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<BitMapBackend, Shift>) -> Result<()>,
) -> Result<()> {
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    draw(BitMapBackend::with_buffer(&mut buf, size).into_drawing_area())?;
    write_png(path, size, &buf)
}

fn svg_figure(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<SVGBackend, Shift>) -> Result<()>,
) -> Result<()> {
    let mut text = String::new();
    draw(SVGBackend::with_string(&mut text, size).into_drawing_area())?;
    write_bytes(path, text.as_bytes())
}

/// The images a figure shows, one per strategy, in results.csv order.
fn strategy_images(run_dir: &Path, names: &[String], suffix: &str) -> Result<Vec<(String, Image)>> {
    names
        .iter()
        .map(|n| {
            Ok((
                n.clone(),
                read_exr(&run_dir.join(format!("{n}{suffix}.exr")))?,
            ))
        })
        .collect()
}

const SCALE: u32 = 2;
const LABEL_H: u32 = 26;
const GAP: u32 = 8;

/// Draws images side by side with a caption above each; `colour(x, y)` per image pixel.
fn draw_tiles(
    root: &DrawingArea<BitMapBackend, Shift>,
    images: &[(String, Image)],
    colour: impl Fn(&Image, u32, u32) -> RGBColor,
) -> Result<()> {
    let e = |e| plot_err(Path::new("tiles"), e);
    let mut x0 = GAP as i32;
    for (name, img) in images {
        root.draw(&Text::new(
            name.clone(),
            (x0, 4),
            ("sans-serif", 16).into_font().color(&BLACK),
        ))
        .map_err(e)?;
        for y in 0..img.height {
            for x in 0..img.width {
                let c = colour(img, x, y);
                for dy in 0..SCALE {
                    for dx in 0..SCALE {
                        root.draw_pixel(
                            (
                                x0 + (x * SCALE + dx) as i32,
                                (LABEL_H + y * SCALE + dy) as i32,
                            ),
                            &c,
                        )
                        .map_err(e)?;
                    }
                }
            }
        }
        x0 += (img.width * SCALE + GAP) as i32;
    }
    Ok(())
}

fn srgb8(v: f64) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

fn viridis(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let c = colorous::VIRIDIS.eval_continuous(t);
    RGBColor(c.r, c.g, c.b)
}

fn mean_channel(img: &Image, x: u32, y: u32) -> f64 {
    let p = img.pixels[(y * img.width + x) as usize];
    (p[0] + p[1] + p[2]) / 3.0
}

/// Writes every figure for `run_dir` into `run_dir/plots/` and returns their paths.
/// A time or an RMSE a log axis can show, with room to pad the axis by 2× either way.
fn plottable(v: f64) -> bool {
    (1e-300..=1e300).contains(&v)
}

pub fn plot_run(run_dir: &Path) -> Result<Vec<PathBuf>> {
    register_font()?;
    let csv_path = run_dir.join("results.csv");
    // A CSV row of text becomes a ResultRow of about the same size, strings and all.
    let bytes = crate::bounded::read_file(&csv_path, 4)?;
    let mut reader = csv::Reader::from_reader(&bytes[..]);
    let rows: Vec<ResultRow> = reader
        .deserialize()
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| Error::Parse {
            path: csv_path.clone(),
            message: e.to_string(),
        })?;
    if rows.is_empty() {
        return Err(Error::Parse {
            path: csv_path,
            message: "no result rows".into(),
        });
    }
    // The names become file names in the run directory, and nothing outside it.
    let bad = |n: &str| n.is_empty() || Path::new(n).file_name() != Some(n.as_ref());
    if let Some(r) = rows.iter().find(|r| bad(&r.strategy)) {
        return Err(Error::Parse {
            path: csv_path,
            message: format!("`{}` is not a strategy name", r.strategy),
        });
    }
    if let Some(r) = rows.iter().find(|r| bad(&r.sampler)) {
        return Err(Error::Parse {
            path: csv_path,
            message: format!("`{}` is not a sampler name", r.sampler),
        });
    }
    // Non-finite, zero or negative values have no place on a log axis: left out, and said.
    let (rows_on_axis, off_axis): (Vec<ResultRow>, Vec<ResultRow>) = rows
        .iter()
        .cloned()
        .partition(|r| plottable(r.time_s) && plottable(r.rmse));
    if !off_axis.is_empty() {
        crate::interrupt::note(&format!(
            "plot: {} of {} rows of {} left out of the RMSE chart (time or RMSE not finite and \
             positive)",
            off_axis.len(),
            rows.len(),
            csv_path.display()
        ));
    }
    let dir = run_dir.join("plots");
    crate::output::check_output_dir(&dir, "RUN_DIR")?;
    let mut written = Vec::new();

    let size = (900, 620);
    for axis in [Axis::Time, Axis::Spp] {
        let c = curves(&rows_on_axis, axis);
        let p = dir.join(format!("{}.png", axis.stem()));
        png_figure(&p, size, |root| draw_rmse(root, &c, axis))?;
        written.push(p);
        let p = dir.join(format!("{}.svg", axis.stem()));
        svg_figure(&p, size, |root| draw_rmse(root, &c, axis))?;
        written.push(p);
    }

    // One image per (strategy, sampler), by its file stem (`compare::image_stem`).
    let mut names: Vec<String> = Vec::new();
    let mut independent: Vec<String> = Vec::new();
    for r in &rows {
        let stem = crate::harness::compare::image_stem(&r.strategy, &r.sampler);
        if !names.contains(&stem) {
            if crate::sampling::generator(&r.sampler).is_none_or(|g| g.independent_samples()) {
                independent.push(stem.clone());
            }
            names.push(stem);
        }
    }
    let images = strategy_images(run_dir, &names, "")?;
    // Images of different sizes (a tampered run) are laid out by their own sizes.
    let h = images.iter().map(|(_, i)| i.height).max().unwrap_or(1);
    let strip_w = images.iter().fold(GAP as u64, |w, (_, i)| {
        w + i.width as u64 * SCALE as u64 + GAP as u64
    });
    let strip_h = (LABEL_H + GAP) as u64 + h as u64 * SCALE as u64;
    if strip_w > i32::MAX as u64 / 2 || strip_h > i32::MAX as u64 / 2 {
        return Err(plot_err(
            &dir,
            format!("a {strip_w}×{strip_h} strip is too large to draw"),
        ));
    }
    // The strip and the variance figure, RGB8, and their PNG encodings.
    crate::bounded::check_memory(
        || format!("{}: a {strip_w}×{strip_h} image strip", run_dir.display()),
        crate::bounded::bytes(strip_w * strip_h, 12),
    )?;
    let strip_size = (strip_w as u32, strip_h as u32);
    let p = dir.join("strip.png");
    png_figure(&p, strip_size, |root| {
        root.fill(&WHITE).map_err(|e| plot_err(&p, e))?;
        draw_tiles(&root, &images, |img, x, y| {
            let q = img.pixels[(y * img.width + x) as usize];
            RGBColor(srgb8(q[0]), srgb8(q[1]), srgb8(q[2]))
        })
    })?;
    written.push(p);

    // The variance of the mean exists for independent samples only (a QMC run writes none:
    // its across-pass variance is not the variance of the mean).
    if independent.len() < names.len() {
        crate::interrupt::note(&format!(
            "plot: variance.png shows the {} independent-sample run(s) only; a non-independent \
             sampler has no per-pixel variance of the mean",
            independent.len()
        ));
    }
    if independent.is_empty() {
        return Ok(written);
    }
    let images: Vec<(String, Image)> = images
        .into_iter()
        .filter(|(n, _)| independent.contains(n))
        .collect();
    let variances = strategy_images(run_dir, &independent, ".variance")?;
    let strip_size = {
        let w = images.iter().fold(GAP as u64, |w, (_, i)| {
            w + i.width as u64 * SCALE as u64 + GAP as u64
        });
        (w as u32, strip_size.1)
    };
    for ((name, img), (_, var)) in images.iter().zip(&variances) {
        if (img.width, img.height) != (var.width, var.height) {
            return Err(Error::Parse {
                path: run_dir.join(format!("{name}.variance.exr")),
                message: format!(
                    "{}×{} pixels, but {name}.exr has {}×{}",
                    var.width, var.height, img.width, img.height
                ),
            });
        }
    }
    // One log10 scale over all strategies: the 1st to 99.9th percentile of the positive
    // values, so a few near-zero pixels (light edges) do not stretch the scale; values outside
    // take the ends of the colour bar.
    let mut logs: Vec<f64> = variances
        .iter()
        .flat_map(|(_, img)| img.pixels.iter().map(|p| (p[0] + p[1] + p[2]) / 3.0))
        .filter(|&v| v > 0.0 && v.is_finite())
        .map(f64::log10)
        .collect();
    logs.sort_by(f64::total_cmp);
    let (lo, hi) = if logs.is_empty() {
        (0.0, 1.0)
    } else {
        let q = |f: f64| logs[((logs.len() - 1) as f64 * f) as usize];
        (q(0.01), q(0.999))
    };
    let span = (hi - lo).max(1e-9);
    const BAR_W: u32 = 110;
    let var_size = (strip_size.0 + BAR_W, strip_size.1 + 30);
    let p = dir.join("variance.png");
    png_figure(&p, var_size, |root| {
        let e = |e| plot_err(&p, e);
        root.fill(&WHITE).map_err(e)?;
        // Zero-variance pixels (e.g. the background) take the bottom of the scale.
        draw_tiles(&root, &variances, |img, x, y| {
            let v = mean_channel(img, x, y);
            viridis(if v > 0.0 && v.is_finite() {
                (v.log10() - lo) / span
            } else {
                0.0
            })
        })?;
        let bx = strip_size.0 as i32 + 4;
        let (top, bottom) = (LABEL_H as i32, (LABEL_H + h * SCALE) as i32);
        for y in top..bottom {
            let t = (bottom - y) as f64 / (bottom - top) as f64;
            root.draw(&Rectangle::new(
                [(bx, y), (bx + 16, y + 1)],
                viridis(t).filled(),
            ))
            .map_err(e)?;
        }
        for k in 0..=4 {
            let t = k as f64 / 4.0;
            let y = bottom - ((bottom - top) as f64 * t) as i32;
            root.draw(&Text::new(
                format!("{:.1e}", 10f64.powf(lo + t * span)),
                (bx + 20, y - 7),
                ("sans-serif", 13).into_font().color(&BLACK),
            ))
            .map_err(e)?;
        }
        root.draw(&Text::new(
            "per-pixel variance of the mean (log scale, mean of RGB)",
            (GAP as i32, (LABEL_H + h * SCALE + 10) as i32),
            ("sans-serif", 14).into_font().color(&BLACK),
        ))
        .map_err(e)?;
        Ok(())
    })?;
    written.push(p);
    Ok(written)
}
