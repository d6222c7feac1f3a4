use super::*;
use crate::multigrid::parts::tests::grid;
use crate::numerics::linalg::spmv_into;

/// b − (A + D) x, zero where `fixed`, by a product.
fn residual(a: &Csr, shift: &[f64], b: &[f64], x: &[f64], fixed: &[bool]) -> Vec<f64> {
    let mut ax = vec![0.0; x.len()];
    spmv_into(a, x, &mut ax);
    (0..x.len())
        .map(|k| {
            let d = shift_at(shift, k);
            if fixed[k] {
                0.0
            } else {
                b[k] - ax[k] - d * x[k]
            }
        })
        .collect()
}

fn largest_gap(p: &[f64], q: &[f64]) -> f64 {
    p.iter()
        .zip(q)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// The sweeps that leave a residual move x exactly as the plain ones (same bits) and
/// leave the residual a product computes afterwards, to rounding: in
/// the orderings in two and three parts (separator rows last) and in the natural
/// one, from a nonzero start, with fixed rows, a shift and every law.
/// A scatter to a row swept later, or none to a separator row swept
/// earlier, leaves residuals off by O(1).
#[test]
fn fused_sweeps_leave_the_residual_of_a_product() {
    let a = grid(300);
    let n = a.nrows();
    let diag = diagonal_places(&a).expect("a grid has its diagonal");
    let b: Vec<f64> = (0..n).map(|k| ((k * 37) % 11) as f64 - 5.0).collect();
    let start: Vec<f64> = (0..n).map(|k| ((k * 13) % 7) as f64 * 0.1).collect();
    let fixed: Vec<bool> = (0..n).map(|k| k % 97 == 0).collect();
    let shift: Vec<f64> = (0..n).map(|k| if k % 5 == 0 { 0.5 } else { 0.0 }).collect();
    let laws: Vec<Local> = (0..n)
        .map(|k| match k % 4 {
            0 => Local::Jump(0.0),
            1 => Local::Slip(1.5),
            2 => Local::Huber {
                wg: 1.0,
                delta: 0.1,
            },
            _ => Local::Free,
        })
        .collect();
    let laws = Laws::of(&laws);
    let (two, three) = (
        Parts::new(&a, 2).expect("a grid splits"),
        Parts::new(&a, 3).expect("a grid splits"),
    );
    for split in [Some(&two), Some(&three), None] {
        for forward in [true, false] {
            let (mut plain, mut fused, mut r) = (start.clone(), start.clone(), vec![7.0; n]);
            linear_sweep(
                &a, &diag, split, &shift, &b, &mut plain, &fixed, forward, None,
            );
            linear_sweep(
                &a,
                &diag,
                split,
                &shift,
                &b,
                &mut fused,
                &fixed,
                forward,
                Some(&mut r),
            );
            assert_eq!(plain, fused, "split {}", split.is_some());
            let gap = largest_gap(&r, &residual(&a, &shift, &b, &fused, &fixed));
            assert!(
                gap < 1e-12,
                "linear, split {}, forward {forward}: {gap:e}",
                split.is_some()
            );
        }

        let (mut plain, mut fused, mut r) = (start.clone(), start.clone(), vec![7.0; n]);
        nonlinear_sweep(&a, &diag, split, &b, &laws, &mut plain, None);
        nonlinear_sweep(&a, &diag, split, &b, &laws, &mut fused, Some(&mut r));
        assert_eq!(plain, fused, "split {}", split.is_some());
        let none = vec![false; n];
        let gap = largest_gap(&r, &residual(&a, &[], &b, &fused, &none));
        assert!(gap < 1e-12, "nonlinear, split {}: {gap:e}", split.is_some());
    }
}

/// The threads of a split sweep write disjoint residuals: a part's
/// row scatters its move into rows of its own part only, forward and
/// backward, and never into the separator's (their residuals are set
/// by their own visit, or recomputed after a backward sweep). The
/// backward sweep's half rows once scattered into the separator's rows,
/// both threads into the same ones: lost updates that no run showed
/// twice alike. This checks the writes themselves, not a run's timing.
#[test]
fn a_part_row_scatters_into_its_own_part_only() {
    let a = grid(300);
    let diag = diagonal_places(&a).expect("a grid has its diagonal");
    // Three parts: the middle one has a neighbour on either side.
    let parts = Parts::new(&a, 3).expect("a grid splits");
    let sep = parts.in_separator();
    let mut r = vec![0.0; a.nrows()];
    let mut written = 0;
    for k in (0..a.nrows()).filter(|&k| !sep[k]) {
        for forward in [true, false] {
            // SAFETY: one thread; the grid's columns are below n.
            unsafe {
                scatter_to_swept(
                    Row::of(&a, a.values(), k, diag[k] as usize),
                    1.0,
                    (Some(sep), forward),
                    Shared::of(&mut r),
                )
            };
            // A row scatters into the rows of its pattern alone.
            for j in a.row(k).0.iter() {
                if std::mem::take(&mut r[j]) == 0.0 {
                    continue;
                }
                written += 1;
                assert!(
                    !sep[j],
                    "row {k} (forward {forward}) wrote separator row {j}"
                );
                assert_eq!(
                    parts.part_of(j),
                    parts.part_of(k),
                    "row {k} (forward {forward}) wrote row {j} of another part"
                );
            }
        }
    }
    assert!(
        written > a.nrows(),
        "the rows do scatter ({written} writes)"
    );
}

/// Each local minimizer is the minimum of its 1-D energy: no sampled
/// admissible point is lower.
#[test]
fn local_minimizers_are_exact() {
    for law in [Local::Free, Local::Jump(0.0), Local::Slip(0.7)] {
        for c in [-2.0, -0.3, 0.0, 0.5, 3.0] {
            let a = 1.7;
            let energy = |x: f64| {
                0.5 * a * x * x - c * x
                    + match law {
                        Local::Slip(b) => b * x.abs(),
                        _ => 0.0,
                    }
            };
            let x = local_minimizer(law, a, c);
            assert!(law != Local::Jump(0.0) || x <= 0.0);
            for i in -400..=400 {
                let y = i as f64 * 0.01;
                if law == Local::Jump(0.0) && y > 0.0 {
                    continue;
                }
                assert!(
                    energy(x) <= energy(y) + 1e-12,
                    "{law:?} c = {c}: {x} vs {y}"
                );
            }
        }
    }
}
