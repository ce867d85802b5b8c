//! The two panels: the slopes over the frames, and the time per frame;
//! in each, an x under every frame that is not `ok`.

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::*;

/// Draws each of `elements` on `area` (pixel coordinates).
pub(super) fn draw_each<DB: DrawingBackend, E>(
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

/// Draws `points` as a line in `style` (dashed or not; the markers apart;
/// nothing for width 0).
pub(super) fn draw_line<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    points: Vec<(i32, i32)>,
    style: SeriesStyle,
) -> anyhow::Result<()> {
    if style.width == 0 {
        return Ok(());
    }
    let stroke = style.colour.stroke_width(style.width);
    if style.dashed {
        area.draw(&DashedPathElement::new(points, DASH.0, DASH.1, stroke))
    } else {
        area.draw(&PathElement::new(points, stroke))
    }
    .map_err(plot_error)
}

/// Width of the y label area, pixels: the widest tick label ("1000.0" at
/// 15 px) beside the axis name, with no overlap (at 56 "time per frame
/// (ms)" was drawn over "120.0").
pub(super) const Y_LABEL_AREA: u32 = 84;

/// A panel over the frames, in frame and value coordinates.
type FrameChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// A panel over the frames: frames along x (whole-frame ticks), `y` up
/// (`y_desc`), its mesh drawn.
fn frame_chart<'a, DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    reports: &[MethodReport],
    y: std::ops::Range<f64>,
    y_desc: &str,
) -> anyhow::Result<FrameChart<'a, DB>> {
    let frames = frame_range(reports);
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(frames.clone(), y)
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .x_labels(frame_tick_count(&frames))
        .x_label_formatter(&|x| frame_tick_label(*x))
        .y_desc(y_desc)
        .label_style((FAMILY, 15))
        .draw()
        .map_err(plot_error)?;
    Ok(chart)
}

/// Draws the slope panel: the ground truth, each method's slopes (lines,
/// then markers), a note when no frame is ok, and the legend if asked.
pub(super) fn draw_slopes<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    reports: &[MethodReport],
    with_legend: bool,
) -> anyhow::Result<()> {
    let (area, legend_area) = split_legend(area);
    let series = slope_series(reports);
    let truth = signed_truth(reports);
    let slopes = series
        .iter()
        .flat_map(|s| s.points().map(|p| p.1))
        .chain(truth.map(|t| t.1));
    let y = value_range(slopes, None);
    let mut chart = frame_chart(&area, reports, y.clone(), "slope (degrees)")?;
    let mut legend = Vec::new();
    if let Some((truth, y)) = truth {
        legend.push(draw_truth(&mut chart, reports, truth, y)?);
    }
    // Lines first, then every marker, so that no line hides a marker.
    legend.extend(draw_series_lines(&mut chart, &series)?);
    draw_series_markers(&mut chart, &series)?;
    legend.extend(draw_not_ok(&mut chart, reports, y.start)?);
    if let Some(lines) = no_ok_note(reports) {
        draw_centred_note(&chart.plotting_area().strip_coord_spec(), &lines)?;
    }
    if with_legend {
        draw_legend(&legend_area, &legend, &coincidence_notes(&series))?;
    }
    Ok(())
}

/// The recording's ground-truth slope and the height to draw it at: signed
/// as the first method's median slope (the truth is given unsigned).
fn signed_truth(reports: &[MethodReport]) -> Option<(f64, f64)> {
    reports.iter().find_map(|r| r.truth_deg).map(|truth| {
        let sign = reports
            .iter()
            .find_map(|r| r.summary.median_slope_deg)
            .map_or(1.0, f64::signum);
        (truth, sign * truth)
    })
}

/// Draws the ground truth as a grey line at `y` across the frames; returns
/// its legend entry.
fn draw_truth<DB: DrawingBackend>(
    chart: &mut FrameChart<'_, DB>,
    reports: &[MethodReport],
    truth: f64,
    y: f64,
) -> anyhow::Result<(String, SeriesStyle)> {
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
    Ok((format!("truth {truth:.1}°"), style))
}

