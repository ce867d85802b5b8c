//! `slope-eval --plot DIR`: one PNG per recording, drawn with `plotters`:
//! above, the per-frame slope of each method, the tracked slope (dashed)
//! and the ground truth (grey line); below, each method's per-frame time.

use std::path::Path;

use anyhow::Context;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
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

/// How one series is drawn: in the chart and in its legend sample alike,
/// so that the sample looks like the line.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SeriesStyle {
    colour: RGBColor,
    width: u32,
    dashed: bool,
    marker: Option<Marker>,
}

/// The marker of a method's per-frame slopes: a shape per method, so that
/// methods that agree (least-squares and tls often do to 0.01°) are both
/// seen (the hollow square is larger than the triangle drawn in it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Marker {
    Disc,
    HollowSquare,
    Triangle,
}

/// Dash and gap of the tracked slope's line, pixels.
const DASH: (u32, u32) = (8, 5);
/// Grey of the truth line.
const TRUTH_GREY: RGBColor = RGBColor(120, 120, 120);
/// Colour of the notes under the legend.
const NOTE_GREY: RGBColor = RGBColor(60, 60, 60);
/// Two series closer than this on every frame are said to coincide.
const SAME_DEG: f64 = 0.01;

fn method_marker(method: slope_ipc_types::SlopeMethod) -> Marker {
    [Marker::Disc, Marker::HollowSquare, Marker::Triangle][method as usize % 3]
}

/// One line of the slope panel with its legend label.
#[derive(Debug, Clone, PartialEq)]
struct Series {
    label: String,
    style: SeriesStyle,
    points: Vec<(f64, f64)>,
}

/// The series of the slope panel, in drawing order: per method its
/// per-frame slope (thin, markers) and its tracked slope (dashed).
fn slope_series(reports: &[MethodReport]) -> Vec<Series> {
    let mut out = Vec::new();
    for report in reports {
        let colour = method_colour(report.method);
        let points: Vec<(f64, f64)> = report
            .estimates
            .iter()
            .filter_map(|f| Some((f.index as f64, f.slope_deg?)))
            .collect();
        let label = if points.is_empty() {
            format!("{} (no ok frame)", report.method.name())
        } else {
            report.method.name().to_string()
        };
        out.push(Series {
            label,
            style: SeriesStyle {
                colour,
                width: 1,
                dashed: false,
                marker: Some(method_marker(report.method)),
            },
            points,
        });
        let tracked: Vec<(f64, f64)> = report
            .estimates
            .iter()
            .filter_map(|f| Some((f.index as f64, f.details.tracked.as_ref()?.slope_deg?)))
            .collect();
        if !tracked.is_empty() {
            out.push(Series {
                label: format!("{} tracked", report.method.name()),
                style: SeriesStyle {
                    colour,
                    width: 2,
                    dashed: true,
                    marker: None,
                },
                points: tracked,
            });
        }
    }
    out
}

