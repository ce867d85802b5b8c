//! Text in pictures: the bundled DejaVu Sans (`assets/DejaVuSans.ttf`,
//! Bitstream Vera licence in `assets/DejaVuSans-LICENSE.txt`) rasterised
//! with `ab_glyph` into a [`ColorImage`], anti-aliased.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use slope_sensor::recording::ColorImage;

/// The bundled font file.
pub const FONT_TTF: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// The bundled font (`None` only if the file in the binary were corrupt,
/// which the tests rule out: text is then left out, never a panic).
pub fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_TTF).ok())
        .as_ref()
}

/// Width of `text` at `px` pixels, in pixels.
pub fn text_width(text: &str, px: f32) -> f32 {
    let Some(font) = font() else {
        return 0.0;
    };
    let scaled = font.as_scaled(PxScale::from(px));
    let mut width = 0.0;
    let mut previous = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = previous {
            width += scaled.kern(p, id);
        }
        width += scaled.h_advance(id);
        previous = Some(id);
    }
    width
}

/// Draws `text` with its top-left corner at `(x, y)`, `px` pixels high, in
/// `color`; pixels outside the image are skipped. Returns the x after it.
pub fn draw_text(
    image: &mut ColorImage,
    x: f32,
    y: f32,
    px: f32,
    color: [u8; 3],
    text: &str,
) -> f32 {
    let Some(font) = font() else {
        return x;
    };
    let scaled = font.as_scaled(PxScale::from(px));
    let baseline = y + scaled.ascent();
    let mut caret = x;
    let mut previous = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = previous {
            caret += scaled.kern(p, id);
        }
        let glyph = id.with_scale_and_position(px, ab_glyph::point(caret, baseline));
        caret += scaled.h_advance(id);
        previous = Some(id);
        let Some(outline) = font.outline_glyph(glyph) else {
            continue;
        };
        let bounds = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let u = bounds.min.x as i64 + i64::from(gx);
            let v = bounds.min.y as i64 + i64::from(gy);
            blend(image, u, v, color, coverage);
        });
    }
    caret
}

/// Fills the rectangle `[x0, x1) x [y0, y1)` (clipped to the image).
pub fn fill_rect(image: &mut ColorImage, x0: i64, y0: i64, x1: i64, y1: i64, color: [u8; 3]) {
    let (w, h) = (i64::from(image.width), i64::from(image.height));
    for v in y0.max(0)..y1.min(h) {
        for u in x0.max(0)..x1.min(w) {
            image.data[(v * w + u) as usize] = color;
        }
    }
}

/// Text on a filled box with a small margin, top-left at `(x, y)`.
pub fn draw_label(
    image: &mut ColorImage,
    x: f32,
    y: f32,
    px: f32,
    fg: [u8; 3],
    bg: [u8; 3],
    text: &str,
) {
    let margin = (px * 0.25).round();
    let width = text_width(text, px);
    fill_rect(
        image,
        (x - margin) as i64,
        (y - margin) as i64,
        (x + width + margin) as i64,
        (y + px * 1.2 + margin) as i64,
        bg,
    );
    draw_text(image, x, y, px, fg, text);
}

/// Mixes `color` into pixel `(u, v)` with weight `coverage` (0..1).
fn blend(image: &mut ColorImage, u: i64, v: i64, color: [u8; 3], coverage: f32) {
    if u < 0 || v < 0 || u >= i64::from(image.width) || v >= i64::from(image.height) {
        return;
    }
    let i = (v * i64::from(image.width) + u) as usize;
    let a = coverage.clamp(0.0, 1.0);
    let pixel = &mut image.data[i];
    for (c, &t) in pixel.iter_mut().zip(&color) {
        *c = (f32::from(*c) * (1.0 - a) + f32::from(t) * a).round() as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_font_draws_text_where_asked() {
        assert!(font().is_some(), "the bundled font must parse");
        let mut image = ColorImage::new(200, 40);
        let end = draw_text(&mut image, 10.0, 5.0, 20.0, [255, 255, 255], "slope 16.0°");
        assert!((end - 10.0 - text_width("slope 16.0°", 20.0)).abs() < 1e-3);
        let lit: Vec<(u32, u32)> = (0..image.height)
            .flat_map(|v| (0..image.width).map(move |u| (u, v)))
            .filter(|&(u, v)| image.get(u, v).is_some_and(|p| p[0] > 128))
            .collect();
        assert!(lit.len() > 100, "{} pixels lit", lit.len());
        // Every lit pixel lies in the text's box; text far off the image is
        // clipped, not a panic.
        assert!(lit
            .iter()
            .all(|&(u, v)| u >= 10 && (u as f32) <= end + 1.0 && (3..30).contains(&v)));
        draw_text(&mut image, -500.0, -500.0, 20.0, [1, 2, 3], "off the image");
        draw_text(&mut image, 190.0, 35.0, 20.0, [1, 2, 3], "at the edge");
    }
}
