//! The overlay of one frame (`slope-eval --render`): the depth image in
//! grey, every surface the estimator saw tinted in its role's colour
//! ([`crate::render::ROLE_COLOURS`]) and labelled with its role and slope
//! (`ramp 16.0°`), the road's boundary in [`ROAD_OUTLINE`], the robot's
//! corridor drawn on the ground in [`CORRIDOR_LINE`], the normals the paper
//! method sampled as dots (kept: green, dropped by the cosine k-means:
//! yellow), and a caption under the image with the slope, its spread, the
//! confidence and the status, then the legend.
//!
//! [`render_overlay`] is pure (data in, image out); drawn at
//! [`SCALE`] times the depth resolution so that the text stays readable.

use slope_ipc_types::{CloudPoint, SurfaceRole};
use slope_sensor::recording::ColorImage;

use crate::overlay_marks::Segment;
use crate::render::{
    grey_levels, role_colour, CORRIDOR_LINE, GROUND_TINT, INCLINED_TINT, ROAD_OUTLINE, UNCLASSIFIED,
};
use crate::text::{draw_label, draw_text, fill_rect, text_width};

/// Output pixels per depth pixel, in each direction.
pub const SCALE: u32 = 2;
/// Colour of a kept normal's dot.
pub const KEPT_NORMAL: [u8; 3] = [40, 230, 60];
/// Colour of a dropped normal's dot.
pub const DROPPED_NORMAL: [u8; 3] = [255, 220, 0];
/// Colours of the other planes in the labelled cloud (`--export-ply`), in
/// the order they were segmented.
pub const OTHER_PLANES: [[u8; 3]; 6] = [
    [150, 110, 200],
    [90, 170, 160],
    [200, 150, 90],
    [170, 90, 130],
    [120, 160, 90],
    [110, 130, 180],
];
/// Share of a surface's colour in its pixels (the rest is the depth grey).
pub const PLANE_WEIGHT: f32 = 0.6;
/// Width of the corridor's lines, output pixels.
pub const LINE_PX: i64 = 3;
/// Caption text height, output pixels.
const TEXT_PX: f32 = 22.0;
/// Label text height, output pixels.
const LABEL_PX: f32 = 20.0;
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

/// What a plane is in the labelled cloud (`--export-ply`).
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

/// One surface in the picture.
#[derive(Debug, Clone)]
pub struct SurfacePixels<'a> {
    /// Its pixels: the inliers of each of its segmented planes.
    pub pixels: Vec<&'a [u32]>,
    /// `None` for a plane no surface holds (no roles in that frame).
    pub role: Option<SurfaceRole>,
    /// Written on it; empty for none.
    pub label: String,
}

/// Everything one overlay shows.
#[derive(Debug, Clone)]
pub struct Overlay<'a> {
    pub points: &'a [CloudPoint],
    pub width: u32,
    pub height: u32,
    /// Every surface, drawn in order (a later one over an earlier one).
    pub surfaces: Vec<SurfacePixels<'a>>,
    /// The road's boundary pixels ([`crate::overlay_marks::boundary_pixels`]).
    pub road_outline: Vec<u32>,
    /// The corridor's edges, depth-pixel coordinates
    /// ([`crate::overlay_marks::corridor_segments`]).
    pub corridor: Vec<Segment>,
    pub normals: &'a [NormalDot],
    /// Caption lines, top to bottom.
    pub caption: Vec<String>,
}

/// The colour of the `k`-th plane with `role` in the labelled cloud.
pub fn plane_colour(k: usize, role: Role) -> [u8; 3] {
    match role {
        Role::Ground => GROUND_TINT,
        Role::Inclined => INCLINED_TINT,
        Role::Other => OTHER_PLANES[k % OTHER_PLANES.len()],
    }
}

/// The colour a surface is tinted in.
pub fn surface_colour(role: Option<SurfaceRole>) -> [u8; 3] {
    role.map_or(UNCLASSIFIED, role_colour)
}

/// The output-pixel coordinate of depth-pixel coordinate `x` (the centre
/// of depth pixel `k` is the centre of its `SCALE` x `SCALE` block).
pub fn to_output(x: f64) -> f64 {
    (x + 0.5) * f64::from(SCALE) - 0.5
}

