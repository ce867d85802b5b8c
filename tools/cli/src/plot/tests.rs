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

#[test]
fn a_series_is_split_into_runs_at_frames_without_a_value() {
    let at = |k: u32, y: Option<f64>| (f64::from(k), y);
    let values = [
        at(0, Some(1.0)),
        at(1, Some(2.0)),
        at(2, None),
        at(3, Some(3.0)),
        at(4, None),
        at(5, None),
        at(6, Some(4.0)),
        at(7, Some(5.0)),
    ];
    assert_eq!(
        runs(values),
        [
            vec![(0.0, 1.0), (1.0, 2.0)],
            vec![(3.0, 3.0)],
            vec![(6.0, 4.0), (7.0, 5.0)],
        ]
    );
    // Gaps at either end open or close no run; no value, no run.
    assert_eq!(
        runs([at(0, None), at(1, Some(1.0)), at(2, None)]),
        [vec![(1.0, 1.0)]]
    );
    assert!(runs([at(0, None), at(1, None)]).is_empty());
    assert!(runs([]).is_empty());
}

/// Frames 0 to 4 at 16° and 20 ms, but frame 2: a bad frame (no slope,
/// no time).
fn report_with_a_bad_frame() -> MethodReport {
    let frames = (0..5)
        .map(|k| {
            let mut f = frame(k, Some(16.0), None);
            f.ms = Some(Timings(StageTimings {
                total_ms: 20.0,
                stages: Vec::new(),
            }));
            if k == 2 {
                f.status = "bad_frame";
                f.slope_deg = None;
                f.ms = None;
            }
            f
        })
        .collect();
    MethodReport::new("gap".into(), SlopeMethod::Paper, frames)
}

/// In `rows` of the chart (left of the legend column): the row with the
/// most pixels of `colour` (the line), the widest run of other pixels
/// between its first and last such pixel (the gap) and the middle of
/// that run.
fn line_gap(
    image: &ColorImage,
    rows: std::ops::Range<usize>,
    colour: [u8; 3],
) -> (usize, usize, usize) {
    let column = PLOT_SIZE.0 as usize - LEGEND_WIDTH as usize;
    let count = |y: usize| {
        (0..column)
            .filter(|&x| pixel(image, x, y) == colour)
            .count()
    };
    let line = rows.max_by_key(|&y| count(y)).expect("rows");
    let xs: Vec<usize> = (0..column)
        .filter(|&x| pixel(image, x, line) == colour)
        .collect();
    let (gap, middle) = xs
        .windows(2)
        .map(|w| (w[1] - w[0] - 1, (w[0] + w[1]) / 2))
        .max()
        .unwrap_or((0, 0));
    (line, gap, middle)
}

/// A frame that is not ok breaks the slope and time lines (they joined
/// frame 1 to frame 3) and gets an x at the bottom of each panel.
#[test]
fn a_frame_that_is_not_ok_breaks_the_lines_and_is_marked() {
    let reports = [report_with_a_bad_frame()];
    let image = plot_recording("gap", &reports).expect("plot");
    let paper = rgb(method_colour(SlopeMethod::Paper));
    let panels = [
        0..slope_panel_bottom(),
        slope_panel_bottom()..PLOT_SIZE.1 as usize,
    ];
    for rows in panels {
        let bottom = rows.end;
        let (line, gap, middle) = line_gap(&image, rows.clone(), paper);
        // About a frame's width (more than 100 pixels) without the line.
        assert!(
            gap > 100,
            "rows {rows:?}: gap of {gap} pixels in row {line}"
        );
        // The x under frame 2, below the line.
        let cross = (line + 5..bottom)
            .flat_map(|y| (middle - 5..=middle + 5).map(move |x| (x, y)))
            .filter(|&(x, y)| pixel(&image, x, y) == paper)
            .count();
        assert!(cross >= 8, "rows {rows:?}: {cross} pixels of the x");
        // The legend's "not ok" sample: a grey x (nothing else in the
        // samples' columns is that grey).
        let x0 = PLOT_SIZE.0 as usize - LEGEND_WIDTH as usize + LEGEND_X as usize;
        let sample = rows
            .flat_map(|y| (x0..x0 + LEGEND_SAMPLE as usize).map(move |x| (x, y)))
            .filter(|&(x, y)| pixel(&image, x, y) == rgb(NOTE_GREY))
            .count();
        assert!(sample >= 8, "{sample} pixels of the legend's x");
    }
}

/// Times of 120 to 1200 ms: in each panel's y label area, the axis name
/// and the tick labels are apart (a white column between them; at 56
/// pixels "time per frame (ms)" was drawn over "120.0").
#[test]
fn the_y_axis_name_is_clear_of_the_tick_labels() {
    let frames = [120.0, 1200.0, 600.0]
        .iter()
        .enumerate()
        .map(|(k, &ms)| {
            let mut f = frame(k as u64, Some(16.0 + k as f64), None);
            f.ms = Some(Timings(StageTimings {
                total_ms: ms,
                stages: Vec::new(),
            }));
            f
        })
        .collect();
    let reports = [MethodReport::new("slow".into(), SlopeMethod::Paper, frames)];
    let image = plot_recording("slow", &reports).expect("plot");
    // Left of the axis line (the chart's margin is 12 pixels), above the
    // x tick labels.
    let columns = 0..12 + Y_LABEL_AREA as usize - 1;
    let bottom = slope_panel_bottom();
    for rows in [20..bottom - 60, bottom + 10..PLOT_SIZE.1 as usize - 60] {
        let dark: Vec<bool> = columns
            .clone()
            .map(|x| {
                rows.clone()
                    .any(|y| pixel(&image, x, y).iter().all(|&c| c < 128))
            })
            .collect();
        // The first run of dark columns is the axis name (15 px text on
        // its side), then white columns, then the tick labels.
        let text: String = dark.iter().map(|&d| if d { '#' } else { '.' }).collect();
        let name_start = text.find('#').expect("an axis name");
        let name_end = name_start + text[name_start..].find('.').expect("a gap");
        let labels_start = name_end + text[name_end..].find('#').expect("tick labels");
        assert!(name_end - name_start <= 20, "rows {rows:?}: {text}");
        assert!(labels_start - name_end >= 3, "rows {rows:?}: {text}");
    }
}
