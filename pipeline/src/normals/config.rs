//! [`NormalsConfig`]: the parameters of the normal estimation.

use serde::{Deserialize, Serialize};

use crate::validate::{at_least, count_in, non_negative, InvalidValue};

/// Normal estimation (`normals/`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NormalsConfig {
    /// K: neighbours of the local plane fit (paper: 100).
    pub neighbours: usize,
    /// Largest pixel window radius tried before the k-d tree takes over.
    pub max_window_radius_px: usize,
    /// Fit each neighbourhood for depth noise along the viewing ray
    /// (`C^-1 r`) instead of isotropic noise (the smallest eigenvector, as
    /// the paper); see `normals/ray_noise.rs`.
    pub ray_noise_correction: bool,
    /// Keep only the normals of interior points, whose smallest window
    /// holds K of the plane's points (border points see one side of their
    /// neighbourhood, and on real surfaces the mixed pixels and multipath of
    /// the edge); all normals when fewer than K or a tenth are interior.
    /// Off by default: the ablation (pipeline README) shows no gain.
    pub interior_only: bool,
    /// The neighbourhood spans at least this radius on the surface, metres
    /// (more than K points near the camera); 0 = K points only.
    pub min_patch_radius_m: f64,
    /// ...and at least this many times the RMS distance of the plane's
    /// RANSAC inliers from their TLS plane (depth noise, quantisation and
    /// roughness together): the noise bias of a local PCA normal is about
    /// `2 (sigma / r)^2` radians, 0.3 degrees at 20; 0 = off.
    pub patch_per_rms: f64,
    /// Pixel windows (ours) or exactly the K nearest from a k-d tree (the
    /// paper, `literal/knn_normals.rs`).
    pub neighbourhood: crate::literal::NormalsNeighbourhood,
}

impl Default for NormalsConfig {
    fn default() -> Self {
        Self {
            neighbours: 100,
            max_window_radius_px: 80,
            ray_noise_correction: false,
            interior_only: false,
            min_patch_radius_m: 0.1,
            patch_per_rms: 20.0,
            neighbourhood: crate::literal::NormalsNeighbourhood::Window,
        }
    }
}

impl NormalsConfig {
    /// This configuration for a plane whose RANSAC inliers lie `rms_m` (RMS)
    /// from their TLS plane: the patch radius grows to `patch_per_rms *
    /// rms_m` when that is larger than `min_patch_radius_m`.
    pub fn for_plane_noise(&self, rms_m: f64) -> NormalsConfig {
        let scaled = self.patch_per_rms * rms_m;
        NormalsConfig {
            min_patch_radius_m: if scaled.is_finite() {
                self.min_patch_radius_m.max(scaled)
            } else {
                self.min_patch_radius_m
            },
            ..self.clone()
        }
    }
}

impl NormalsConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        count_in("neighbours", self.neighbours, 3, 1000)?;
        at_least("max_window_radius_px", self.max_window_radius_px, 1)?;
        non_negative("min_patch_radius_m", self.min_patch_radius_m)?;
        non_negative("patch_per_rms", self.patch_per_rms)
    }
}
