//! The overlay of one frame (`slope-eval --render`): the depth image in
//! grey, every segmented plane in its own colour (the ground red, the
//! inclined plane blue, the others muted), "ground" and "inclined" written
//! on their planes, the normals the paper method sampled as dots (kept:
//! green, dropped by the cosine k-means: yellow), and a caption under the
//! image with the slope, its spread, the confidence and the status.
//!
//! [`render_overlay`] is pure (data in, image out); drawn at
//! [`SCALE`] times the depth resolution so that the text stays readable.

use slope_ipc_types::CloudPoint;
use slope_sensor::recording::ColorImage;

use crate::render::{grey_levels, GROUND_TINT, INCLINED_TINT};
use crate::text::{draw_label, draw_text, fill_rect, text_width};

/// Output pixels per depth pixel, in each direction.
pub const SCALE: u32 = 2;
/// Colour of a kept normal's dot.
pub const KEPT_NORMAL: [u8; 3] = [40, 230, 60];
/// Colour of a dropped normal's dot.
pub const DROPPED_NORMAL: [u8; 3] = [255, 220, 0];
/// Colours of the other planes, in the order they were segmented.
pub const OTHER_PLANES: [[u8; 3]; 6] = [
    [150, 110, 200],
    [90, 170, 160],
    [200, 150, 90],
    [170, 90, 130],
    [120, 160, 90],
    [110, 130, 180],
];
/// Share of a plane's colour in its pixels (the rest is the depth grey).
const PLANE_WEIGHT: f32 = 0.6;
/// Caption text height, output pixels.
const TEXT_PX: f32 = 22.0;
/// At most this many kept and this many dropped normals are drawn (an even
/// share of each).
const KEPT_DOTS: usize = 700;
const DROPPED_DOTS: usize = 1200;
const CAPTION_BG: [u8; 3] = [20, 20, 24];
const CAPTION_FG: [u8; 3] = [240, 240, 240];
/// A label's box stays this many depth pixels inside the image (where the
/// image is large enough), so that it is read whole.
pub const LABEL_EDGE: usize = 4;
/// A label whose box lies at least this share on its plane fits: among
/// the pixels where it fits, the one nearest the plane's centroid is taken.
const LABEL_COVERAGE: f64 = 0.9;

/// What a plane is in the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Ground,
    Inclined,
    Other,
}

/// One normal the paper method sampled: its pixel and whether the cosine
/// k-means kept it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NormalDot {
    pub pixel: u32,
    pub kept: bool,
}

/// Everything one overlay shows.
#[derive(Debug, Clone)]
pub struct Overlay<'a> {
    pub points: &'a [CloudPoint],
    pub width: u32,
    pub height: u32,
    /// Every segmented plane: its inlier pixels and its role.
    pub planes: Vec<(&'a [u32], Role)>,
    pub normals: &'a [NormalDot],
    /// Caption lines, top to bottom.
    pub caption: Vec<String>,
}

/// The colour of the `k`-th plane with `role`.
pub fn plane_colour(k: usize, role: Role) -> [u8; 3] {
    match role {
        Role::Ground => GROUND_TINT,
        Role::Inclined => INCLINED_TINT,
        Role::Other => OTHER_PLANES[k % OTHER_PLANES.len()],
    }
}

