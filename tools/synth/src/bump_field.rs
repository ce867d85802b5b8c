//! Smooth random-looking bumps on a face: a height field over the face's
//! two in-plane coordinates (s, t), the sum of a few plane waves
//! `a_k sin(k_k · (s, t) + φ_k)` with random directions, wavelengths and
//! phases drawn from a seeded generator. Its value and gradient are exact,
//! and so are the bounds the ray march relies on ([`BumpField::max_height_m`],
//! [`BumpField::max_slope`]).

use std::f64::consts::TAU;

use rand::Rng;

/// Share of the roughness each wave gets (they add up to 1, so the field
/// never exceeds the roughness).
const AMPLITUDE_SHARES: [f64; 3] = [0.45, 0.35, 0.2];
/// Each wave's wavelength is the typical wavelength times a factor drawn
/// from this range.
const WAVELENGTH_FACTORS: (f64, f64) = (0.75, 1.5);

/// One plane wave of a [`BumpField`].
#[derive(Debug, Clone, Copy, PartialEq)]
struct Wave {
    amplitude_m: f64,
    /// Wave vector in (s, t), radians per metre.
    wave_vector: [f64; 2],
    phase_rad: f64,
}

impl Wave {
    fn angle(&self, s: f64, t: f64) -> f64 {
        self.wave_vector[0] * s + self.wave_vector[1] * t + self.phase_rad
    }
}

/// A height field over a face: the displacement along the face's outward
/// normal at in-plane coordinates (s, t), metres.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BumpField {
    waves: Vec<Wave>,
}

impl BumpField {
    /// No bumps: a plane.
    pub fn flat() -> Self {
        Self::default()
    }

    /// A random field whose height never exceeds `roughness_m` in size,
    /// with wavelengths between 0.75 and 1.5 times `wavelength_m` (> 0).
    pub fn random<R: Rng + ?Sized>(roughness_m: f64, wavelength_m: f64, rng: &mut R) -> Self {
        let (low, high) = WAVELENGTH_FACTORS;
        let waves = AMPLITUDE_SHARES
            .iter()
            .map(|share| {
                let direction = rng.random::<f64>() * TAU;
                let wavelength = wavelength_m * (low + (high - low) * rng.random::<f64>());
                let k = TAU / wavelength;
                Wave {
                    amplitude_m: share * roughness_m,
                    wave_vector: [k * direction.cos(), k * direction.sin()],
                    phase_rad: rng.random::<f64>() * TAU,
                }
            })
            .collect();
        Self { waves }
    }

    /// Displacement at (s, t), metres.
    pub fn height_m(&self, s: f64, t: f64) -> f64 {
        self.waves
            .iter()
            .map(|w| w.amplitude_m * w.angle(s, t).sin())
            .sum()
    }

    /// Partial derivatives of the displacement by s and t.
    pub fn gradient(&self, s: f64, t: f64) -> [f64; 2] {
        self.waves.iter().fold([0.0, 0.0], |[ds, dt], w| {
            let c = w.amplitude_m * w.angle(s, t).cos();
            [ds + c * w.wave_vector[0], dt + c * w.wave_vector[1]]
        })
    }

    /// An upper bound of `|height_m|` everywhere.
    pub fn max_height_m(&self) -> f64 {
        self.waves.iter().map(|w| w.amplitude_m.abs()).sum()
    }

    /// An upper bound of the gradient's length everywhere.
    pub fn max_slope(&self) -> f64 {
        self.waves
            .iter()
            .map(|w| w.amplitude_m.abs() * w.wave_vector[0].hypot(w.wave_vector[1]))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn field(seed: u64) -> BumpField {
        BumpField::random(0.03, 0.2, &mut ChaCha8Rng::seed_from_u64(seed))
    }

    #[test]
    fn bounds_hold_and_gradient_matches_finite_differences() {
        let f = field(3);
        assert!((f.max_height_m() - 0.03).abs() < 1e-15);
        // Slope bound from the wavelengths: at most 0.03 * 2π / 0.15.
        assert!(f.max_slope() <= 0.03 * TAU / 0.15 + 1e-12);
        let h = 1e-6;
        let mut largest: f64 = 0.0;
        for i in 0..400 {
            let (s, t) = (f64::from(i) * 0.013 - 2.0, f64::from(i % 37) * 0.029 - 0.5);
            let z = f.height_m(s, t);
            assert!(z.abs() <= f.max_height_m());
            largest = largest.max(z.abs());
            let [gs, gt] = f.gradient(s, t);
            let ns = (f.height_m(s + h, t) - f.height_m(s - h, t)) / (2.0 * h);
            let nt = (f.height_m(s, t + h) - f.height_m(s, t - h)) / (2.0 * h);
            assert!((gs - ns).abs() < 1e-7 && (gt - nt).abs() < 1e-7);
            assert!(gs.hypot(gt) <= f.max_slope());
        }
        // Not a plane: the bumps reach a good part of their bound.
        assert!(largest > 0.015, "largest bump {largest}");
    }

    #[test]
    fn same_seed_same_field_other_seed_other_field() {
        assert_eq!(field(5), field(5));
        assert_ne!(field(5), field(6));
        assert_eq!(BumpField::flat().height_m(0.3, 0.4), 0.0);
        assert_eq!(BumpField::flat().max_slope(), 0.0);
    }
}