/// Renders the overlay: `SCALE * width` wide, `SCALE * height` plus the
/// caption high. Pixel indices outside the cloud are ignored.
pub fn render_overlay(o: &Overlay<'_>) -> ColorImage {
    let (w, h) = (o.width as usize, o.height as usize);
    let mut base = grey_levels(o.points, o.width, o.height);
    for surface in &o.surfaces {
        let colour = surface_colour(surface.role);
        for &i in surface.pixels.iter().flat_map(|p| p.iter()) {
            if let Some(pixel) = base.get_mut(i as usize) {
                *pixel = mix(*pixel, colour, PLANE_WEIGHT);
            }
        }
    }
    let caption_h = caption_height(o.caption.len() + 2);
    let (ow, oh) = (o.width * SCALE, o.height * SCALE);
    let mut image = ColorImage::new(ow, oh + caption_h);
    let s = SCALE as usize;
    for v in 0..oh as usize {
        for u in 0..ow as usize {
            image.data[v * ow as usize + u] = base[(v / s) * w + u / s];
        }
    }
    for &p in &o.road_outline {
        let (u, v) = (
            (p as usize % w.max(1)) as i64,
            (p as usize / w.max(1)) as i64,
        );
        if v < h as i64 {
            let (x, y) = (u * i64::from(SCALE), v * i64::from(SCALE));
            let side = i64::from(SCALE);
            fill_rect(&mut image, x, y, x + side, y + side, ROAD_OUTLINE);
        }
    }
    for segment in &o.corridor {
        draw_segment(&mut image, *segment, oh, CORRIDOR_LINE);
    }
    draw_normals(&mut image, o.normals, w, h);
    let mut placed = Vec::new();
    for surface in o.surfaces.iter().filter(|s| !s.label.is_empty()) {
        if let Some(label) = draw_surface_label(&mut image, surface, w, h, &placed) {
            placed.push(label);
        }
    }
    draw_caption(&mut image, oh, &o.caption);
    image
}

/// A line [`LINE_PX`] wide along `segment` (depth-pixel coordinates), on
/// the picture's top `height` rows.
fn draw_segment(image: &mut ColorImage, segment: Segment, height: u32, colour: [u8; 3]) {
    let [(u0, v0), (u1, v1)] = segment;
    let (x0, y0, x1, y1) = (to_output(u0), to_output(v0), to_output(u1), to_output(v1));
    let length = (x1 - x0).hypot(y1 - y0);
    if !length.is_finite() {
        return;
    }
    // Steps of a quarter pixel: every pixel the line crosses is hit.
    let steps = (length * 4.0).ceil().max(1.0) as usize;
    let half = LINE_PX / 2;
    for k in 0..=steps {
        let t = k as f64 / steps as f64;
        let (x, y) = (
            (x0 + t * (x1 - x0)).round() as i64,
            (y0 + t * (y1 - y0)).round() as i64,
        );
        let bottom = (y + half + 1).min(i64::from(height));
        fill_rect(image, x - half, y - half, x + half + 1, bottom, colour);
    }
}

/// A surface's label on its own pixels, nearest its centroid, on a box of
/// its colour, clear of the labels `placed` before where it can be; its box.
fn draw_surface_label(
    image: &mut ColorImage,
    surface: &SurfacePixels<'_>,
    w: usize,
    h: usize,
    placed: &[LabelBox],
) -> Option<LabelBox> {
    let margin = (LABEL_PX * 0.25).round();
    let box_px = (
        text_width(&surface.label, LABEL_PX) + 2.0 * margin,
        LABEL_PX * 1.2 + 2.0 * margin,
    );
    // The label box in depth pixels, rounded up.
    let box_depth = (
        (box_px.0 / SCALE as f32).ceil() as usize,
        (box_px.1 / SCALE as f32).ceil() as usize,
    );
    let pixels: Vec<u32> = surface
        .pixels
        .iter()
        .flat_map(|p| p.iter().copied())
        .collect();
    let place = label_anchor(&pixels, w, h, box_depth, placed)?;
    // The text box centred in the depth-pixel box the anchor chose.
    let (u0, v0) = place.top_left;
    let x = u0 as f32 * SCALE as f32 + (box_depth.0 as f32 * SCALE as f32 - box_px.0) / 2.0;
    let y = v0 as f32 * SCALE as f32 + (box_depth.1 as f32 * SCALE as f32 - box_px.1) / 2.0;
    draw_label(
        image,
        x + margin,
        y + margin,
        LABEL_PX,
        [255, 255, 255],
        surface_colour(surface.role),
        &surface.label,
    );
    Some(LabelBox {
        top_left: place.top_left,
        size: box_depth,
    })
}

/// Height of a caption of `lines` lines (the legend included), pixels.
fn caption_height(lines: usize) -> u32 {
    ((lines as f32) * TEXT_PX * 1.4 + TEXT_PX * 0.6).ceil() as u32
}

