//! Stage 2, plane segmentation: the planes of the points the outlier
//! filter kept, each with its inliers in pixel order
//! ([`SegmentedPlane`]), by one of two designs (`segmentation.proposal`):
//!
//! - `"cells"` (the default, `cells/`): planar cells of the pixel grid
//!   grown into regions propose the planes, the paper's RANSAC fits each
//!   region's plane over the region's own points and the plane floods its
//!   band on the sample grid; the sequential extraction then runs on what
//!   no proposed plane explains;
//! - `"sequential"` (`ransac_planes/`, an option the ablation compares):
//!   RANSAC extractions one after another on a sample of the pixel grid,
//!   each plane the largest connected region of the best hypothesis's
//!   inliers.
//!
//! Both end the same way: every kept pixel goes to the nearest plane of
//! the sample cells around it within the inlier distance, and each plane
//! is refitted by TLS on all its pixels (`ransac_planes/labelling.rs`).
//! The paper as written (`ransac.scoring = "every-point"`,
//! `literal/every_point_ransac.rs`) is chosen by the estimator before this
//! stage and ignores this section.

use rand_chacha::ChaCha8Rng;

use crate::cloud::CloudView;
use crate::ransac_planes::{PlaneSegmenter, RansacConfig, SegmentedPlane};

pub mod cells;
mod config;

pub use cells::CellProposal;
pub use config::{Proposal, SegmentationConfig};

/// Reusable buffers of both designs.
#[derive(Debug, Default, Clone)]
pub struct Segmentation {
    segmenter: PlaneSegmenter,
    cells: CellProposal,
}

impl Segmentation {
    pub fn new() -> Self {
        Self::default()
    }

    /// Threads the shared labelling pass may use (`None`: the caller's
    /// alone); the planes are the same, bit for bit, either way.
    pub fn set_workers(&mut self, workers: Option<std::sync::Arc<rayon::ThreadPool>>) {
        self.segmenter.set_workers(workers);
    }

    /// The planes of the last [`Self::segment`] call, largest first (up to
    /// the final relabelling).
    pub fn planes(&self) -> &[SegmentedPlane] {
        self.segmenter.planes()
    }

    /// Segments the points marked in `keep` (one flag per pixel) into
    /// planes with the design `config` names.
    pub fn segment(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        ransac: &RansacConfig,
        config: &SegmentationConfig,
        rng: &mut ChaCha8Rng,
    ) -> &[SegmentedPlane] {
        match config.proposal {
            Proposal::Cells => {
                let mut proposal = self.cells.configured(config);
                self.segmenter
                    .segment_proposed(cloud, keep, ransac, &mut proposal, rng)
            }
            Proposal::Sequential => self.segmenter.segment(cloud, keep, ransac, rng),
        }
    }
}