/// Renders the overlay: `SCALE * width` wide, `SCALE * height` plus the
/// caption high. Pixel indices outside the cloud are ignored.
pub fn render_overlay(o: &Overlay<'_>) -> ColorImage {
    let (w, h) = (o.width as usize, o.height as usize);
    let mut base = grey_levels(o.points, o.width, o.height);
    for (k, (inliers, role)) in o.planes.iter().enumerate() {
        let colour = plane_colour(k, *role);
        for &i in inliers.iter() {
            if let Some(pixel) = base.get_mut(i as usize) {
                *pixel = mix(*pixel, colour, PLANE_WEIGHT);
            }
        }
    }
    let caption_h = caption_height(o.caption.len() + 1);
    let (ow, oh) = (o.width * SCALE, o.height * SCALE);
    let mut image = ColorImage::new(ow, oh + caption_h);
    for v in 0..oh as usize {
        for u in 0..ow as usize {
            let s = SCALE as usize;
            image.data[v * ow as usize + u] = base[(v / s) * w + u / s];
        }
    }
    draw_normals(&mut image, o.normals, w, h);
    for (inliers, role) in &o.planes {
        let name = match role {
            Role::Ground => "ground",
            Role::Inclined => "inclined",
            Role::Other => continue,
        };
        let margin = (TEXT_PX * 0.25).round();
        let box_px = (
            text_width(name, TEXT_PX) + 2.0 * margin,
            TEXT_PX * 1.2 + 2.0 * margin,
        );
        // The label box in depth pixels, rounded up.
        let box_depth = (
            (box_px.0 / SCALE as f32).ceil() as usize,
            (box_px.1 / SCALE as f32).ceil() as usize,
        );
        if let Some(place) = label_anchor(inliers, w, h, box_depth) {
            // The text box centred in the depth-pixel box the anchor chose.
            let (u0, v0) = place.top_left;
            let x = u0 as f32 * SCALE as f32 + (box_depth.0 as f32 * SCALE as f32 - box_px.0) / 2.0;
            let y = v0 as f32 * SCALE as f32 + (box_depth.1 as f32 * SCALE as f32 - box_px.1) / 2.0;
            draw_label(
                &mut image,
                x + margin,
                y + margin,
                TEXT_PX,
                [255, 255, 255],
                plane_colour(0, *role),
                name,
            );
        }
    }
    draw_caption(&mut image, oh, &o.caption);
    image
}

/// Height of a caption of `lines` lines (the legend included), pixels.
fn caption_height(lines: usize) -> u32 {
    ((lines as f32) * TEXT_PX * 1.4 + TEXT_PX * 0.6).ceil() as u32
}

/// The caption lines and the colour legend, under the picture.
fn draw_caption(image: &mut ColorImage, top: u32, lines: &[String]) {
    let width = i64::from(image.width);
    fill_rect(
        image,
        0,
        i64::from(top),
        width,
        i64::from(image.height),
        CAPTION_BG,
    );
    let x0 = TEXT_PX * 0.5;
    let mut y = top as f32 + TEXT_PX * 0.3;
    for line in lines {
        draw_text(image, x0, y, TEXT_PX, CAPTION_FG, line);
        y += TEXT_PX * 1.4;
    }
    let legend = [
        (GROUND_TINT, "ground"),
        (INCLINED_TINT, "inclined"),
        (OTHER_PLANES[0], "other planes"),
        (KEPT_NORMAL, "kept normals"),
        (DROPPED_NORMAL, "dropped normals"),
    ];
    let mut x = x0;
    for (colour, name) in legend {
        let side = (TEXT_PX * 0.8) as i64;
        let top = (y + TEXT_PX * 0.2) as i64;
        fill_rect(image, x as i64, top, x as i64 + side, top + side, colour);
        x = draw_text(image, x + side as f32 + 6.0, y, TEXT_PX, CAPTION_FG, name) + TEXT_PX;
    }
}

/// Dots at the sampled normals' pixels: an even share of the kept ones
/// (at most [`KEPT_DOTS`]) and of the dropped ones (at most
/// [`DROPPED_DOTS`]).
fn draw_normals(image: &mut ColorImage, normals: &[NormalDot], w: usize, h: usize) {
    let kept = normals.iter().filter(|n| n.kept).count();
    let strides = [
        (normals.len() - kept).div_ceil(DROPPED_DOTS).max(1),
        kept.div_ceil(KEPT_DOTS).max(1),
    ];
    let mut seen = [0usize; 2];
    for n in normals {
        let k = usize::from(n.kept);
        seen[k] += 1;
        if seen[k] % strides[k] != 0 {
            continue;
        }
        let (u, v) = (n.pixel as usize % w.max(1), n.pixel as usize / w.max(1));
        if v >= h {
            continue;
        }
        let colour = if n.kept { KEPT_NORMAL } else { DROPPED_NORMAL };
        let (cx, cy) = ((u as u32 * SCALE) as i64, (v as u32 * SCALE) as i64);
        fill_rect(image, cx - 2, cy - 2, cx + 3, cy + 3, [0, 0, 0]);
        fill_rect(image, cx - 1, cy - 1, cx + 2, cy + 2, colour);
    }
}