/// The caption lines and the colour legend (the roles on one line, the
/// marks on the next), under the picture.
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
    let roles: Vec<([u8; 3], &str)> = SurfaceRole::ALL
        .iter()
        .map(|&r| (role_colour(r), r.name()))
        .collect();
    let marks = [
        (ROAD_OUTLINE, "road outline"),
        (CORRIDOR_LINE, "corridor"),
        (KEPT_NORMAL, "kept normals"),
        (DROPPED_NORMAL, "dropped normals"),
    ];
    for legend in [&roles[..], &marks[..]] {
        let mut x = x0;
        for &(colour, name) in legend {
            let side = (TEXT_PX * 0.8) as i64;
            let top = (y + TEXT_PX * 0.2) as i64;
            fill_rect(image, x as i64, top, x as i64 + side, top + side, colour);
            x = draw_text(image, x + side as f32 + 6.0, y, TEXT_PX, CAPTION_FG, name) + TEXT_PX;
        }
        y += TEXT_PX * 1.4;
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

/// A label's box in depth pixels: its top-left pixel and its size
/// (columns, rows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LabelBox {
    pub top_left: (usize, usize),
    pub size: (usize, usize),
}

impl LabelBox {
    /// Whether the two boxes share a pixel.
    pub fn overlaps(&self, other: &LabelBox) -> bool {
        let apart = |a: usize, la: usize, b: usize, lb: usize| a + la <= b || b + lb <= a;
        !(apart(self.top_left.0, self.size.0, other.top_left.0, other.size.0)
            || apart(self.top_left.1, self.size.1, other.top_left.1, other.size.1))
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
/// those whose box lies at least 90 % on the plane; a box clear of the
/// boxes `taken` (labels written before) first, wherever the plane has
/// one. The box stays [`LABEL_EDGE`] pixels inside the image where the
/// image is large enough.
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
    taken: &[LabelBox],
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
    let mut best: Option<((bool, f64, f64), LabelPlace)> = None;
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
        let this = LabelBox {
            top_left: (u0, v0),
            size: (bw, bh),
        };
        let clear = !taken.iter().any(|t| t.overlaps(&this));
        let key = (clear, coverage, -distance);
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

/// The role whose tint over some grey best explains `p`: `p - w * c`
/// is nearest the grey axis for the right colour `c`.
#[cfg(test)]
pub(crate) fn tint_role(p: [u8; 3]) -> Option<SurfaceRole> {
    let residual = |c: [u8; 3]| {
        let q: Vec<f64> = (0..3)
            .map(|k| f64::from(p[k]) - f64::from(PLANE_WEIGHT) * f64::from(c[k]))
            .collect();
        let mean = q.iter().sum::<f64>() / 3.0;
        q.iter().map(|x| (x - mean).powi(2)).sum::<f64>()
    };
    SurfaceRole::ALL
        .into_iter()
        .map(|r| (r, residual(role_colour(r))))
        .filter(|(_, e)| *e < 3.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(r, _)| r)
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

    #[test]
    fn each_surface_has_its_role_colour_and_the_marks_theirs() {
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
        fn surface<'a>(pixels: &'a [u32], role: SurfaceRole, label: &str) -> SurfacePixels<'a> {
            SurfacePixels {
                pixels: vec![pixels],
                role: Some(role),
                label: label.to_string(),
            }
        }
        let (ground_a, ground_b) = ground.split_at(ground.len() / 2);
        let overlay = Overlay {
            points: &points,
            width: 120,
            height: 90,
            surfaces: vec![
                SurfacePixels {
                    pixels: vec![ground_a, ground_b],
                    role: Some(SurfaceRole::Ground),
                    label: "ground".into(),
                },
                surface(&inclined, SurfaceRole::Ramp, "ramp 16.0°"),
                surface(&other, SurfaceRole::Wall, ""),
            ],
            road_outline: vec![44 * 120 + 100],
            corridor: vec![[(10.0, 80.0), (40.0, 50.0)]],
            normals: &normals,
            caption: vec!["slope +16.02° ± 0.20°".into(), "confidence 1.00".into()],
        };
        let image = render_overlay(&overlay);
        assert_eq!(image.width, 240);
        assert!(image.height > 180);
        // Away from the labels and dots: both halves of the ground its
        // colour, the ramp and the wall theirs, the rest grey.
        let at = |u: u32, v: u32| image.get(u * SCALE, v * SCALE).unwrap();
        assert_eq!(tint_role(at(2, 85)), Some(SurfaceRole::Ground));
        assert_eq!(tint_role(at(118, 47)), Some(SurfaceRole::Ground));
        assert_eq!(tint_role(at(118, 1)), Some(SurfaceRole::Ramp));
        assert_eq!(tint_role(at(1, 1)), Some(SurfaceRole::Wall));
        let grey = at(50, 2);
        assert!(grey[0] == grey[1] && grey[1] == grey[2], "{grey:?}");
        assert_eq!(tint_role(grey), None);
        // The road's boundary pixel, its whole 2 x 2 block; the corridor's
        // line through its end points and its middle.
        for (u, v) in [(200, 88), (201, 89)] {
            assert_eq!(image.get(u, v), Some(ROAD_OUTLINE), "({u}, {v})");
        }
        for (u, v) in [(10.0, 80.0), (25.0, 65.0), (40.0, 50.0)] {
            let (x, y) = (to_output(u).round() as u32, to_output(v).round() as u32);
            assert_eq!(image.get(x, y), Some(CORRIDOR_LINE), "({u}, {v})");
        }
        // The dots: kept green, dropped yellow.
        assert_eq!(image.get(80 * SCALE, 5 * SCALE), Some(KEPT_NORMAL));
        assert_eq!(image.get(115 * SCALE, 5 * SCALE), Some(DROPPED_NORMAL));
        // The labels are written on their surfaces: white text pixels near
        // the ramp's centre (97, 22), on its blue.
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
        let place = label_anchor(&floor, w, h, label, &[]).expect("a place");
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
        let place = label_anchor(&pieces, w, h, label, &[]).expect("a place");
        let (u, v) = place.pixel;
        assert!(
            (60..140).contains(&u) && (110..150).contains(&v),
            "{place:?}"
        );
        assert!(box_share(&pieces, w, place, label) >= 0.9, "{place:?}");
        // A plane the label cannot fit in still gets a pixel of its own.
        let sliver = rect(200, (0, 200), (149, 150));
        let place = label_anchor(&sliver, w, h, label, &[]).expect("a place");
        assert_eq!(place.pixel.1, 149, "{place:?}");
        assert!(place.top_left.1 + label.1 <= h, "{place:?}");
        // Nothing on the grid: no place.
        assert_eq!(label_anchor(&[1_000_000], w, h, label, &[]), None);
        assert_eq!(label_anchor(&[], w, h, label, &[]), None);
    }