/// Draws the lines of each of `series` (dashed or not, no markers), one
/// per run, so that no line crosses a frame without a value; a run of one
/// point without markers is a dot. Returns their legend entries, in order.
fn draw_series_lines<DB: DrawingBackend>(
    chart: &mut FrameChart<'_, DB>,
    series: &[Series],
) -> anyhow::Result<Vec<(String, SeriesStyle)>> {
    let mut legend = Vec::with_capacity(series.len());
    for s in series {
        let stroke = s.style.colour.stroke_width(s.style.width);
        for run in &s.runs {
            if let ([point], None) = (&run[..], s.style.marker) {
                let dot = Circle::new(*point, s.style.width + 1, s.style.colour.filled());
                chart.draw_series([dot]).map_err(plot_error)?;
            } else if s.style.dashed {
                let line = DashedLineSeries::new(run.iter().copied(), DASH.0, DASH.1, stroke);
                chart.draw_series(line).map_err(plot_error)?;
            } else {
                let line = LineSeries::new(run.iter().copied(), stroke);
                chart.draw_series(line).map_err(plot_error)?;
            }
        }
        legend.push((s.label.clone(), s.style));
    }
    Ok(legend)
}

/// Pixels between the rows of x's under the frames that are not `ok` (one
/// row per method, the first at the bottom).
const NOT_OK_ROW: i32 = 11;

/// Draws an x in the method's colour under each frame of `reports` that is
/// not `ok`, at the bottom of the panel (`y_bottom`), a row per method;
/// returns the legend entry "not ok" when there is one.
fn draw_not_ok<DB: DrawingBackend>(
    chart: &mut FrameChart<'_, DB>,
    reports: &[MethodReport],
    y_bottom: f64,
) -> anyhow::Result<Option<(String, SeriesStyle)>> {
    let mut any = false;
    for (row, report) in reports.iter().enumerate() {
        let frames = not_ok_frames(report);
        any |= !frames.is_empty();
        let style = method_colour(report.method).stroke_width(2);
        let dy = -7 - NOT_OK_ROW * row as i32;
        chart
            .draw_series(
                frames
                    .into_iter()
                    .map(|x| EmptyElement::at((x, y_bottom)) + Cross::new((0, dy), 4, style)),
            )
            .map_err(plot_error)?;
    }
    let style = SeriesStyle {
        colour: NOTE_GREY,
        width: 0,
        dashed: false,
        marker: Some(Marker::Cross),
    };
    Ok(any.then(|| ("not ok".to_string(), style)))
}

/// Draws the markers of each of `series` that has some.
fn draw_series_markers<DB: DrawingBackend>(
    chart: &mut FrameChart<'_, DB>,
    series: &[Series],
) -> anyhow::Result<()> {
    for s in series {
        if let Some(marker) = s.style.marker {
            draw_markers!(
                ChartContext::draw_series,
                &mut *chart,
                marker,
                s.points(),
                s.style.colour
            )?;
        }
    }
    Ok(())
}

/// `lines` in a framed box in the middle of `area`.
pub(super) fn draw_centred_note<DB: DrawingBackend>(
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

pub(super) fn draw_times<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    reports: &[MethodReport],
    with_legend: bool,
) -> anyhow::Result<()> {
    let (area, legend_area) = split_legend(area);
    let times = reports.iter().flat_map(|r| {
        r.estimates
            .iter()
            .filter_map(|f| Some(f.ms.as_ref()?.0.total_ms))
    });
    let y = value_range(times, Some(0.0));
    let mut chart = frame_chart(&area, reports, y.clone(), "time per frame (ms)")?;
    let series: Vec<Series> = reports
        .iter()
        .map(|report| Series {
            label: format!("{} time", report.method.name()),
            style: SeriesStyle {
                colour: method_colour(report.method),
                width: 2,
                dashed: false,
                marker: None,
            },
            runs: runs(report.estimates.iter().map(|f| {
                let ms = f.ms.as_ref().map(|t| t.0.total_ms);
                (f.index as f64, ms)
            })),
        })
        .collect();
    let mut legend = draw_series_lines(&mut chart, &series)?;
    legend.extend(draw_not_ok(&mut chart, reports, y.start)?);
    if with_legend {
        draw_legend(&legend_area, &legend, &[])?;
    }
    Ok(())
}
