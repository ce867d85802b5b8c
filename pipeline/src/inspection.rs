//! What the estimator saw in its last frame, for pictures and exports:
//! the segmented planes, their roles and the sampled normals. Data only;
//! the estimator fills it (`Estimator::inspection`).

use crate::ransac_planes::SegmentedPlane;

/// One normal the paper method sampled, for pictures and exports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InspectedNormal {
    /// The pixel (row-major index) the normal was computed at.
    pub pixel: u32,
    /// Unit normal, camera frame.
    pub normal: [f32; 3],
    /// True when the cosine k-means kept it (its cluster is the dominant
    /// one or merged into it).
    pub kept: bool,
    /// True on the inclined plane, false on the ground.
    pub inclined: bool,
}

/// What the estimator saw in its last frame: every segmented plane, the
/// roles the selection gave them, and the normals the paper method sampled
/// (kept only with [`Estimator::set_inspect`], which costs a copy of the
/// normals per frame).
///
/// [`Estimator::set_inspect`]: crate::Estimator::set_inspect
#[derive(Debug, Clone, Copy)]
pub struct Inspection<'a> {
    /// Every plane RANSAC segmented, in the order found.
    pub planes: &'a [SegmentedPlane],
    /// Indices into `planes` of the ground's segments (empty without a
    /// measured ground).
    pub ground: &'a [usize],
    /// Index into `planes` of the inclined plane.
    pub inclined: Option<usize>,
    /// The paper method's sampled normals, inclined plane first.
    pub normals: &'a [InspectedNormal],
}
