//! `slope-eval --plot DIR`: one PNG per recording, drawn with `plotters`:
//! above, the per-frame slope of each method, the tracked slope (dashed)
//! and the ground truth (grey line); below, each method's per-frame time.

use std::path::Path;

use anyhow::Context;
use plotters::prelude::*;
use plotters::style::FontStyle;
use slope_sensor::recording::ColorImage;

use crate::eval::MethodReport;
use crate::render::write_png;
use crate::text::FONT_TTF;

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
    register_font();
    let (w, h) = PLOT_SIZE;
    let mut buffer = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let root = root.titled(title, (FAMILY, 22)).map_err(plot_error)?;
        let (top, bottom) = root.split_vertically((h as f64 * 0.62) as u32);
        draw_slopes(&top, reports)?;
        draw_times(&bottom, reports)?;
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

fn draw_slopes<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    reports: &[MethodReport],
) -> anyhow::Result<()> {
    let slopes = reports.iter().flat_map(|r| {
        r.estimates.iter().flat_map(|f| {
            let tracked = f.details.tracked.as_ref().and_then(|t| t.slope_deg);
            [f.slope_deg, tracked, f.truth_deg].into_iter().flatten()
        })
    });
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(frame_range(reports), value_range(slopes, None))
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .x_labels(frame_tick_count(&frame_range(reports)))
        .x_label_formatter(&|x| frame_tick_label(*x))
        .y_desc("slope (degrees)")
        .label_style((FAMILY, 15))
        .draw()
        .map_err(plot_error)?;
    if let Some(truth) = reports.iter().find_map(|r| r.truth_deg) {
        let sign = reports
            .iter()
            .find_map(|r| r.summary.median_slope_deg)
            .map_or(1.0, f64::signum);
        let x = frame_range(reports);
        chart
            .draw_series(LineSeries::new(
                [(x.start, sign * truth), (x.end, sign * truth)],
                RGBColor(120, 120, 120).stroke_width(2),
            ))
            .map_err(plot_error)?
            .label(format!("truth {truth:.1}°"))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RGBColor(120, 120, 120)));
    }
    for report in reports {
        let colour = method_colour(report.method);
        let points: Vec<(f64, f64)> = report
            .estimates
            .iter()
            .filter_map(|f| Some((f.index as f64, f.slope_deg?)))
            .collect();
        chart
            .draw_series(LineSeries::new(
                points.iter().copied(),
                colour.stroke_width(1),
            ))
            .map_err(plot_error)?
            .label(report.method.name())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour));
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
            .map_err(plot_error)?;
        let tracked: Vec<(f64, f64)> = report
            .estimates
            .iter()
            .filter_map(|f| Some((f.index as f64, f.details.tracked.as_ref()?.slope_deg?)))
            .collect();
        if !tracked.is_empty() {
            chart
                .draw_series(DashedLineSeries::new(tracked, 6, 4, colour.stroke_width(2)))
                .map_err(plot_error)?
                .label(format!("{} tracked", report.method.name()))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
    }
    chart
        .configure_series_labels()
        .label_font((FAMILY, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(plot_error)?;
    Ok(())
}

fn draw_times<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    reports: &[MethodReport],
) -> anyhow::Result<()> {
    let times = reports.iter().flat_map(|r| {
        r.estimates
            .iter()
            .filter_map(|f| Some(f.ms.as_ref()?.0.total_ms))
    });
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(frame_range(reports), value_range(times, Some(0.0)))
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .x_labels(frame_tick_count(&frame_range(reports)))
        .x_label_formatter(&|x| frame_tick_label(*x))
        .y_desc("time per frame (ms)")
        .label_style((FAMILY, 15))
        .draw()
        .map_err(plot_error)?;
    for report in reports {
        let colour = method_colour(report.method);
        let points: Vec<(f64, f64)> = report
            .estimates
            .iter()
            .filter_map(|f| Some((f.index as f64, f.ms.as_ref()?.0.total_ms)))
            .collect();
        // A line needs two points: a single frame is drawn as a marker.
        let markers = if points.len() == 1 { &points[..] } else { &[] };
        chart
            .draw_series(markers.iter().map(|&p| Circle::new(p, 4, colour.filled())))
            .map_err(plot_error)?;
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))
            .map_err(plot_error)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{FrameDetails, FrameResult, Timings};
    use slope_ipc_types::SlopeMethod;
    use slope_pipeline::StageTimings;

    #[test]
    fn ticks_are_whole_frames_never_minus_zero() {
        assert_eq!(frame_tick_label(-0.0), "0");
        assert_eq!(frame_tick_label(-1e-9), "0");
        assert_eq!(frame_tick_label(2.0), "2");
        assert_eq!(frame_tick_label(-3.0), "-3");
        assert_eq!(frame_tick_label(1234.0), "1234");
        for between in [-0.4, -0.2, 0.2, 0.5, 1.5, 2.4] {
            assert_eq!(frame_tick_label(between), "", "{between}");
        }
        assert_eq!(frame_tick_count(&(-0.5..0.5)), 1);
        assert_eq!(frame_tick_count(&(-0.5..2.5)), 3);
        assert_eq!(frame_tick_count(&(-0.5..29.5)), 11);
    }

    /// One frame: the time panel (a line of one point drew nothing) shows
    /// a marker in the method's colour.
    #[test]
    fn a_single_frame_is_drawn_as_a_marker() {
        let frame = FrameResult {
            index: 0,
            status: "no_ground",
            slope_deg: None,
            std_deg: None,
            distance_m: None,
            truth_deg: None,
            ms: Some(Timings(StageTimings {
                total_ms: 12.0,
                stages: Vec::new(),
            })),
            error: None,
            details: FrameDetails::default(),
        };
        let report = MethodReport::new("one".into(), SlopeMethod::Paper, vec![frame]);
        let image = plot_recording("one", &[report]).expect("plot");
        let RGBColor(r, g, b) = method_colour(SlopeMethod::Paper);
        let top = (PLOT_SIZE.1 as f64 * 0.62) as usize;
        let in_time_panel = image
            .data
            .chunks_exact(PLOT_SIZE.0 as usize)
            .skip(top)
            .flatten()
            .filter(|&&p| p == [r, g, b])
            .count();
        assert!(
            in_time_panel > 10,
            "{in_time_panel} pixels of the method's colour"
        );
    }
}
