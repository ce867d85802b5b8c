//! The camera's parameters as libfreenect2 reports them (IR intrinsics and
//! distortion, the colour camera's calibration, the depth processing
//! settings), and the checks that keep libfreenect2's registration
//! arithmetic defined: pure, no device and no library needed.

use super::error::Kinect2Error;

/// Width of the depth (IR) image, pixels.
pub const DEPTH_WIDTH: usize = 512;
/// Height of the depth (IR) image, pixels.
pub const DEPTH_HEIGHT: usize = 424;
/// Width of the colour image, pixels.
pub const COLOR_WIDTH: usize = 1920;
/// Height of the colour image, pixels.
pub const COLOR_HEIGHT: usize = 1080;
/// Pixels of a depth image.
pub const DEPTH_PIXELS: usize = DEPTH_WIDTH * DEPTH_HEIGHT;

/// libfreenect2's depth processing configuration (`Freenect2Device::Config`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthConfig {
    /// Depth below this is dropped, metres.
    pub min_depth_m: f32,
    /// Depth beyond this is dropped, metres.
    pub max_depth_m: f32,
    /// Removes some flying pixels.
    pub bilateral_filter: bool,
    /// Removes pixels on depth edges (noisy on a time-of-flight camera).
    pub edge_aware_filter: bool,
}

impl Default for DepthConfig {
    /// libfreenect2's defaults, as its `Config()` documents them (0.5 m,
    /// 4.5 m, both filters on); the binding's tests check them against the
    /// library's own.
    fn default() -> Self {
        Self {
            min_depth_m: 0.5,
            max_depth_m: 4.5,
            bilateral_filter: true,
            edge_aware_filter: true,
        }
    }
}

/// Intrinsics and distortion of the IR (depth) camera, as libfreenect2
/// reports them: pixel centres at +0.5, images horizontally mirrored.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IrParams {
    pub fx: f32,
    pub fy: f32,
    pub cx: f32,
    pub cy: f32,
    pub k1: f32,
    pub k2: f32,
    pub k3: f32,
    pub p1: f32,
    pub p2: f32,
}

/// The colour camera's factory parameters (intrinsics and the polynomial
/// depth-to-colour mapping), field for field libfreenect2's
/// `ColorCameraParams`: only the registration interprets them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ColorParams {
    pub fx: f32,
    pub fy: f32,
    pub cx: f32,
    pub cy: f32,
    pub shift_d: f32,
    pub shift_m: f32,
    pub mx_x3y0: f32,
    pub mx_x0y3: f32,
    pub mx_x2y1: f32,
    pub mx_x1y2: f32,
    pub mx_x2y0: f32,
    pub mx_x0y2: f32,
    pub mx_x1y1: f32,
    pub mx_x1y0: f32,
    pub mx_x0y1: f32,
    pub mx_x0y0: f32,
    pub my_x3y0: f32,
    pub my_x0y3: f32,
    pub my_x2y1: f32,
    pub my_x1y2: f32,
    pub my_x2y0: f32,
    pub my_x0y2: f32,
    pub my_x1y1: f32,
    pub my_x1y0: f32,
    pub my_x0y1: f32,
    pub my_x0y0: f32,
}

impl ColorParams {
    /// Focal lengths and principal point of the 1920 x 1080 colour image:
    /// `[fx, fy, cx, cy]`.
    pub fn intrinsics(&self) -> [f32; 4] {
        [self.fx, self.fy, self.cx, self.cy]
    }
}

/// Checks that `value` is finite and within `lo..=hi`.
fn in_range(name: &str, value: f32, lo: f32, hi: f32) -> Result<(), Kinect2Error> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(Kinect2Error::InvalidParams(format!(
            "{name} = {value} is outside {lo} ..= {hi}"
        )))
    }
}