/// Notes on series drawn over each other: two series of the same kind
/// (both per-frame, or both tracked) with points on the same frames, within
/// [`SAME_DEG`] on each, the later one hiding the earlier's line ("tls
/// hides least-squares: ...").
fn coincidence_notes(series: &[Series]) -> Vec<String> {
    let mut notes = Vec::new();
    for (i, a) in series.iter().enumerate() {
        for b in &series[i + 1..] {
            let same = a.style.dashed == b.style.dashed
                && !a.points.is_empty()
                && a.points.len() == b.points.len()
                && a.points
                    .iter()
                    .zip(&b.points)
                    .all(|(p, q)| (p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() <= SAME_DEG);
            if same {
                notes.push(format!(
                    "{} hides {}: within {SAME_DEG}° on every frame",
                    b.label, a.label
                ));
            }
        }
    }
    notes
}

/// The note of a slope panel without any `ok` frame (nothing to draw): the
/// statuses counted, per method when there are several; `None` when some
/// frame is `ok`.
pub fn no_ok_note(reports: &[MethodReport]) -> Option<Vec<String>> {
    let any_ok = reports
        .iter()
        .any(|r| r.estimates.iter().any(|f| f.slope_deg.is_some()));
    if any_ok {
        return None;
    }
    let counts = |r: &MethodReport| {
        let counts: Vec<String> = r
            .summary
            .not_ok
            .0
            .iter()
            .map(|(name, count)| format!("{name} x{count}"))
            .collect();
        if counts.is_empty() {
            "no frame".to_string()
        } else {
            counts.join(", ")
        }
    };
    Some(match reports {
        [one] => vec![format!("no ok frame: {}", counts(one))],
        _ => std::iter::once("no ok frame:".to_string())
            .chain(
                reports
                    .iter()
                    .map(|r| format!("{}: {}", r.method.name(), counts(r))),
            )
            .collect(),
    })
}

/// Draws `marker`s in `colour` centred at `points` with `draw(target,
/// elements)`: `ChartContext::draw_series` (data coordinates) or
/// [`draw_each`] (an area's pixels). A macro, as each shape is its own type.
macro_rules! draw_markers {
    ($draw:path, $target:expr, $marker:expr, $points:expr, $colour:expr) => {{
        let colour: RGBColor = $colour;
        match $marker {
            Marker::Disc => $draw(
                $target,
                $points.map(|p| EmptyElement::at(p) + Circle::new((0, 0), 3, colour.filled())),
            )
            .map(|_| ())
            .map_err(plot_error),
            Marker::HollowSquare => $draw(
                $target,
                $points.map(|p| {
                    EmptyElement::at(p) + Rectangle::new([(-6, -6), (6, 6)], colour.stroke_width(2))
                }),
            )
            .map(|_| ())
            .map_err(plot_error),
            Marker::Triangle => $draw(
                $target,
                $points
                    .map(|p| EmptyElement::at(p) + TriangleMarker::new((0, 0), 5, colour.filled())),
            )
            .map(|_| ())
            .map_err(plot_error),
        }
    }};
}

/// Draws each of `elements` on `area` (pixel coordinates).
fn draw_each<DB: DrawingBackend, E>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    elements: impl Iterator<Item = E>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    E: plotters::element::Drawable<DB>,
    for<'a> &'a E: plotters::element::PointCollection<'a, (i32, i32)>,
{
    for element in elements {
        area.draw(&element)?;
    }
    Ok(())
}

/// Draws `points` as a line in `style` (dashed or not; the markers apart).
fn draw_line<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    points: Vec<(i32, i32)>,
    style: SeriesStyle,
) -> anyhow::Result<()> {
    let stroke = style.colour.stroke_width(style.width);
    if style.dashed {
        area.draw(&DashedPathElement::new(points, DASH.0, DASH.1, stroke))
    } else {
        area.draw(&PathElement::new(points, stroke))
    }
    .map_err(plot_error)
}

/// Pixel layout of the legend column: left margin, top, row height and
/// the width of a sample line.
const LEGEND_X: i32 = 10;
const LEGEND_TOP: i32 = 24;
const LEGEND_ROW: i32 = 26;
const LEGEND_SAMPLE: i32 = 40;
const LEGEND_FONT: u32 = 15;
/// Width of the column right of each panel that holds its legend (outside
/// the plotting area, so that it hides no data).
pub const LEGEND_WIDTH: u32 = 240;

