//! The optional depth-noise correction of a neighbourhood's covariance
//! (`ray_noise_correction`, module doc of `normals`).

use nalgebra::Vector3;

const LATERAL_JITTER_PX: f64 = 0.5;

/// Variance of the depth noise along the unit `ray` to subtract from the
/// covariance `cov` of a patch at depth `z_m` with (uncorrected) unit normal
/// `normal`, seen through a camera of focal length `focal_px`: the Kinect v2
/// model, capped below the variance that would make `cov - s^2 r r^T`
/// singular.
pub fn ray_noise_variance(
    cov: &[f64; 6],
    ray: &Vector3<f64>,
    z_m: f64,
    normal: &Vector3<f64>,
    focal_px: f64,
    scale: f64,
) -> f64 {
    let model = scale * ray_noise_model(ray, z_m, normal, focal_px);
    if !(model > 0.0) {
        return 0.0;
    }
    // 1 / r^T C^-1 r, through the adjugate: det / (r^T adj r).
    let [a, b, c, d, e, f] = *cov;
    let adj = [
        d * f - e * e,
        c * e - b * f,
        b * e - c * d,
        a * f - c * c,
        b * c - a * e,
        a * d - b * b,
    ];
    let det = a * adj[0] + b * adj[1] + c * adj[2];
    let quad = ray.x * (adj[0] * ray.x + adj[1] * ray.y + adj[2] * ray.z)
        + ray.y * (adj[1] * ray.x + adj[3] * ray.y + adj[4] * ray.z)
        + ray.z * (adj[2] * ray.x + adj[4] * ray.y + adj[5] * ray.z);
    if !(det > 0.0) || !(quad > 0.0) {
        return 0.0;
    }
    let cap = det / quad;
    model.min(0.95 * cap)
}

/// Variance of the modelled depth noise along the unit `ray` (before any
/// cap) of a patch at depth `z_m` with unit normal `normal`: the Kinect v2
/// axial model, mm quantisation and lateral jitter (module doc).
pub fn ray_noise_model(ray: &Vector3<f64>, z_m: f64, normal: &Vector3<f64>, focal_px: f64) -> f64 {
    if !(z_m > 0.0) || !(ray.z > 1e-3) || !(focal_px > 0.0) {
        return 0.0;
    }
    let cos_incidence = normal.dot(ray).abs();
    let theta = cos_incidence.clamp(0.0, 1.0).acos().min(89f64.to_radians());
    let grazing = theta * theta / (std::f64::consts::FRAC_PI_2 - theta).powi(2);
    let sigma_mm = (1.5 - 0.5 * z_m + 0.3 * z_m * z_m + 0.1 * z_m.powf(1.5) * grazing).max(0.0);
    // Millimetre depth quantisation: uniform, variance 1/12 mm^2.
    // Lateral jitter: the depth of a plane through pixel ray (a, b, 1) z
    // changes by -z n_xy / (n . r~) per unit of a or b.
    let slope =
        (normal.x * normal.x + normal.y * normal.y).sqrt() / (cos_incidence * (1.0 / ray.z));
    let lateral_m = LATERAL_JITTER_PX / focal_px * z_m * slope.min(50.0);
    let var_z = (sigma_mm * sigma_mm + 1.0 / 12.0) * 1e-6 + lateral_m * lateral_m;
    var_z / (ray.z * ray.z)
}