/// Refuses camera parameters for which libfreenect2's registration would
/// convert a non-finite or out-of-`int`-range coordinate (undefined
/// behaviour in C++). The bounds are generous for a Kinect v2 (IR fx ~365,
/// colour fx ~1081, shift_d ~863, shift_m ~52, polynomial coefficients
/// below 1) and keep every mapped coordinate, and the colour offset
/// `cx + cy * 1920`, well inside `i32`.
pub fn validate_params(ir: &IrParams, color: &ColorParams) -> Result<(), Kinect2Error> {
    in_range("IR fx", ir.fx, 200.0, 2000.0)?;
    in_range("IR fy", ir.fy, 200.0, 2000.0)?;
    in_range("IR cx", ir.cx, 0.0, DEPTH_WIDTH as f32)?;
    in_range("IR cy", ir.cy, 0.0, DEPTH_HEIGHT as f32)?;
    for (name, k) in [
        ("IR k1", ir.k1),
        ("IR k2", ir.k2),
        ("IR k3", ir.k3),
        ("IR p1", ir.p1),
        ("IR p2", ir.p2),
    ] {
        in_range(name, k, -1.0, 1.0)?;
    }
    let c = color;
    in_range("colour fx", c.fx, 200.0, 5000.0)?;
    in_range("colour fy", c.fy, 200.0, 5000.0)?;
    in_range(
        "colour cx",
        c.cx,
        -(COLOR_WIDTH as f32),
        2.0 * COLOR_WIDTH as f32,
    )?;
    in_range(
        "colour cy",
        c.cy,
        -(COLOR_HEIGHT as f32),
        2.0 * COLOR_HEIGHT as f32,
    )?;
    in_range("colour shift_d", c.shift_d, 1.0, 1e5)?;
    in_range("colour shift_m", c.shift_m, -1000.0, 1000.0)?;
    let polynomial = [
        c.mx_x3y0, c.mx_x0y3, c.mx_x2y1, c.mx_x1y2, c.mx_x2y0, c.mx_x0y2, c.mx_x1y1, c.mx_x1y0,
        c.mx_x0y1, c.mx_x0y0, c.my_x3y0, c.my_x0y3, c.my_x2y1, c.my_x1y2, c.my_x2y0, c.my_x0y2,
        c.my_x1y1, c.my_x1y0, c.my_x0y1, c.my_x0y0,
    ];
    for value in polynomial {
        in_range("a colour polynomial coefficient", value, -1.0, 1.0)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinect_like() -> (IrParams, ColorParams) {
        let ir = IrParams {
            fx: 365.5,
            fy: 365.5,
            cx: 257.3,
            cy: 205.9,
            k1: 0.0905,
            k2: -0.2685,
            k3: 0.0911,
            ..Default::default()
        };
        let color = ColorParams {
            fx: 1081.37,
            fy: 1081.37,
            cx: 959.5,
            cy: 539.5,
            shift_d: 863.0,
            shift_m: 52.0,
            mx_x1y0: 0.64,
            mx_x0y0: 0.14,
            my_x0y1: 0.64,
            my_x0y0: 0.002,
            ..Default::default()
        };
        (ir, color)
    }

    #[test]
    fn plausible_parameters_pass_and_broken_ones_are_named() {
        let (ir, color) = kinect_like();
        validate_params(&ir, &color).expect("a Kinect-like calibration");
        for (bad, name) in [
            (IrParams { fx: f32::NAN, ..ir }, "IR fx"),
            (IrParams { cy: 1e9, ..ir }, "IR cy"),
            (
                IrParams {
                    k2: f32::INFINITY,
                    ..ir
                },
                "IR k2",
            ),
            (IrParams { fy: 0.0, ..ir }, "IR fy"),
        ] {
            let message = validate_params(&bad, &color)
                .expect_err("broken IR parameters")
                .to_string();
            assert!(message.contains(name), "{message}");
        }
        let message = validate_params(
            &ir,
            &ColorParams {
                shift_d: 0.0,
                ..color
            },
        )
        .expect_err("shift_d of 0 divides by zero")
        .to_string();
        assert!(message.contains("shift_d"), "{message}");
        let broken = ColorParams {
            my_x0y3: f32::NAN,
            ..color
        };
        let message = validate_params(&ir, &broken)
            .expect_err("a NaN coefficient")
            .to_string();
        assert!(message.contains("polynomial coefficient"), "{message}");
    }

    #[test]
    fn the_depth_defaults_are_those_libfreenect2_documents() {
        let config = DepthConfig::default();
        assert_eq!(
            (config.min_depth_m, config.max_depth_m),
            (0.5, 4.5),
            "{config:?}"
        );
        assert!(config.bilateral_filter && config.edge_aware_filter);
    }
}
