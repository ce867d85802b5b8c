//! The paper's stages as written, for the `paper-literal` preset
//! ([`crate::EstimatorConfig::paper_literal`]) and the ablation that
//! measures what each of our changes buys (`examples/ablation.rs`). Each
//! file is one stage, selected by a switch in that stage's own config:
//!
//! | file | stage | switch (literal value) |
//! |---|---|---|
//! | `knn_outlier.rs` | statistical outlier removal, 20 nearest neighbours from a k-d tree over the whole cloud | `outlier.neighbourhood = "kd-tree"` |
//! | `every_point_ransac.rs` | RANSAC: three-point hypotheses scored on every kept point, largest plane out, repeat | `ransac.scoring = "every-point"` |
//! | `depth_pass_through.rs` | pass-through on the depth axis z: the nearest 10,000 points of a plane | `pass_through.mode = "depth"` |
//! | `knn_normals.rs` | PCA normal over exactly the K = 100 nearest points (k-d tree) | `normals.neighbourhood = "kd-tree"` |
//!
//! The other literal values are existing keys: `ransac.
//! distance_threshold_per_m2 = 0`, `normals.min_patch_radius_m = 0`,
//! `normals.patch_per_rms = 0`, `normals.interior_only = false`,
//! `kmeans.merge_spread_ratio = 0`, `cumulative.draws = 100`,
//! `cumulative.about_axis = false`. The plane selection is ours in both.
//! They are slow (a k-d tree over ~200,000 points per frame, RANSAC over
//! all of them) and exact: each file's tests hold it to a brute-force
//! oracle.

pub mod depth_pass_through;
pub mod every_point_ransac;
pub mod knn_normals;
pub mod knn_outlier;

pub use depth_pass_through::{DepthPassThrough, PassThroughMode};
pub use every_point_ransac::{EveryPointRansac, RansacScoring};
pub use knn_normals::{KnnNormalEstimator, NormalsNeighbourhood};
pub use knn_outlier::{KnnOutlierFilter, OutlierNeighbourhood};
