//! Stalls at floating-point resolution. An iteration whose iterate no
//! longer changes beyond a few units in the last place of its own size is
//! a fixed point of the arithmetic: no further iteration can bring it
//! closer to a tolerance it has not met. Every iterative loop of the
//! solvers asks [`Resolution::stalled`] after each step and stops with
//! [`crate::Status::InsufficientProgress`] when it says so, instead of
//! running to its cap (issue 47: 2,000,057 multigrid iterations at
//! max|Δv| ≈ 9e-20, 71 s, before the cap of one Uzawa step was reached).

/// Changes within this many units of roundoff (ε = 2.2e-16) of the
/// iterate's size are rounding: a sum of a row of A and a few updates
/// moves an entry by several ulps without any progress.
pub const ULPS: f64 = 64.0;

/// Steps in a row at resolution before a loop is called stalled: one step
/// at resolution may be the last one of a converging iteration whose own
/// test is about to be met.
pub const WINDOW: usize = 3;

/// The smallest change that is not rounding, for an iterate of largest
/// magnitude `size`.
pub fn floor(size: f64) -> f64 {
    ULPS * f64::EPSILON * size
}

/// Counts the steps in a row whose change was rounding.
#[derive(Clone, Copy, Debug, Default)]
pub struct Resolution {
    in_a_row: usize,
}

impl Resolution {
    /// After a step that changed the iterate by at most `change` (max|Δx|)
    /// and left it of size `size` (max|x|): whether the loop has stalled,
    /// [`WINDOW`] steps in a row within [`floor`]`(size)`. A zero change of
    /// a zero iterate is a stall too (nothing moves).
    pub fn stalled(&mut self, change: f64, size: f64) -> bool {
        self.step(change <= floor(size))
    }

    /// After a step of an iteration whose state has several parts: whether
    /// it has stalled, given whether every part moved by rounding only in
    /// this step (`at_resolution`).
    pub fn step(&mut self, at_resolution: bool) -> bool {
        self.in_a_row = if at_resolution { self.in_a_row + 1 } else { 0 };
        self.in_a_row >= WINDOW
    }

    /// The sentence for a stalled loop's detail.
    pub fn detail(what: &str, change: f64, size: f64) -> String {
        format!(
            "stalled at floating-point resolution: {what} changed by {change:.1e} for {WINDOW} steps in a row, within {ULPS} roundoffs of its size {size:.1e}, so no further step can meet the tolerance"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_for_a_window_in_a_row_is_a_stall_and_progress_resets_it() {
        let mut r = Resolution::default();
        let size = 1e-4;
        let tiny = 0.5 * floor(size);
        assert!(!r.stalled(tiny, size));
        assert!(!r.stalled(tiny, size));
        assert!(!r.stalled(1e-10, size), "a real change resets the count");
        for _ in 1..WINDOW {
            assert!(!r.stalled(tiny, size));
        }
        assert!(r.stalled(tiny, size));
        // Scale-free: the same pattern at any size.
        let mut r = Resolution::default();
        for _ in 1..WINDOW {
            assert!(!r.stalled(0.5 * floor(1e40), 1e40));
        }
        assert!(r.stalled(0.5 * floor(1e40), 1e40));
        assert!(!Resolution::default().stalled(f64::NAN, 1.0));
    }
}