/// Where a plane's label goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LabelPlace {
    /// The plane's pixel `(u, v)` the label is centred on.
    pub pixel: (usize, usize),
    /// The top-left pixel of the label's box (the box is moved inside the
    /// image's border, so it may not be centred on `pixel` near an edge).
    pub top_left: (usize, usize),
}

/// Where a plane's label goes: the pixel `(u, v)` of `pixels` (on a
/// `w` x `h` grid) on which a label box of `label` (columns, rows) centred
/// there covers the most of the plane, nearest the plane's centroid among
/// those whose box lies at least 90 % on the plane. The box stays
/// [`LABEL_EDGE`] pixels inside the image where the image is large enough.
///
/// The centroid alone is not enough: a segment that wraps around another
/// plane (the floor around a stair) or comes in two pieces has its
/// centroid on another plane, and the label landed there. `None` for a
/// plane with no pixel inside the grid.
pub fn label_anchor(
    pixels: &[u32],
    w: usize,
    h: usize,
    label: (usize, usize),
) -> Option<LabelPlace> {
    let mut mask = vec![false; w * h];
    let mut count = 0usize;
    let (mut su, mut sv) = (0.0f64, 0.0f64);
    for &p in pixels {
        let p = p as usize;
        if let Some(m) = mask.get_mut(p) {
            if !*m {
                *m = true;
                count += 1;
                su += (p % w) as f64;
                sv += (p / w) as f64;
            }
        }
    }
    if count == 0 {
        return None;
    }
    let centroid = (su / count as f64, sv / count as f64);
    // Summed-area table: inside[(v * (w + 1)) + u] counts the plane's
    // pixels above and left of (u, v).
    let mut inside = vec![0u32; (w + 1) * (h + 1)];
    for v in 0..h {
        let mut row = 0u32;
        for u in 0..w {
            row += u32::from(mask[v * w + u]);
            inside[(v + 1) * (w + 1) + u + 1] = inside[v * (w + 1) + u + 1] + row;
        }
    }
    let (bw, bh) = (label.0.clamp(1, w), label.1.clamp(1, h));
    let area = (bw * bh) as f64;
    // How far the box's centre may go: LABEL_EDGE from the image edge
    // where the image leaves room for it.
    let edge_u = LABEL_EDGE.min((w - bw) / 2);
    let edge_v = LABEL_EDGE.min((h - bh) / 2);
    let mut best: Option<((f64, f64), LabelPlace)> = None;
    for (p, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
        let (u, v) = (p % w, p / w);
        // The box's top-left, moved inside the allowed band.
        let u0 = (u.saturating_sub(bw / 2)).clamp(edge_u, w - bw - edge_u);
        let v0 = (v.saturating_sub(bh / 2)).clamp(edge_v, h - bh - edge_v);
        let (u1, v1) = (u0 + bw, v0 + bh);
        let covered = inside[v1 * (w + 1) + u1] + inside[v0 * (w + 1) + u0]
            - inside[v0 * (w + 1) + u1]
            - inside[v1 * (w + 1) + u0];
        let coverage = (f64::from(covered) / area).min(LABEL_COVERAGE);
        let distance = (u as f64 - centroid.0).powi(2) + (v as f64 - centroid.1).powi(2);
        let key = (coverage, -distance);
        if best.is_none_or(|(b, _)| key > b) {
            let place = LabelPlace {
                pixel: (u, v),
                top_left: (u0, v0),
            };
            best = Some((key, place));
        }
    }
    best.map(|(_, place)| place)
}