/// The legend in its own column: per entry a sample drawn like its line
/// (same width, dash and marker) and its label; then `notes`, wrapped.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[(String, SeriesStyle)],
    notes: &[String],
) -> anyhow::Result<()> {
    let font = TextStyle::from((FAMILY, LEGEND_FONT).into_font());
    let left = font.pos(Pos::new(HPos::Left, VPos::Center));
    let mut y = LEGEND_TOP;
    for (label, style) in entries {
        let x1 = LEGEND_X + LEGEND_SAMPLE;
        draw_line(area, vec![(LEGEND_X, y), (x1, y)], *style)?;
        if let Some(marker) = style.marker {
            let at = [(LEGEND_X + LEGEND_SAMPLE / 2, y)];
            draw_markers!(draw_each, area, marker, at.into_iter(), style.colour)?;
        }
        area.draw(&Text::new(label.as_str(), (x1 + 8, y), left.clone()))
            .map_err(plot_error)?;
        y += LEGEND_ROW;
    }
    let note_style = font.color(&NOTE_GREY);
    let (width, height) = area.dim_in_pixel();
    let width = width.saturating_sub(2 * LEGEND_X as u32);
    y += LEGEND_ROW / 2;
    for note in notes {
        for line in wrap(note, |t| {
            area.estimate_text_size(t, &font).map_or(0, |(w, _)| w) <= width
        }) {
            if y + LEGEND_ROW > height as i32 {
                // Out of room: the rest would be cut in half.
                return Ok(());
            }
            area.draw(&Text::new(line, (LEGEND_X, y - 8), note_style.clone()))
                .map_err(plot_error)?;
            y += LEGEND_ROW - 6;
        }
        y += 6;
    }
    Ok(())
}

/// `text` in lines that `fits`, broken at spaces (a word longer than a
/// line is a line of its own).
fn wrap(text: &str, fits: impl Fn(&str) -> bool) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let candidate = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if line.is_empty() || fits(&candidate) {
            line = candidate;
        } else {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

fn draw_slopes<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    reports: &[MethodReport],
    with_legend: bool,
) -> anyhow::Result<()> {
    let (w, _) = area.dim_in_pixel();
    let (area, legend_area) = area.split_horizontally(w.saturating_sub(LEGEND_WIDTH));
    let series = slope_series(reports);
    let truth = reports.iter().find_map(|r| r.truth_deg).map(|truth| {
        let sign = reports
            .iter()
            .find_map(|r| r.summary.median_slope_deg)
            .map_or(1.0, f64::signum);
        (truth, sign * truth)
    });
    let slopes = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .chain(truth.map(|t| t.1));
    let mut chart = ChartBuilder::on(&area)
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
    let mut legend = Vec::new();
    if let Some((truth, y)) = truth {
        let style = SeriesStyle {
            colour: TRUTH_GREY,
            width: 3,
            dashed: false,
            marker: None,
        };
        let x = frame_range(reports);
        chart
            .draw_series(LineSeries::new(
                [(x.start, y), (x.end, y)],
                style.colour.stroke_width(style.width),
            ))
            .map_err(plot_error)?;
        legend.push((format!("truth {truth:.1}°"), style));
    }
    // Lines first, then every marker, so that no line hides a marker.
    for s in &series {
        let stroke = s.style.colour.stroke_width(s.style.width);
        if s.style.dashed {
            chart
                .draw_series(DashedLineSeries::new(
                    s.points.iter().copied(),
                    DASH.0,
                    DASH.1,
                    stroke,
                ))
                .map_err(plot_error)?;
        } else {
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), stroke))
                .map_err(plot_error)?;
        }
        legend.push((s.label.clone(), s.style));
    }
    for s in &series {
        if let Some(marker) = s.style.marker {
            draw_markers!(
                ChartContext::draw_series,
                &mut chart,
                marker,
                s.points.iter().copied(),
                s.style.colour
            )?;
        }
    }
    if let Some(lines) = no_ok_note(reports) {
        draw_centred_note(&chart.plotting_area().strip_coord_spec(), &lines)?;
    }
    if with_legend {
        draw_legend(&legend_area, &legend, &coincidence_notes(&series))?;
    }
    Ok(())
}

