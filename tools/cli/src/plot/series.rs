//! The plotted series: each method's per-frame and tracked slope and the
//! truth, how each is drawn (in runs of consecutive frames with a value,
//! and the frames that are not `ok`), and the notes on series that
//! coincide or that have no `ok` frame.

use plotters::prelude::*;
use slope_ipc_types::EstimateStatus;

use super::*;

/// How one series is drawn: in the chart and in its legend sample alike,
/// so that the sample looks like the line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SeriesStyle {
    pub(super) colour: RGBColor,
    /// Line width, pixels; 0: no line (a marker only).
    pub(super) width: u32,
    pub(super) dashed: bool,
    pub(super) marker: Option<Marker>,
}

/// The marker of a method's per-frame slopes: a shape per method, so that
/// methods that agree (least-squares and tls often do to 0.01°) are both
/// seen (the hollow square is larger than the triangle drawn in it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Marker {
    Disc,
    HollowSquare,
    Triangle,
    /// An x: a frame that is not `ok`.
    Cross,
}

/// Dash and gap of the tracked slope's line, pixels.
pub(super) const DASH: (u32, u32) = (8, 5);
/// Grey of the truth line.
pub(super) const TRUTH_GREY: RGBColor = RGBColor(120, 120, 120);
/// Colour of the notes under the legend.
pub(super) const NOTE_GREY: RGBColor = RGBColor(60, 60, 60);
/// Two series closer than this on every frame are said to coincide.
pub(super) const SAME_DEG: f64 = 0.01;

pub(super) fn method_marker(method: slope_ipc_types::SlopeMethod) -> Marker {
    [Marker::Disc, Marker::HollowSquare, Marker::Triangle][method as usize % 3]
}

/// One line of the slope panel with its legend label.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Series {
    pub(super) label: String,
    pub(super) style: SeriesStyle,
    /// The points, in runs of consecutive frames with a value (see
    /// [`runs`]): each run is a line of its own.
    pub(super) runs: Vec<Vec<(f64, f64)>>,
}

impl Series {
    /// Every point of every run, in frame order.
    pub(super) fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.runs.iter().flatten().copied()
    }
}

/// `values` (frame, value if any) in runs of consecutive frames with a
/// value: a frame without one ends a run, so that a line drawn per run
/// never joins the frames on either side of a gap. A run may be one point.
pub(super) fn runs(values: impl IntoIterator<Item = (f64, Option<f64>)>) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut run = Vec::new();
    for (x, value) in values {
        match value {
            Some(y) => run.push((x, y)),
            None if !run.is_empty() => out.push(std::mem::take(&mut run)),
            None => {}
        }
    }
    if !run.is_empty() {
        out.push(run);
    }
    out
}

/// The frames of `report` whose status is not `ok` (a bad frame, no
/// inclined plane, ...).
pub(super) fn not_ok_frames(report: &MethodReport) -> Vec<f64> {
    report
        .estimates
        .iter()
        .filter(|f| f.status != EstimateStatus::Ok.name())
        .map(|f| f.index as f64)
        .collect()
}

/// The series of the slope panel, in drawing order: per method its
/// per-frame slope (thin, markers) and its tracked slope (dashed).
pub(super) fn slope_series(reports: &[MethodReport]) -> Vec<Series> {
    let mut out = Vec::new();
    for report in reports {
        let colour = method_colour(report.method);
        let points = runs(
            report
                .estimates
                .iter()
                .map(|f| (f.index as f64, f.slope_deg)),
        );
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
            runs: points,
        });
        let tracked = runs(report.estimates.iter().map(|f| {
            let slope = f.details.tracked.as_ref().and_then(|t| t.slope_deg);
            (f.index as f64, slope)
        }));
        if !tracked.is_empty() {
            out.push(Series {
                label: format!("{} tracked", report.method.name()),
                style: SeriesStyle {
                    colour,
                    width: 2,
                    dashed: true,
                    marker: None,
                },
                runs: tracked,
            });
        }
    }
    out
}

/// Notes on series drawn over each other: two series of the same kind
/// (both per-frame, or both tracked) with points on the same frames, within
/// [`SAME_DEG`] on each, the later one hiding the earlier's line ("tls
/// hides least-squares: ...").
pub(super) fn coincidence_notes(series: &[Series]) -> Vec<String> {
    let mut notes = Vec::new();
    for (i, a) in series.iter().enumerate() {
        for b in &series[i + 1..] {
            let same = a.style.dashed == b.style.dashed
                && a.points().next().is_some()
                && a.points().count() == b.points().count()
                && a.points()
                    .zip(b.points())
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
            Marker::Cross => $draw(
                $target,
                $points
                    .map(|p| EmptyElement::at(p) + Cross::new((0, 0), 4, colour.stroke_width(2))),
            )
            .map(|_| ())
            .map_err(plot_error),
        }
    }};
}