fn mix(base: [u8; 3], colour: [u8; 3], weight: f32) -> [u8; 3] {
    let mut out = [0; 3];
    for c in 0..3 {
        out[c] =
            (f32::from(base[c]) * (1.0 - weight) + f32::from(colour[c]) * weight).round() as u8;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 120 x 90 cloud: the lower half is the ground, a block on the right
    /// of the upper half the inclined plane, one other plane on the left.
    fn scene() -> (Vec<CloudPoint>, Vec<u32>, Vec<u32>, Vec<u32>) {
        let (w, h) = (120u32, 90u32);
        let points = (0..w * h)
            .map(|i| CloudPoint {
                x_m: 0.0,
                y_m: 0.0,
                z_m: 1.0 + (i / w) as f32 * 0.01,
                rgb: 0,
            })
            .collect();
        let ground = (45 * w..h * w).collect();
        let inclined = (0..45)
            .flat_map(|v| (75..120).map(move |u| v * w + u))
            .collect();
        let other = (0..45)
            .flat_map(|v| (0..30).map(move |u| v * w + u))
            .collect();
        (points, ground, inclined, other)
    }

    fn dominant(p: [u8; 3]) -> usize {
        (0..3).max_by_key(|&c| p[c]).unwrap_or(0)
    }

    #[test]
    fn each_plane_has_its_colour_and_the_caption_its_text() {
        let (points, ground, inclined, other) = scene();
        let normals = [
            NormalDot {
                pixel: 5 * 120 + 80,
                kept: true,
            },
            NormalDot {
                pixel: 5 * 120 + 115,
                kept: false,
            },
        ];
        let overlay = Overlay {
            points: &points,
            width: 120,
            height: 90,
            planes: vec![
                (&ground, Role::Ground),
                (&inclined, Role::Inclined),
                (&other, Role::Other),
            ],
            normals: &normals,
            caption: vec!["slope +16.02° ± 0.20°".into(), "confidence 1.00".into()],
        };
        let image = render_overlay(&overlay);
        assert_eq!(image.width, 240);
        assert!(image.height > 180);
        // Away from the labels and dots: ground red, inclined blue, the
        // other plane its own colour, the rest grey.
        let at = |u: u32, v: u32| image.get(u * SCALE, v * SCALE).unwrap();
        assert_eq!(dominant(at(2, 85)), 0, "{:?}", at(2, 85));
        assert_eq!(dominant(at(118, 1)), 2, "{:?}", at(118, 1));
        let grey = at(50, 2);
        assert!(grey[0] == grey[1] && grey[1] == grey[2], "{grey:?}");
        assert_ne!(at(1, 1), grey);
        // The dots: kept green, dropped yellow.
        assert_eq!(image.get(80 * SCALE, 5 * SCALE), Some(KEPT_NORMAL));
        assert_eq!(image.get(115 * SCALE, 5 * SCALE), Some(DROPPED_NORMAL));
        // The labels are written on their planes: white text pixels near
        // the inclined plane's centre (97, 22), on its blue.
        let white = (40..80)
            .flat_map(|v| (160..230).map(move |u| (u, v)))
            .filter(|&(u, v)| image.get(u, v).is_some_and(|p| p.iter().all(|&c| c > 200)))
            .count();
        assert!(white > 20, "{white}");
        // The caption area holds text (bright pixels on the dark band).
        let bright = (180..image.height)
            .flat_map(|v| (0..image.width).map(move |u| (u, v)))
            .filter(|&(u, v)| image.get(u, v).is_some_and(|p| p[0] > 200 && p[1] > 200))
            .count();
        assert!(bright > 30, "{bright}");
    }

    /// The pixels of `(u, v)` in `rect` (columns `u0..u1`, rows `v0..v1`) on a
    /// `w`-wide grid.
    fn rect(w: u32, (u0, u1): (u32, u32), (v0, v1): (u32, u32)) -> Vec<u32> {
        (v0..v1)
            .flat_map(|v| (u0..u1).map(move |u| v * w + u))
            .collect()
    }

    /// How many of the label box's pixels are in `plane`.
    fn box_share(plane: &[u32], w: usize, place: LabelPlace, label: (usize, usize)) -> f64 {
        let (u0, v0) = place.top_left;
        let inside = (v0..v0 + label.1)
            .flat_map(|v| (u0..u0 + label.0).map(move |u| (v * w + u) as u32))
            .filter(|p| plane.contains(p))
            .count();
        inside as f64 / (label.0 * label.1) as f64
    }

    /// A floor that wraps around a stair (a U: two legs and a band along
    /// the bottom) has its centroid on the stair, not on itself: the label
    /// goes on one of its own pixels, its box on the floor and inside the
    /// image (it was written at the centroid, on the stair).
    #[test]
    fn a_label_sits_on_its_own_plane_when_the_centroid_is_not() {
        let (w, h) = (200usize, 150usize);
        let mut floor = rect(200, (0, 40), (0, 150));
        floor.extend(rect(200, (160, 200), (0, 150)));
        floor.extend(rect(200, (40, 160), (120, 150)));
        let label = (40, 14);
        // The centroid (100, ~85) is on the stair between the legs.
        let (cu, cv) = (100u32, 85u32);
        assert!(!floor.contains(&(cv * 200 + cu)));
        let place = label_anchor(&floor, w, h, label).expect("a place");
        let (u, v) = place.pixel;
        assert!(floor.contains(&((v * w + u) as u32)), "{place:?}");
        assert!(box_share(&floor, w, place, label) >= 0.9, "{place:?}");
        let (u0, v0) = place.top_left;
        assert!(u0 >= LABEL_EDGE && v0 >= LABEL_EDGE, "{place:?}");
        assert!(u0 + label.0 + LABEL_EDGE <= w && v0 + label.1 + LABEL_EDGE <= h);
        // Two pieces, a thin one at the top and a thick one at the bottom,
        // the centroid between them: the label goes on the one it fits in.
        let mut pieces = rect(200, (0, 200), (0, 6));
        pieces.extend(rect(200, (60, 140), (110, 150)));
        let place = label_anchor(&pieces, w, h, label).expect("a place");
        let (u, v) = place.pixel;
        assert!(
            (60..140).contains(&u) && (110..150).contains(&v),
            "{place:?}"
        );
        assert!(box_share(&pieces, w, place, label) >= 0.9, "{place:?}");
        // A plane the label cannot fit in still gets a pixel of its own.
        let sliver = rect(200, (0, 200), (149, 150));
        let place = label_anchor(&sliver, w, h, label).expect("a place");
        assert_eq!(place.pixel.1, 149, "{place:?}");
        assert!(place.top_left.1 + label.1 <= h, "{place:?}");
        // Nothing on the grid: no place.
        assert_eq!(label_anchor(&[1_000_000], w, h, label), None);
        assert_eq!(label_anchor(&[], w, h, label), None);
    }

    #[test]
    fn pixels_outside_the_cloud_are_ignored() {
        let point = CloudPoint {
            x_m: 0.0,
            y_m: 0.0,
            z_m: 1.0,
            rgb: 0,
        };
        let points = vec![point; 4];
        let far = [1_000_000u32];
        let overlay = Overlay {
            points: &points,
            width: 2,
            height: 2,
            planes: vec![(&far, Role::Ground)],
            normals: &[NormalDot {
                pixel: 99,
                kept: true,
            }],
            caption: vec![],
        };
        let image = render_overlay(&overlay);
        assert_eq!(image.width, 4);
        assert!(image.data[..16]
            .iter()
            .all(|p| p[0] == p[1] && p[1] == p[2]));
    }
}
