//! The legend column beside each panel, and its notes wrapped to fit.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::*;

/// Pixel layout of the legend column: left margin, top, row height and
/// the width of a sample line.
pub(super) const LEGEND_X: i32 = 10;
pub(super) const LEGEND_TOP: i32 = 24;
pub(super) const LEGEND_ROW: i32 = 26;
pub(super) const LEGEND_SAMPLE: i32 = 40;
pub(super) const LEGEND_FONT: u32 = 15;
/// Width of the column right of each panel that holds its legend (outside
/// the plotting area, so that it hides no data).
pub const LEGEND_WIDTH: u32 = 240;

/// A panel's area split into its chart (left) and its legend column
/// ([`LEGEND_WIDTH`], right).
pub(super) fn split_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
) -> (
    DrawingArea<DB, plotters::coord::Shift>,
    DrawingArea<DB, plotters::coord::Shift>,
) {
    let (w, _) = area.dim_in_pixel();
    area.split_horizontally(w.saturating_sub(LEGEND_WIDTH))
}

/// The legend in its own column: per entry a sample drawn like its line
/// (same width, dash and marker) and its label; then `notes`, wrapped.
pub(super) fn draw_legend<DB: DrawingBackend>(
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
pub(super) fn wrap(text: &str, fits: impl Fn(&str) -> bool) -> Vec<String> {
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
