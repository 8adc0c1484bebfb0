//! Deterministic Gaussian noise and quantisation.
//!
//! The generator is xoshiro256** seeded through splitmix64, written here so
//! that a seed gives the same image whatever crate versions are used; normal
//! deviates come from the Box-Muller transform (`ln`, `sqrt`, `sin`, `cos`
//! of the standard library, whose last bit could in principle differ between
//! platforms' math libraries).

/// A small deterministic pseudo-random generator (xoshiro256**).
#[derive(Clone, Debug)]
pub struct Rng {
    s: [u64; 4],
    spare: Option<f64>,
}

impl Rng {
    /// A generator whose state is filled from `seed` by splitmix64 (any seed,
    /// including 0, is fine).
    pub fn new(seed: u64) -> Rng {
        let mut x = seed;
        let mut next = || {
            x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        };
        Rng {
            s: [next(), next(), next(), next()],
            spare: None,
        }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[1].wrapping_mul(5).rotate_left(7).wrapping_mul(9);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in `[0, 1)`, a multiple of `2^-53`.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal deviate (mean 0, standard deviation 1), Box-Muller;
    /// deviates come in pairs, the second is kept for the next call.
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let u1 = 1.0 - self.uniform(); // in (0, 1]: ln is finite
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// Add to every value an independent normal deviate of standard deviation
/// `std` (same units as the values), drawn in row-major order from
/// [`Rng::new`]`(seed)`. Nothing happens when `std <= 0`.
pub fn add_gaussian_noise(data: &mut [f64], std: f64, seed: u64) {
    if std.is_nan() || std <= 0.0 {
        return;
    }
    let mut rng = Rng::new(seed);
    for v in data.iter_mut() {
        *v += std * rng.normal();
    }
}

/// Quantise like an unsigned integer image of `bits` bits read back as real
/// numbers: `v -> round(clamp(v, 0, 1) (2^bits - 1)) / (2^bits - 1)`.
/// `bits` between 1 and 32.
pub fn quantise(data: &mut [f64], bits: u8) {
    let levels = ((1u64 << bits.clamp(1, 32)) - 1) as f64;
    for v in data.iter_mut() {
        *v = (v.clamp(0.0, 1.0) * levels).round() / levels;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xoshiro_reference_values() {
        // Reference: xoshiro256** with state [1, 2, 3, 4] (Vigna's C code).
        let mut r = Rng {
            s: [1, 2, 3, 4],
            spare: None,
        };
        let got: Vec<u64> = (0..4).map(|_| r.next_u64()).collect();
        assert_eq!(got, vec![11520, 0, 1509978240, 1215971899390074240]);
    }

    #[test]
    fn splitmix_reference_value() {
        // splitmix64 from seed 0 gives 0xE220A8397B1DCDAF first.
        assert_eq!(Rng::new(0).s[0], 0xE220_A839_7B1D_CDAF);
    }

    #[test]
    fn normal_moments() {
        let mut r = Rng::new(42);
        let n = 200_000;
        let z: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let mean = z.iter().sum::<f64>() / n as f64;
        let var = z.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.01, "{var}");
    }
}