    /// Two planes side by side in a band where both labels would go to the
    /// same spot (the band is narrower than two boxes side by side but
    /// tall): the second label moves along its plane, clear of the first;
    /// with no room clear of it, it still gets its best place.
    #[test]
    fn a_label_keeps_clear_of_the_labels_before_it() {
        let (w, h) = (200usize, 150usize);
        let label = (40, 14);
        let left = rect(200, (60, 100), (0, 150));
        let right = rect(200, (100, 140), (0, 150));
        let first = label_anchor(&left, w, h, label, &[]).expect("a place");
        let first = LabelBox {
            top_left: first.top_left,
            size: label,
        };
        let alone = label_anchor(&right, w, h, label, &[]).expect("a place");
        let alone = LabelBox {
            top_left: alone.top_left,
            size: label,
        };
        // Nearest their centroids, the two boxes overlap (the band is 80
        // px wide for two boxes of 40 that each want its plane's centre).
        let wide = (60, 14);
        let a = label_anchor(&left, w, h, wide, &[]).expect("a place");
        let b = label_anchor(&right, w, h, wide, &[]).expect("a place");
        let (a, b) = (
            LabelBox {
                top_left: a.top_left,
                size: wide,
            },
            LabelBox {
                top_left: b.top_left,
                size: wide,
            },
        );
        assert!(a.overlaps(&b), "{a:?} {b:?}");
        let moved = label_anchor(&right, w, h, wide, &[a]).expect("a place");
        let moved = LabelBox {
            top_left: moved.top_left,
            size: wide,
        };
        assert!(!moved.overlaps(&a), "{moved:?} {a:?}");
        assert!(box_share(&right, w, moved_place(moved), wide) >= 0.5);
        // Boxes that fit side by side stay where they were.
        assert!(!first.overlaps(&alone));
        let kept = label_anchor(&right, w, h, label, &[first]).expect("a place");
        assert_eq!(kept.top_left, alone.top_left);
        // A plane with no place clear of a box covering it all: its best.
        let cover = LabelBox {
            top_left: (0, 0),
            size: (w, h),
        };
        let stuck = label_anchor(&right, w, h, label, &[cover]).expect("a place");
        assert_eq!(stuck.top_left, alone.top_left);
    }

    fn moved_place(b: LabelBox) -> LabelPlace {
        LabelPlace {
            pixel: b.top_left,
            top_left: b.top_left,
        }
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
            surfaces: vec![SurfacePixels {
                pixels: vec![&far],
                role: Some(SurfaceRole::Ground),
                label: "ground".into(),
            }],
            road_outline: vec![1_000_000],
            corridor: vec![[(-100.0, -100.0), (-50.0, -50.0)]],
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
