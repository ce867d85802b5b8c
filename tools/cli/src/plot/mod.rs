//! `slope-eval --plot DIR`: one PNG per recording, drawn with `plotters`:
//! above, the per-frame slope of each method, the tracked slope (dashed)
//! and the ground truth (grey line); below, each method's per-frame time.
//! Lines break at frames without a value, and the frames that are not
//! `ok` get an x at the bottom of each panel.
//!
//! One concern per file: `series.rs` (what is plotted and how each series
//! looks, its runs of frames with a value, the frames not `ok`, the notes
//! on coinciding or empty series), `legend.rs` (the
//! legend column beside each panel), `charts.rs` (the two panels); this
//! file lays out the picture and its axes.

use std::path::Path;

use anyhow::Context;
use plotters::prelude::*;
use plotters::style::FontStyle;
use slope_sensor::recording::ColorImage;

use crate::eval::MethodReport;
use crate::render::write_png;
use crate::text::FONT_TTF;

// `draw_markers!` is defined in series.rs: that module comes first.
#[macro_use]
mod series;
mod charts;
mod legend;
#[cfg(test)]
mod tests;

use charts::*;
use legend::*;
use series::*;

pub use legend::LEGEND_WIDTH;
pub use series::no_ok_note;

/// Picture size, pixels.
pub const PLOT_SIZE: (u32, u32) = (1100, 760);
/// The font family name the plots use (the bundled DejaVu Sans).
const FAMILY: &str = "sans-serif";

/// Colour of each method, in `SlopeMethod::ALL` order.
const METHOD_COLOURS: [RGBColor; 3] = [
    RGBColor(30, 90, 200),
    RGBColor(220, 120, 20),
    RGBColor(40, 150, 60),
];

fn method_colour(method: slope_ipc_types::SlopeMethod) -> RGBColor {
    METHOD_COLOURS[method as usize % METHOD_COLOURS.len()]
}

/// Registers the bundled font with plotters (once per process).
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if plotters::style::register_font(FAMILY, FontStyle::Normal, FONT_TTF).is_err() {
            tracing::warn!("the bundled font did not load: plots have no text");
        }
    });
}

/// Draws the plot of one recording's reports (one per method).
pub fn plot_recording(title: &str, reports: &[MethodReport]) -> anyhow::Result<ColorImage> {
    draw_plot(title, reports, true)
}

/// The plot, with or without the legends (without: to check that they hide
/// nothing).
fn draw_plot(
    title: &str,
    reports: &[MethodReport],
    with_legend: bool,
) -> anyhow::Result<ColorImage> {
    register_font();
    let (w, h) = PLOT_SIZE;
    let mut buffer = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let root = root.titled(title, (FAMILY, 22)).map_err(plot_error)?;
        let (top, bottom) = root.split_vertically((h as f64 * 0.62) as u32);
        draw_slopes(&top, reports, with_legend)?;
        draw_times(&bottom, reports, with_legend)?;
        root.present().map_err(plot_error)?;
    }
    let data = buffer.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    Ok(ColorImage {
        width: w,
        height: h,
        data,
    })
}

/// Writes the plot of one recording to `path`.
pub fn write_recording_plot(
    path: &Path,
    title: &str,
    reports: &[MethodReport],
) -> anyhow::Result<()> {
    let image = plot_recording(title, reports)?;
    write_png(path, &image).with_context(|| format!("cannot write the plot {}", path.display()))
}

fn plot_error<E: std::fmt::Debug>(err: E) -> anyhow::Error {
    anyhow::anyhow!("drawing the plot failed: {err:?}")
}

/// The x range over every frame index of the reports.
fn frame_range(reports: &[MethodReport]) -> std::ops::Range<f64> {
    let indices = reports
        .iter()
        .flat_map(|r| r.estimates.iter().map(|f| f.index as f64));
    let (lo, hi) = indices.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    if lo.is_finite() {
        lo - 0.5..hi + 0.5
    } else {
        0.0..1.0
    }
}

/// The label of an x tick at frame `x`: the frame index where `x` is a
/// whole number, nothing between frames (plotters puts ticks at fractions
/// of a short range; "{x:.0}" made them "-0 0 0 1").
pub fn frame_tick_label(x: f64) -> String {
    let whole = x.round();
    if (x - whole).abs() < 1e-6 {
        // `+ 0.0` turns -0 into 0.
        format!("{}", whole + 0.0)
    } else {
        String::new()
    }
}

/// How many x ticks to ask plotters for: one per frame of `range` (at
/// most 11, plotters' default), so that short ranges get whole frames.
fn frame_tick_count(range: &std::ops::Range<f64>) -> usize {
    let frames = (range.end - range.start).round().max(1.0);
    if frames < 11.0 {
        frames as usize
    } else {
        11
    }
}

/// A y range holding `values` with a margin.
fn value_range(values: impl Iterator<Item = f64>, floor: Option<f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return 0.0..1.0;
    }
    let margin = ((hi - lo) * 0.1).max(0.5);
    let lo = floor.map_or(lo - margin, |f| f.max(lo - margin));
    lo..hi + margin
}