/// `lines` in a framed box in the middle of `area`.
fn draw_centred_note<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    lines: &[String],
) -> anyhow::Result<()> {
    let font = TextStyle::from((FAMILY, 18).into_font());
    let (w, h) = area.dim_in_pixel();
    let row = 26i32;
    let text_w = lines
        .iter()
        .map(|l| area.estimate_text_size(l, &font).map_or(0, |(w, _)| w))
        .max()
        .unwrap_or(0) as i32;
    let box_h = row * lines.len() as i32 + 16;
    let (cx, cy) = (w as i32 / 2, h as i32 / 2);
    let (x0, y0) = (cx - text_w / 2 - 14, cy - box_h / 2);
    let corners = [(x0, y0), (cx + text_w / 2 + 14, y0 + box_h)];
    area.draw(&Rectangle::new(corners, WHITE.filled()))
        .map_err(plot_error)?;
    area.draw(&Rectangle::new(corners, BLACK.stroke_width(1)))
        .map_err(plot_error)?;
    let style = font.pos(Pos::new(HPos::Center, VPos::Center));
    for (k, line) in lines.iter().enumerate() {
        let y = y0 + 8 + row / 2 + row * k as i32;
        area.draw(&Text::new(line.as_str(), (cx, y), style.clone()))
            .map_err(plot_error)?;
    }
    Ok(())
}

