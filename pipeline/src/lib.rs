//! The slope estimator: the method of "Application-Oriented Fusion Estimation
//! Method for Road Slope Using RGB-D Robots" on organised Kinect clouds, and
//! the least-squares and TLS baselines it is compared with.
//!
//! One stage per file, each a pure function or a small struct that reuses
//! its buffers (see the crate README for every shortcut against the paper):
//!
//! | file | stage |
//! |---|---|
//! | `statistical_outlier/` | 1. statistical outlier removal (m = 20, alpha = 2; grid path, exact fallback, general m, threshold) |
//! | `segmentation/` | 2. plane segmentation: the design chosen by `segmentation.proposal`; `cells/` the cell-grid proposal (planar cells, region growing, RANSAC fit per region, its band flooded, coplanar merge, the sequential extraction on the rest) |
//! | `ransac_planes/` | 2. RANSAC plane segmentation, sequential (sample grid, f32 inlier test, hypotheses, regions, labelling; the labelling both designs share) |
//! | `pass_through.rs` | 3. pass-through filter (at most 10,000 points a plane) |
//! | `normals/` | 4. PCA normals over K = 100 neighbours (window tables, k-d tree fallback, coarse grid normals) |
//! | `cosine_kmeans/` | 5. cosine k-means, dominant cluster (farthest-first centres, f32 assignment and cluster sums, Lloyd iterations, merge) |
//! | `cumulative_angle.rs` | 6. cumulative averaging of the angle |
//! | `plane_fit.rs` | TLS and least-squares plane fits (baselines) |
//! | `baseline.rs` | the least-squares and TLS baselines: each chosen plane's pixels fitted by one plane |
//! | `selection/` | plane quality; the ground; every surface with its role (ground, step, ramp, wall, elevated, overhang); the road ahead in the robot's corridor; sign, distance; the chosen planes' pixels (the ground's segments joined) |
//! | `sensor_noise.rs` | the depth sensor's noise, the yardstick of flatness |
//! | `finish.rs` | the estimate from a method's fit: sign, distance, planes, confidence (the paper method checked against TLS) |
//! | `confidence.rs` | how far to trust an estimate, and why |
//! | `ground_reach.rs` | how far ahead the ground was seen (where a floor ends before a drop-off) |
//! | `tracking.rs` | the slope of the plane ahead followed over frames |
//! | `message.rs` | an estimate written into the `SlopeEstimate` message |
//! | `surfaces_message.rs` | an estimate's surfaces written into the `Surfaces` message |
//! | `estimator.rs` | orchestration and timings |
//! | `estimate.rs` | what the estimator returns: the estimate, its planes and timings |
//! | `inspection.rs` | what the estimator saw in its last frame (planes, roles, sampled normals) |
//! | `literal/` | the paper's stages as written (k-d tree neighbours, every-point RANSAC, depth pass-through): the `paper-literal` preset |

// `!(x > 0.0)` is how this crate says "not a positive number, NaN
// included": the NaN-safe reading is the point, not a style slip.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod baseline;
pub mod cloud;
pub mod confidence;
pub mod config;
pub mod cosine_kmeans;
pub mod cumulative_angle;
mod estimate;
pub mod estimator;
mod finish;
#[doc(hidden)]
pub mod fixtures;
pub mod ground_reach;
mod inspection;
pub mod literal;
pub mod message;
pub mod normals;
pub mod pass_through;
pub mod plane_fit;
pub mod ransac_planes;
pub mod segmentation;
pub mod selection;
pub mod sensor_noise;
pub mod statistical_outlier;
pub mod surfaces_message;
pub mod tracking;
pub mod validate;
mod workers;

pub use cloud::CloudView;
pub use config::{
    parse_method, ConfigError, CumulativeConfig, EstimatorConfig, KmeansConfig, NormalsConfig,
    OutlierConfig, PassThroughConfig, RansacConfig, RoadConfig, SegmentationConfig,
    SelectionConfig, TrackingConfig,
};
pub use estimator::{
    Estimate, Estimator, FrameInfo, InspectedNormal, Inspection, PlaneEstimate, StageTimings,
};
pub use sensor_noise::NoiseModel;
pub use slope_ipc_types::{EstimateStatus, SlopeMethod};
