//! A small deterministic generator for the fuzz tests: the same mutants on every run and
//! machine, so a failure found once is found again.

/// A 64-bit linear congruential generator with Knuth's MMIX constants (multiplier
/// 6364136223846793005, increment 1442695040888963407; Knuth, TAOCP vol. 2, 3.3.4), taking
/// the high 31 bits of each state.
#[derive(Debug, Clone)]
pub struct Lcg(pub u64);

impl Lcg {
    /// The next value (31 bits).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0 >> 33
    }

    /// A value in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// One of `items` (which must not be empty).
    pub fn pick<'a>(&mut self, items: &[&'a str]) -> &'a str {
        items[self.below(items.len())]
    }
}
