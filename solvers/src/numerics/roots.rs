//! Roots of monotone functions of one variable.

/// A root of a nonincreasing function near `x0`: bracketed by doubling
/// steps from `step`, then bisected to the last bit. None if no sign change
/// is found within 200 doublings.
pub(crate) fn monotone_root(f: impl Fn(f64) -> f64, x0: f64, step: f64) -> Option<f64> {
    let f0 = f(x0);
    if f0 == 0.0 {
        return Some(x0);
    }
    // f nonincreasing: f0 > 0 → the root is to the right.
    let dir = if f0 > 0.0 { 1.0 } else { -1.0 };
    let mut step = step.abs().max(f64::MIN_POSITIVE);
    let (mut lo, mut hi) = (x0, x0);
    let mut found = false;
    for _ in 0..200 {
        let x = x0 + dir * step;
        if f(x) * f0 <= 0.0 {
            if dir > 0.0 {
                hi = x;
            } else {
                lo = x;
            }
            found = true;
            break;
        }
        if dir > 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        step *= 2.0;
    }
    if !found {
        return None;
    }
    // Invariant: the sign of f changes between lo and hi.
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let fm = f(mid);
        if fm == 0.0 {
            return Some(mid);
        }
        if (fm > 0.0) == (dir > 0.0) {
            // Same side as x0.
            if dir > 0.0 { lo = mid } else { hi = mid }
        } else if dir > 0.0 {
            hi = mid
        } else {
            lo = mid
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotone_roots_are_found_on_either_side() {
        let f = |x: f64| 3.0 - x;
        assert!((monotone_root(f, 0.0, 0.1).unwrap() - 3.0).abs() < 1e-12);
        assert!((monotone_root(f, 10.0, 0.1).unwrap() - 3.0).abs() < 1e-12);
        let flat = |_x: f64| 1.0;
        assert!(monotone_root(flat, 0.0, 1.0).is_none());
    }
}
