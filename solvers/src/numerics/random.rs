//! Deterministic pseudo-random numbers (no dependency): Knuth's MMIX linear
//! congruential generator, the top 53 bits of its state as a double. Used
//! to perturb starting points reproducibly and by tests.

/// A linear congruential generator, state x ← 6364136223846793005·x +
/// 1442695040888963407 (mod 2⁶⁴) (Knuth, TAOCP vol. 2, MMIX).
#[derive(Clone, Debug)]
pub(crate) struct Lcg(u64);

impl Lcg {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next number, uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The next number, uniform in [−1, 1).
    pub fn symmetric(&mut self) -> f64 {
        self.uniform() * 2.0 - 1.0
    }
}