fn draw_times<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    reports: &[MethodReport],
    with_legend: bool,
) -> anyhow::Result<()> {
    let (w, _) = area.dim_in_pixel();
    let (area, legend_area) = area.split_horizontally(w.saturating_sub(LEGEND_WIDTH));
    let times = reports.iter().flat_map(|r| {
        r.estimates
            .iter()
            .filter_map(|f| Some(f.ms.as_ref()?.0.total_ms))
    });
    let mut chart = ChartBuilder::on(&area)
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
    let mut legend = Vec::new();
    for report in reports {
        let style = SeriesStyle {
            colour: method_colour(report.method),
            width: 2,
            dashed: false,
            marker: None,
        };
        let points: Vec<(f64, f64)> = report
            .estimates
            .iter()
            .filter_map(|f| Some((f.index as f64, f.ms.as_ref()?.0.total_ms)))
            .collect();
        // A line needs two points: a single frame is drawn as a marker.
        let markers = if points.len() == 1 { &points[..] } else { &[] };
        chart
            .draw_series(
                markers
                    .iter()
                    .map(|&p| Circle::new(p, 4, style.colour.filled())),
            )
            .map_err(plot_error)?;
        chart
            .draw_series(LineSeries::new(
                points,
                style.colour.stroke_width(style.width),
            ))
            .map_err(plot_error)?;
        legend.push((format!("{} time", report.method.name()), style));
    }
    if with_legend {
        draw_legend(&legend_area, &legend, &[])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{FrameDetails, FrameResult, Timings, TrackedJson};
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

    /// Frame `index` with `slope` (ok) or `status`, a tracked slope and a
    /// truth of 16°.
    fn frame(index: u64, slope: Option<f64>, tracked: Option<f64>) -> FrameResult {
        FrameResult {
            index,
            status: if slope.is_some() {
                "ok"
            } else {
                "no_inclined_plane"
            },
            slope_deg: slope,
            std_deg: None,
            distance_m: None,
            truth_deg: Some(16.0),
            ms: Some(Timings(StageTimings {
                total_ms: 20.0 + index as f64,
                stages: Vec::new(),
            })),
            error: None,
            details: FrameDetails {
                tracked: tracked.map(|t| TrackedJson {
                    slope_deg: Some(t),
                    std_deg: None,
                    frames: 1,
                    accepted: true,
                }),
                ..FrameDetails::default()
            },
        }
    }

    fn report(method: SlopeMethod, slopes: &[f64], tracked: Option<f64>) -> MethodReport {
        let frames = slopes
            .iter()
            .enumerate()
            .map(|(k, &s)| frame(k as u64, Some(s), tracked))
            .collect();
        MethodReport::new("synthetic".into(), method, frames)
    }

    /// Where the slope panel ends (the time panel begins), pixels.
    fn slope_panel_bottom() -> usize {
        (PLOT_SIZE.1 as f64 * 0.62) as usize
    }

    fn pixel(image: &ColorImage, x: usize, y: usize) -> [u8; 3] {
        image.data[y * image.width as usize + x]
    }

    fn rgb(c: RGBColor) -> [u8; 3] {
        [c.0, c.1, c.2]
    }

    /// Slopes over the whole range (the highest in the last frames, where
    /// the legend box was): every pixel the legends change is in the column
    /// right of the plotting areas, none in a chart.
    #[test]
    fn the_legend_hides_no_data() {
        let slopes: Vec<f64> = (0..12).map(|k| 15.0 + 0.1 * k as f64).collect();
        let reports = [
            report(SlopeMethod::Paper, &slopes, Some(15.5)),
            report(SlopeMethod::Tls, &slopes[..6], None),
        ];
        let with = draw_plot("t", &reports, true).expect("plot");
        let without = draw_plot("t", &reports, false).expect("plot");
        let w = PLOT_SIZE.0 as usize;
        let column = w - LEGEND_WIDTH as usize;
        let changed: Vec<usize> = (0..with.data.len())
            .filter(|&i| with.data[i] != without.data[i])
            .map(|i| i % w)
            .collect();
        assert!(changed.len() > 500, "{} pixels of legend", changed.len());
        assert!(
            changed.iter().all(|&x| x >= column),
            "a legend pixel at x {:?} left of {column}",
            changed.iter().min()
        );
    }

    /// The legend's samples look like their lines: the truth a thick grey
    /// line, a method's per-frame slope a thin line with its marker, its
    /// tracked slope a dashed line of two pixels.
    #[test]
    fn legend_samples_look_like_their_lines() {
        let reports = [report(SlopeMethod::Paper, &[16.1, 16.2, 16.0], Some(16.1))];
        let image = plot_recording("t", &reports).expect("plot");
        let x0 = PLOT_SIZE.0 as usize - LEGEND_WIDTH as usize + LEGEND_X as usize;
        // Down the sample's first pixels: runs of colour, one per entry.
        let mut runs: Vec<([u8; 3], usize, usize)> = Vec::new();
        for y in 0..slope_panel_bottom() {
            let p = pixel(&image, x0 + 1, y);
            if p == [255, 255, 255] {
                continue;
            }
            match runs.last_mut() {
                Some((c, start, len)) if *c == p && *start + *len == y => *len += 1,
                _ => runs.push((p, y, 1)),
            }
        }
        let paper = rgb(method_colour(SlopeMethod::Paper));
        let colours: Vec<[u8; 3]> = runs.iter().map(|r| r.0).collect();
        assert_eq!(colours, [rgb(TRUTH_GREY), paper, paper], "{runs:?}");
        let (truth, slope, tracked) = (runs[0], runs[1], runs[2]);
        // Thin per-frame, thicker tracked, thickest truth; the truth's
        // sample as thick as its line in the chart (between frames 0 and 1).
        assert!(slope.2 < tracked.2 && tracked.2 < truth.2, "{runs:?}");
        let in_chart = (0..slope_panel_bottom())
            .filter(|&y| pixel(&image, x0 / 4, y) == rgb(TRUTH_GREY))
            .count();
        assert_eq!(truth.2, in_chart, "{runs:?}");
        // The per-frame sample carries the marker (taller in its middle).
        let middle = x0 + LEGEND_SAMPLE as usize / 2;
        let marker = (slope.1 - 6..slope.1 + 6)
            .filter(|&y| pixel(&image, middle, y) == paper)
            .count();
        assert!(marker >= 5, "{marker} rows of marker");
        // The tracked sample is dashed: colour, a gap, colour again.
        let row: Vec<bool> = (x0..x0 + LEGEND_SAMPLE as usize)
            .map(|x| pixel(&image, x, tracked.1) == paper)
            .collect();
        let starts = row.windows(2).filter(|w| !w[0] && w[1]).count();
        assert!(starts >= 2, "dashes {row:?}");
    }

    /// least-squares and tls agreeing on every frame: both are seen (the
    /// square markers around the triangles) and a note says they coincide.
    #[test]
    fn methods_that_agree_are_both_seen() {
        let slopes = [16.05, 16.06, 16.05, 16.04];
        let reports = [
            report(SlopeMethod::LeastSquares, &slopes, None),
            report(SlopeMethod::Tls, &slopes, None),
        ];
        let image = plot_recording("t", &reports).expect("plot");
        let column = PLOT_SIZE.0 as usize - LEGEND_WIDTH as usize;
        let count = |c: RGBColor| {
            (0..slope_panel_bottom())
                .flat_map(|y| (0..column).map(move |x| (x, y)))
                .filter(|&(x, y)| pixel(&image, x, y) == rgb(c))
                .count()
        };
        let (least, tls) = (
            count(method_colour(SlopeMethod::LeastSquares)),
            count(method_colour(SlopeMethod::Tls)),
        );
        assert!(least > 4 * 20 && tls > 4 * 20, "{least} {tls}");
        let notes = coincidence_notes(&slope_series(&reports));
        assert_eq!(
            notes,
            ["tls hides least-squares: within 0.01° on every frame"]
        );
        // A difference beyond 0.01° on one frame: no note.
        let other = [
            report(SlopeMethod::LeastSquares, &slopes, None),
            report(SlopeMethod::Tls, &[16.05, 16.06, 16.05, 16.1], None),
        ];
        assert!(coincidence_notes(&slope_series(&other)).is_empty());
    }

    /// A recording without an ok frame: the slope panel says so, with the
    /// statuses counted (it was an empty 0-1° panel with a legend).
    #[test]
    fn a_recording_without_an_ok_frame_says_so() {
        let frames = vec![frame(0, None, None), frame(1, None, None)];
        let one = MethodReport::new("flat".into(), SlopeMethod::Paper, frames.clone());
        assert_eq!(
            no_ok_note(std::slice::from_ref(&one)),
            Some(vec!["no ok frame: no_inclined_plane x2".to_string()])
        );
        let two = [
            one.clone(),
            MethodReport::new("flat".into(), SlopeMethod::Tls, frames),
        ];
        assert_eq!(
            no_ok_note(&two),
            Some(vec![
                "no ok frame:".to_string(),
                "paper: no_inclined_plane x2".to_string(),
                "tls: no_inclined_plane x2".to_string(),
            ])
        );
        let ok = report(SlopeMethod::Paper, &[16.0], None);
        assert_eq!(no_ok_note(&[ok, one.clone()]), None);
        // In the picture: dark text in the middle of the slope chart.
        let image = plot_recording("flat", &[one]).expect("plot");
        let column = PLOT_SIZE.0 as usize - LEGEND_WIDTH as usize;
        let (cx, cy) = (column / 2, slope_panel_bottom() / 2);
        let dark = (cy - 30..cy + 30)
            .flat_map(|y| (cx - 150..cx + 150).map(move |x| (x, y)))
            .filter(|&(x, y)| pixel(&image, x, y).iter().all(|&c| c < 80))
            .count();
        assert!(dark > 100, "{dark} dark pixels");
    }

    #[test]
    fn notes_wrap_at_spaces() {
        let fits = |t: &str| t.len() <= 10;
        assert_eq!(wrap("aaa bbb ccc ddd", fits), ["aaa bbb", "ccc ddd"]);
        assert_eq!(
            wrap("averyveryverylongword x", fits),
            ["averyveryverylongword", "x"]
        );
        assert!(wrap("", fits).is_empty());
    }
}
