//! A chosen plane's pixels: one RANSAC plane (the inclined plane), or the
//! ground's segments joined into one (their pixels merged in pixel order,
//! their moments summed, their quality pooled).

use nalgebra::Vector3;

use super::quality::PooledQuality;
use super::{Ground, PlaneQuality, PlaneSummary, Selection};
use crate::cloud::PixelBox;
use crate::plane_fit::Moments;
use crate::ransac_planes::SegmentedPlane;

/// The pixels of a chosen plane (one RANSAC plane, or the ground's
/// segments together), their centroid and RMS distance from their plane.
pub(crate) struct PlaneSegment<'a> {
    pub(crate) inliers: &'a [u32],
    /// The pixels' bounding box, when the segmentation knows it (every
    /// segment's: [`SegmentedPlane::pixel_box`]).
    pub(crate) pixel_box: Option<PixelBox>,
    pub(crate) centroid: Vector3<f64>,
    pub(crate) rms_m: f64,
    pub(crate) quality: PlaneQuality,
    /// Moments of the pixels (their TLS and least-squares fits).
    pub(crate) moments: Moments,
}

impl<'a> PlaneSegment<'a> {
    /// One RANSAC plane.
    pub(crate) fn of(plane: &'a SegmentedPlane, summary: &PlaneSummary) -> Self {
        Self {
            inliers: &plane.inliers,
            pixel_box: plane.pixel_box,
            centroid: plane.centroid,
            rms_m: plane.rms_m,
            quality: summary.quality,
            moments: plane.moments,
        }
    }

    /// The planes `members` together (the ground's segments): their pixels
    /// in pixel order (into `pixels`), centroid, RMS and quality.
    pub(crate) fn joined(
        planes: &[SegmentedPlane],
        summaries: &[PlaneSummary],
        members: &[usize],
        pixels: &'a mut Vec<u32>,
    ) -> Self {
        pixels.clear();
        let mut centroid = Vector3::zeros();
        let mut pooled = PooledQuality::default();
        let mut moments = Moments::new();
        let mut pixel_box = Some(PixelBox::EMPTY);
        for &k in members {
            let p = &planes[k];
            pixel_box = pixel_box.zip(p.pixel_box).map(|(a, b)| a.union(&b));
            moments.merge(&p.moments);
            merge_sorted(pixels, &p.inliers);
            let n = p.inliers.len() as f64;
            centroid += p.centroid * n;
            pooled.add(p.inliers.len(), p.rms_m, &summaries[k].quality);
        }
        let quality = pooled.quality(pixels.len());
        let n = pixels.len().max(1) as f64;
        Self {
            inliers: pixels,
            pixel_box: pixel_box.filter(|b| !b.is_empty()),
            centroid: centroid / n,
            rms_m: quality.rms_m,
            quality,
            moments,
        }
    }
}

/// The selection's chosen planes among `planes`: the inclined plane (with
/// its other pieces joined, their pixels into `inclined_pixels`), and the
/// ground's segments joined (their pixels into `ground_pixels`; `None` for
/// a ground from the mount).
pub(crate) fn chosen_segments<'a>(
    planes: &'a [SegmentedPlane],
    summaries: &[PlaneSummary],
    selection: &Selection,
    inclined_pixels: &'a mut Vec<u32>,
    ground_pixels: &'a mut Vec<u32>,
) -> (PlaneSegment<'a>, Option<PlaneSegment<'a>>) {
    let inclined = if selection.inclined_pieces.is_empty() {
        PlaneSegment::of(&planes[selection.inclined], &summaries[selection.inclined])
    } else {
        let mut members = vec![selection.inclined];
        members.extend_from_slice(&selection.inclined_pieces);
        PlaneSegment::joined(planes, summaries, &members, inclined_pixels)
    };
    let ground = match &selection.ground {
        Ground::Planes(members) => Some(PlaneSegment::joined(
            planes,
            summaries,
            members,
            ground_pixels,
        )),
        Ground::Mount => None,
    };
    (inclined, ground)
}

/// Merges the sorted `more` into the sorted `into` (segments' inliers are
/// in pixel order, and so is their union: a merge, not a sort).
fn merge_sorted(into: &mut Vec<u32>, more: &[u32]) {
    if into
        .last()
        .is_none_or(|&last| more.first().is_none_or(|&f| last < f))
    {
        into.extend_from_slice(more);
        return;
    }
    let old = std::mem::take(into);
    into.reserve(old.len() + more.len());
    let (mut a, mut b) = (old.as_slice(), more);
    while let (Some(&x), Some(&y)) = (a.first(), b.first()) {
        if x <= y {
            into.push(x);
            a = &a[1..];
        } else {
            into.push(y);
            b = &b[1..];
        }
    }
    into.extend_from_slice(a);
    into.extend_from_slice(b);
}

#[cfg(test)]
mod tests {
    use super::merge_sorted;

    /// The merge of sorted lists is their sorted union (the oracle: sort).
    #[test]
    fn merged_segments_are_in_pixel_order() {
        let lists: [&[u32]; 4] = [&[5, 9, 40], &[1, 2, 41, 50], &[], &[60, 61]];
        let mut merged = Vec::new();
        for list in lists {
            merge_sorted(&mut merged, list);
        }
        let mut sorted: Vec<u32> = lists.concat();
        sorted.sort_unstable();
        assert_eq!(merged, sorted);
    }
}
