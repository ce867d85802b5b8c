//! One axis of the sample grid: which pixels are sample points, and which
//! pixels each sample point stands for.
//!
//! The sample points are every `stride`-th pixel counted from the nearer
//! end of the axis, from pixel `stride / 2` (so the set is symmetric about
//! the axis's centre: the mirror image of a frame samples the mirror image
//! of its pixels, and its planes are found on the mirrored cells; a grid
//! counted from one end samples a mirrored frame one pixel off). The two
//! halves meet at the centre with a gap of up to `2 * stride - 1` pixels.
//! Each pixel stands for the nearest sample point; a pixel halfway between
//! two goes to the one nearer the axis's centre (the rule is its own
//! mirror image but at the centre pixel of an odd axis, halfway between
//! two sample points equally far from the centre: it goes to the lower).

/// The sample points of one axis and the run of pixels each stands for.
#[derive(Debug, Default, Clone)]
pub struct SampleAxis {
    /// The pixel of each sample point, increasing.
    pub at: Vec<u32>,
    /// Per sample point, the first pixel of its run, then the axis's
    /// length: sample point `j` stands for pixels
    /// `run_start[j]..run_start[j + 1]` (empty without sample points).
    pub run_start: Vec<u32>,
    /// Per pixel: the sample point it stands for (empty without sample
    /// points).
    pub of_pixel: Vec<u32>,
    /// The axis's length and stride the buffers were built for.
    built: Option<(usize, usize)>,
}

impl SampleAxis {
    /// The sample points of an axis `len` pixels long, every `stride`-th
    /// (at least 1); kept as they are when built for the same values.
    pub fn build(&mut self, len: usize, stride: usize) {
        let s = stride.max(1);
        if self.built == Some((len, s)) {
            return;
        }
        self.built = Some((len, s));
        let half = s / 2;
        self.at.clear();
        self.at.extend(
            (0..len)
                .filter(|&u| u.min(len - 1 - u) % s == half)
                .map(|u| u as u32),
        );
        self.run_start.clear();
        self.of_pixel.clear();
        if self.at.is_empty() {
            return;
        }
        self.run_start.push(0);
        for pair in self.at.windows(2) {
            self.run_start.push(boundary(pair[0], pair[1], len));
        }
        self.run_start.push(len as u32);
        for (j, run) in self.run_start.windows(2).enumerate() {
            self.of_pixel
                .extend(std::iter::repeat_n(j as u32, (run[1] - run[0]) as usize));
        }
    }

    /// Number of sample points.
    pub fn len(&self) -> usize {
        self.at.len()
    }

    /// True without sample points.
    pub fn is_empty(&self) -> bool {
        self.at.is_empty()
    }
}

/// The first pixel nearer sample point `b` than `a` (`a < b`), a pixel
/// halfway between them going to the one nearer the centre of an axis
/// `len` pixels long (to `a` when both are as near).
fn boundary(a: u32, b: u32, len: usize) -> u32 {
    let sum = a + b;
    if sum % 2 == 1 {
        return sum / 2 + 1;
    }
    // Twice a pixel's distance from the centre, `|2 x - (len - 1)|`.
    let off_centre = |x: u32| (2 * i64::from(x) - (len as i64 - 1)).abs();
    if off_centre(b) < off_centre(a) {
        sum / 2
    } else {
        sum / 2 + 1
    }
}

#[cfg(test)]
mod tests {
    use super::SampleAxis;

    fn axis(len: usize, stride: usize) -> SampleAxis {
        let mut a = SampleAxis::default();
        a.build(len, stride);
        a
    }

    #[test]
    fn kinect2_width_samples_every_fourth_pixel_from_both_edges() {
        let a = axis(512, 4);
        assert_eq!(a.len(), 128);
        assert_eq!(&a.at[..3], &[2, 6, 10]);
        assert_eq!(&a.at[62..66], &[250, 254, 257, 261]);
        assert_eq!(a.at[127], 509);
        assert_eq!(&a.run_start[..3], &[0, 4, 8]);
        // 254 and 257 split the centre's pixels 255 | 256.
        assert_eq!(a.run_start[64], 256);
        assert_eq!(a.run_start[128], 512);
    }

    /// Brute force: every axis length and stride up to a few, the
    /// sample set is its own mirror image, every pixel stands for a
    /// nearest sample point, and the runs mirror the runs but at the
    /// centre pixel of an odd axis between two sample points equally far.
    #[test]
    fn sample_points_and_runs_are_their_own_mirror_image_and_nearest() {
        for len in 1..70usize {
            for stride in 1..7 {
                let a = axis(len, stride);
                let mirror = |x: u32| len as u32 - 1 - x;
                let at: Vec<u32> = a.at.iter().rev().map(|&x| mirror(x)).collect();
                assert_eq!(at, a.at, "len {len} stride {stride}");
                if a.is_empty() {
                    assert!(a.of_pixel.is_empty() && a.run_start.is_empty());
                    continue;
                }
                assert_eq!(a.of_pixel.len(), len);
                let n = a.len() as u32;
                for u in 0..len as u32 {
                    let j = a.of_pixel[u as usize];
                    let d = a.at[j as usize].abs_diff(u);
                    let nearest = a.at.iter().map(|&x| x.abs_diff(u)).min().unwrap();
                    assert_eq!(d, nearest, "len {len} stride {stride} pixel {u}");
                    let centre_tie = 2 * u + 1 == len as u32
                        && a.at.iter().filter(|&&x| x.abs_diff(u) == d).count() == 2;
                    if !centre_tie {
                        assert_eq!(
                            a.of_pixel[mirror(u) as usize],
                            n - 1 - j,
                            "len {len} stride {stride} pixel {u}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_stride_beyond_the_axis_has_no_sample_points() {
        assert!(axis(10, 1000).is_empty());
        assert!(axis(10, usize::MAX).is_empty());
        assert!(axis(0, 4).is_empty());
        assert_eq!(axis(1, 1).at, vec![0]);
    }
}
