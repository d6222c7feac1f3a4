//! The linear multigrid step of TNNMG: one V-cycle with symmetric
//! Gauss-Seidel on the truncated Galerkin hierarchy (Gräser & Sander 2019,
//! section 4.2; Kornhuber 1994 for truncated bases in contact).
//!
//! The coordinates at a kink of the nonsmooth energy (closed contact
//! t_i = 0, stick s_i = 0) are truncated: the correction keeps them at
//! zero, so the fine-level operator is A restricted to the others, and the
//! prolongation onto the finest level is P_T = T P (T zeroes the truncated
//! rows). The coarse operators are the Galerkin products
//! A_{L−1} = P_Tᵀ A P_T and A_l = P_lᵀ A_{l+1} P_l below.
//!
//! Truncation touches only contact unknowns, so the hierarchy is built once
//! untruncated (A⁰_l) and truncation is a local correction: T A T = A − E
//! with E_ij = A_ij where i or j is truncated, hence
//! A_{L−1} = A⁰_{L−1} − Pᵀ E P and A_l = A⁰_l − C_l with
//! C_l = P_lᵀ C_{l+1} P_l. Each C_l lives near the contact zone (O(h⁻¹)
//! entries), so a change of the truncated set costs O(h⁻¹), not the O(h⁻²)
//! of rebuilding the products (which was a fifth of a 1/256 solve). A
//! coarse unknown whose fine support is truncated entirely is left at zero.

use std::time::Instant;

use crate::numerics::linalg::Csr;

use crate::multigrid::galerkin::galerkin;
use crate::multigrid::parts::Parts;
use crate::multigrid::smoother::{Place, diagonal_position, linear_sweep, place_in_row, shift_at};
use crate::numerics::linalg::{TransposePlan, spmv_into, spmv_transpose_into};
use crate::numerics::threads::threads;

/// Eigenvalues below this fraction of the largest are the coarsest
/// operator's kernel (the rigid mode, when no jump is truncated): its
/// solve is the pseudo-inverse's, the least-squares answer of a consistent
/// system.
const KERNEL_FRACTION: f64 = 1e-12;

/// A coarse unknown is left at zero when truncation takes its diagonal
/// below this fraction of the untruncated one. A coarse hat function whose
/// fine support keeps any untruncated node keeps a diagonal of order one
/// quarter of its own; one truncated entirely keeps only rounding (1e-16).
const FIXED_FRACTION: f64 = 1e-10;

/// The exact solve on the coarsest level (h = 1/2: at most 17 unknowns,
/// whatever the mesh): the pseudo-inverse of its matrix on the unknowns
/// that are not fixed, from a symmetric eigendecomposition (faer). Gauss-
/// Seidel there left the near-rigid motion of an upper body held at a few
/// closed nodes unresolved, and TNNMG's line search then stretched every
/// correction by 1.5-1.7 at a rate of 0.5 per iteration.
struct CoarsestSolve {
    free: Vec<usize>,
    pinv: faer::Mat<f64>,
}

impl CoarsestSolve {
    fn new(level: &Level) -> Self {
        let free: Vec<usize> = (0..level.a.nrows()).filter(|&k| !level.fixed[k]).collect();
        let mut dense = faer::Mat::<f64>::zeros(free.len(), free.len());
        let mut position = vec![usize::MAX; level.a.nrows()];
        for (i, &k) in free.iter().enumerate() {
            position[k] = i;
        }
        for (row, col, &v) in level.a.triplet_iter() {
            if position[row] != usize::MAX && position[col] != usize::MAX {
                dense[(position[row], position[col])] = v;
            }
        }
        let nf = free.len();
        let pinv = match dense.self_adjoint_eigen(faer::Side::Lower) {
            Ok(evd) => {
                let (u, s) = (evd.U(), evd.S().column_vector());
                let largest = (0..nf).fold(0.0f64, |m, i| m.max(s[i].abs()));
                faer::Mat::from_fn(nf, nf, |i, j| {
                    (0..nf)
                        .filter(|&e| s[e] > KERNEL_FRACTION * largest)
                        .map(|e| u[(i, e)] * u[(j, e)] / s[e])
                        .sum()
                })
            }
            Err(_) => faer::Mat::zeros(nf, nf),
        };
        Self { free, pinv }
    }

    fn solve(&self, b: &[f64], x: &mut [f64]) {
        x.fill(0.0);
        for (i, &k) in self.free.iter().enumerate() {
            x[k] = self
                .free
                .iter()
                .enumerate()
                .map(|(j, &l)| self.pinv[(i, j)] * b[l])
                .sum();
        }
    }
}

/// A coarse level: its Galerkin matrix for the current truncated set, the
/// places of the diagonal entries, the unknowns left at zero, and the
/// untruncated values of the entries the current truncation changed (only
/// those: a truncation touches O(h⁻¹) entries near Γ_K, and a copy of
/// every value was a twelfth of the peak memory at h = 1/1024; a copy of
/// the diagonal was 2.7 bytes per finest unknown).
struct Level {
    a: Csr,
    diag: Vec<Place>,
    /// The several-core Gauss-Seidel ordering of `a`'s rows, if it has one.
    parts: Option<Parts>,
    /// Left at zero: untruncated, the rows without a positive diagonal;
    /// truncated, also those whose diagonal the truncation took below
    /// [`FIXED_FRACTION`] of its untruncated value.
    fixed: Vec<bool>,
    /// (row, untruncated diagonal) of each row with a positive diagonal
    /// that the current truncation changed.
    diagonal_changed: Vec<(usize, f64)>,
    /// The untruncated values' table length, when `a`'s rows are shared: a
    /// truncation gives the few rows it changes copies of their own past
    /// it, and the others stay shared.
    shared_len: usize,
    /// (row, its shared start) of each row given a copy of its own.
    moved: Vec<(usize, u32)>,
    /// (position, untruncated value) of each entry changed, when `a`'s
    /// values are stored row by row.
    touched: Vec<(usize, f64)>,
}

impl Level {
    /// The level of Galerkin matrix `a`, each distinct row of values stored
    /// once when they are few ([`Csr::shared`]): on a uniform mesh the
    /// coarse levels have as few distinct rows as the stiffness, and a
    /// sweep over the level below the finest then reads 4 bytes of values
    /// per row instead of 8 per entry (it was a quarter of a V-cycle's time
    /// at h = 1/1024). Every value reads back to the bit.
    fn new(a: Csr) -> Result<Self, String> {
        let a = a.shared();
        // A row without a positive diagonal stays fixed.
        let (mut diag, mut fixed) = (Vec::with_capacity(a.nrows()), Vec::with_capacity(a.nrows()));
        for k in 0..a.nrows() {
            let found = diagonal_position(&a, k, 0.0);
            diag.push(found.map_or(Ok(0), |p| place_in_row(&a, k, p))?);
            fixed.push(found.is_none());
        }
        Ok(Self {
            diagonal_changed: Vec::new(),
            parts: Parts::new(&a, threads()),
            shared_len: if a.is_shared() { a.stored_values() } else { 0 },
            a,
            diag,
            fixed,
            moved: Vec::new(),
            touched: Vec::new(),
        })
    }

    /// Back to the untruncated matrix (latest change first, so that an
    /// entry changed twice gets its first saved value).
    fn restore(&mut self) {
        // The rows a truncation fixed had a positive diagonal: free again.
        for (k, _) in self.diagonal_changed.drain(..) {
            self.fixed[k] = false;
        }
        if self.a.is_shared() {
            self.a.unshare_undo(self.moved.drain(..), self.shared_len);
            return;
        }
        let values = self.a.values_mut();
        for (p, value) in self.touched.drain(..).rev() {
            values[p] = value;
        }
    }

    /// Subtracts the correction `c` (merged triplets, all on the pattern)
    /// and marks the unknowns whose diagonal vanished.
    fn subtract(&mut self, c: &[(usize, usize, f64)]) {
        let shared = self.a.is_shared();
        for &(i, j, value) in c {
            let p = self
                .a
                .position(i, j)
                .expect("a Galerkin correction lies on the Galerkin pattern");
            let q = p - self.a.row_range(i).0;
            let (row, moved) = self.a.row_values_mut(i, self.shared_len);
            if let Some(before) = moved {
                self.moved.push((i, before));
            }
            if !shared {
                self.touched.push((p, row[q]));
            }
            // Each entry once (merged), so its value here is untruncated.
            if i == j && !self.fixed[i] {
                self.diagonal_changed.push((i, row[q]));
            }
            row[q] -= value;
        }
        for &(k, full) in &self.diagonal_changed {
            let p = self.a.row_range(k).0 + usize::from(self.diag[k]);
            // Fixed unless above the fraction (a NaN diagonal fixes it).
            let kept = self.a.value_at(k, p).partial_cmp(&(FIXED_FRACTION * full));
            self.fixed[k] = kept != Some(std::cmp::Ordering::Greater);
        }
    }
}

/// Sums the triplets of equal position (sorted by row, then column).
fn merge(mut t: Vec<(usize, usize, f64)>) -> Vec<(usize, usize, f64)> {
    t.sort_unstable_by_key(|&(i, j, _)| (i, j));
    let mut out: Vec<(usize, usize, f64)> = Vec::with_capacity(t.len());
    for (i, j, v) in t {
        match out.last_mut() {
            Some(last) if (last.0, last.1) == (i, j) => last.2 += v,
            _ => out.push((i, j, v)),
        }
    }
    out
}

/// Pᵀ C P for C given by merged triplets: two sparse products, (C P) then
/// Pᵀ (C P), each merged.
fn galerkin_triplets(p: &Csr, c: &[(usize, usize, f64)]) -> Vec<(usize, usize, f64)> {
    let row = |k: usize| {
        let (cols, vals) = p.row(k);
        cols.iter().zip(vals)
    };
    let cp = merge(
        c.iter()
            .flat_map(|&(i, j, v)| row(j).map(move |(b, &pjb)| (i, b, v * pjb)))
            .collect(),
    );
    merge(
        cp.iter()
            .flat_map(|&(i, b, v)| row(i).map(move |(a, &pia)| (a, b, pia * v)))
            .collect(),
    )
}

/// The truncated hierarchy of one operator A, with the V-cycle's vectors
/// (allocated once, not per cycle).
pub(crate) struct Hierarchy {
    /// The places of A's diagonal entries within their rows.
    pub(crate) diag: Vec<Place>,
    /// The several-core Gauss-Seidel ordering of A's rows, if it has one.
    pub(crate) parts: Option<Parts>,
    /// Each prolongation's restriction Pᵀ r on every thread, if it has a
    /// plan ([`TransposePlan`]; else two halves).
    restrictions: Vec<Option<TransposePlan>>,
    /// The truncated unknowns the levels are built for, ascending (a few
    /// contact unknowns: the flags of every unknown are the caller's, and
    /// a copy of them here was a byte per unknown).
    truncated: Vec<usize>,
    /// The diagonal D added to A on the finest level.
    shift: Vec<f64>,
    /// Levels 0 … L−1, coarse to fine, below the finest.
    levels: Vec<Level>,
    coarsest: CoarsestSolve,
    /// Each coarse level's correction and right-hand side (the finest
    /// level's are the V-cycle's own arguments).
    x: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    /// Each coarse level's residual (the finest level's lives in the
    /// V-cycle's `ac` argument).
    r: Vec<Vec<f64>>,
    /// Seconds the V-cycles spent on the finest level (its sweeps and
    /// transfers), summed until the caller takes them
    /// ([`Hierarchy::take_finest_seconds`]).
    finest_seconds: f64,
    /// Seconds of whole V-cycles, likewise ([`Hierarchy::take_cycle_seconds`]).
    cycle_seconds: f64,
}

impl Hierarchy {
    /// The untruncated Galerkin hierarchy of `a` for the prolongations `p`
    /// (coarse to fine): A⁰_{L−1} = Pᵀ A P, A⁰_l = P_lᵀ A⁰_{l+1} P_l.
    /// A coarse level whose diagonal lies past a row's 65 536th entry is
    /// refused (see [`Place`]).
    pub(crate) fn new(a: &Csr, diag: Vec<Place>, p: &[Csr]) -> Result<Self, String> {
        // Pᵀ only while its product is formed: the V-cycle restricts with P
        // itself (at h = 1/1024 the stored transposes were 150 MB).
        let top = p.len() - 1;
        let mut coarse = vec![galerkin(&p[top].transpose(), a, &p[top])?];
        for l in (0..top).rev() {
            let above = coarse.last().expect("one at least");
            let next = galerkin(&p[l].transpose(), above, &p[l])?;
            coarse.push(next);
        }
        coarse.reverse();
        let levels = coarse
            .into_iter()
            .map(Level::new)
            .collect::<Result<Vec<Level>, String>>()?;
        let zeros = || {
            levels
                .iter()
                .map(|l| vec![0.0; l.a.nrows()])
                .collect::<Vec<_>>()
        };
        let coarsest = CoarsestSolve::new(&levels[0]);
        Ok(Self {
            diag,
            parts: Parts::new(a, threads()),
            restrictions: p.iter().map(|p| TransposePlan::new(p, threads())).collect(),
            truncated: Vec::new(),
            shift: Vec::new(),
            coarsest,
            x: zeros(),
            b: zeros(),
            r: zeros(),
            levels,
            finest_seconds: 0.0,
            cycle_seconds: 0.0,
        })
    }

    /// The seconds of whole V-cycles since the last call.
    pub(crate) fn take_cycle_seconds(&mut self) -> f64 {
        std::mem::take(&mut self.cycle_seconds)
    }

    /// The seconds the V-cycles spent on the finest level since the last
    /// call (the rest of a V-cycle is its coarse levels).
    pub(crate) fn take_finest_seconds(&mut self) -> f64 {
        std::mem::take(&mut self.finest_seconds)
    }

    /// Makes the hierarchy that of T(A + D)T for the truncated set
    /// `truncated` and D = diag(`shift`) (see the module); nothing to do
    /// when they are the current ones.
    pub(crate) fn truncate(&mut self, a: &Csr, p: &[Csr], truncated: &[bool], shift: &[f64]) {
        // An all-zero D is kept as none (the given-friction laws have no
        // curvature): no vector of the finest size for it.
        let shift = if shift.iter().all(|&d| d == 0.0) {
            &[][..]
        } else {
            shift
        };
        let set = || {
            truncated
                .iter()
                .enumerate()
                .filter(|(_, cut)| **cut)
                .map(|(j, _)| j)
        };
        if set().eq(self.truncated.iter().copied()) && self.shift == shift {
            return;
        }
        self.truncated.clear();
        self.truncated.extend(set());
        self.shift.clear();
        self.shift.extend_from_slice(shift);
        // E: the entries of A in a truncated row or column (A symmetric).
        let mut e = Vec::new();
        for &j in &self.truncated {
            let (cols, vals) = a.row(j);
            for (i, &v) in cols.iter().zip(vals) {
                e.push((j, i, v));
                if !truncated[i] {
                    e.push((i, j, v));
                }
            }
        }
        for (k, &d) in shift.iter().enumerate() {
            if d != 0.0 && !truncated[k] {
                e.push((k, k, -d));
            }
        }
        let mut c = merge(e);
        for l in (0..self.levels.len()).rev() {
            c = galerkin_triplets(&p[l], &c);
            let level = &mut self.levels[l];
            level.restore();
            level.subtract(&c);
        }
        self.coarsest = CoarsestSolve::new(&self.levels[0]);
    }

    /// One V-cycle from zero for A_T c = d (d zero on the truncated set),
    /// `sweeps` = (below, finest): that many Gauss-Seidel sweeps before and
    /// after each coarse correction below the finest level, and on it; the
    /// correction is written to `c` (zero on the truncated set) and A_T c,
    /// A_T = T(A + D)T, to `ac`: the last sweep leaves it, so that the
    /// conjugate gradients need no product of their own. `a` is the finest
    /// level's matrix, `p` the prolongations, `truncated` the flags of the
    /// set last given to [`Hierarchy::truncate`]. The finest level works in
    /// `d` and `c` themselves (no copies of the finest size).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn v_cycle(
        &mut self,
        a: &Csr,
        p: &[Csr],
        truncated: &[bool],
        d: &[f64],
        (coarse_sweeps, finest_sweeps): (usize, usize),
        c: &mut [f64],
        ac: &mut [f64],
    ) {
        let Self {
            diag,
            parts,
            restrictions,
            truncated: _,
            shift,
            levels,
            coarsest,
            x,
            b,
            r,
            finest_seconds,
            cycle_seconds,
        } = self;
        let cycle_clock = Instant::now();
        let top = levels.len();
        let level = |l: usize| match levels.get(l) {
            Some(lv) => (
                &lv.a,
                &lv.diag[..],
                lv.parts.as_ref(),
                &[][..],
                &lv.fixed[..],
            ),
            None => (a, &diag[..], parts.as_ref(), &shift[..], truncated),
        };
        let sweeps = |l: usize| {
            if l == top {
                finest_sweeps
            } else {
                coarse_sweeps
            }
        };
        // Down: smooth, restrict the residual (zero on the truncated set,
        // so Pᵀ r = P_Tᵀ r on the finest level).
        for l in (1..=top).rev() {
            let clock = (l == top).then(Instant::now);
            let (matrix, dg, split, dk, fixed) = level(l);
            let (x_below, x_here) = x.split_at_mut(l);
            let (b_below, b_here) = b.split_at_mut(l);
            let (xl, bl): (&mut [f64], &[f64]) = if l == top {
                (&mut *c, d)
            } else {
                (&mut x_here[0], &b_here[0])
            };
            xl.fill(0.0);
            // The finest level's residual lives in `ac`, free until the
            // last sweep writes it (a vector of the finest size less).
            let rl: &mut [f64] = if l == top { &mut *ac } else { &mut r[l] };
            // The last sweep leaves the residual behind (one pass over
            // the level's matrix instead of two); none: x = 0, r = b.
            let s = sweeps(l);
            for sweep in 1..=s {
                let last = (sweep == s).then_some(&mut *rl);
                linear_sweep(matrix, dg, split, dk, bl, xl, fixed, true, last);
            }
            if s == 0 {
                for ((rk, bk), &cut) in rl.iter_mut().zip(bl).zip(fixed) {
                    *rk = if cut { 0.0 } else { *bk };
                }
            }
            // x below is free until the coarse solve: the scratch of the
            // two-half restriction, when P has no plan.
            match &restrictions[l - 1] {
                Some(plan) => plan.apply(&p[l - 1], rl, &mut b_below[l - 1]),
                None => {
                    spmv_transpose_into(&p[l - 1], rl, &mut b_below[l - 1], &mut x_below[l - 1])
                }
            }
            if let Some(t) = clock {
                *finest_seconds += t.elapsed().as_secs_f64();
            }
        }
        coarsest.solve(&b[0], &mut x[0]);
        // Up: prolongate (P_T = T P on the finest level), add, smooth
        // backward.
        for l in 1..=top {
            let clock = (l == top).then(Instant::now);
            let (matrix, dg, split, dk, fixed) = level(l);
            let (below, here) = x.split_at_mut(l);
            let (xl, bl): (&mut [f64], &[f64]) = if l == top {
                (&mut *c, d)
            } else {
                (&mut here[0], &b[l])
            };
            let rl: &mut [f64] = if l == top { &mut *ac } else { &mut r[l] };
            spmv_into(&p[l - 1], &below[l - 1], rl);
            for ((xk, rk), &cut) in xl.iter_mut().zip(&*rl).zip(fixed) {
                if !cut {
                    *xk += rk;
                }
            }
            // The last sweep on the finest level leaves its residual in
            // `ac` (free again once prolongated): A_T c = b − r.
            let s = sweeps(l);
            for sweep in 1..=s {
                let last = (l == top && sweep == s).then_some(&mut *rl);
                linear_sweep(matrix, dg, split, dk, bl, xl, fixed, false, last);
            }
            if l == top && s > 0 {
                for (q, bk) in rl.iter_mut().zip(bl) {
                    *q = bk - *q;
                }
            }
            if let Some(t) = clock {
                *finest_seconds += t.elapsed().as_secs_f64();
            }
        }
        if sweeps(top) == 0 {
            truncated_product(a, truncated, shift, c, ac);
        }
        *cycle_seconds += cycle_clock.elapsed().as_secs_f64();
    }
}

/// A_T c = T(A + D)T c into `out` for c zero on the truncated set
/// (`truncated`), D = diag(`shift`) (empty: none): one product.
pub(crate) fn truncated_product(
    a: &Csr,
    truncated: &[bool],
    shift: &[f64],
    c: &[f64],
    out: &mut [f64],
) {
    spmv_into(a, c, out);
    for (k, q) in out.iter_mut().enumerate() {
        *q = if truncated[k] {
            0.0
        } else {
            *q + shift_at(shift, k) * c[k]
        };
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::smoother::diagonal_places;
    use super::*;
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    /// The matrix of triplets `t` (duplicates summed).
    pub(in crate::multigrid) fn csr(t: &[(usize, usize, f64)], rows: usize, cols: usize) -> Csr {
        let mut coo = CooMatrix::new(rows, cols);
        for &(i, j, v) in t {
            coo.push(i, j, v);
        }
        Csr::try_from(&CsrMatrix::from(&coo)).unwrap()
    }

    /// The 1D Laplacian on 2^k − 1 interior nodes (its interior rows all
    /// alike: shared).
    fn laplacian(k: u32) -> Csr {
        let n = (1usize << k) - 1;
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 2.0));
            if i > 0 {
                t.push((i, i - 1, -1.0));
                t.push((i - 1, i, -1.0));
            }
        }
        csr(&t, n, n).shared()
    }

    /// Linear interpolation from 2^(k−1) − 1 to 2^k − 1 interior nodes.
    fn interpolation(k: u32) -> Csr {
        let (nf, nc) = ((1usize << k) - 1, (1usize << (k - 1)) - 1);
        let mut t = Vec::new();
        for j in 0..nc {
            t.extend([(2 * j, j, 0.5), (2 * j + 1, j, 1.0), (2 * j + 2, j, 0.5)]);
        }
        csr(&t, nf, nc).shared()
    }

    /// T A T: the truncated rows and columns removed.
    fn truncated(a: &Csr, cut: &[bool]) -> Csr {
        let t: Vec<_> = a
            .triplet_iter()
            .filter(|&(i, j, _)| !cut[i] && !cut[j])
            .map(|(i, j, &v)| (i, j, v))
            .collect();
        csr(&t, a.nrows(), a.ncols())
    }

    fn dense(a: &Csr) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; a.ncols()]; a.nrows()];
        for (i, j, &v) in a.triplet_iter() {
            d[i][j] = v;
        }
        d
    }

    /// Each level of the truncated hierarchy is the Galerkin product of the
    /// truncated matrix (Gräser & Sander 2019, step 3), with the coarse
    /// levels' rows shared; after another truncation and after none, the
    /// levels are those of that set, and with none the untruncated ones to
    /// the bit (what a level changed for one truncation is undone).
    #[test]
    fn truncated_levels_are_the_galerkin_products_of_the_truncated_matrix() {
        let a = laplacian(6);
        let p: Vec<Csr> = (2..=6).map(interpolation).collect();
        let mut h = Hierarchy::new(&a, diagonal_places(&a).unwrap(), &p).unwrap();
        assert!(h.levels.iter().all(|l| l.a.is_shared()));
        let untruncated: Vec<Csr> = h.levels.iter().map(|l| l.a.clone()).collect();
        let n = a.nrows();
        for cut in [
            (0..n).map(|k| k % 7 == 3 || k == 20).collect::<Vec<bool>>(),
            (0..n).map(|k| (30..40).contains(&k)).collect(),
            vec![false; n],
        ] {
            h.truncate(&a, &p, &cut, &[]);
            let mut expected = truncated(&a, &cut);
            for l in (0..h.levels.len()).rev() {
                expected = galerkin(&p[l].transpose(), &expected, &p[l]).unwrap();
                let (got, want) = (dense(&h.levels[l].a), dense(&expected));
                for (g, w) in got.iter().flatten().zip(want.iter().flatten()) {
                    assert!((g - w).abs() <= 1e-12, "level {l}: {g} vs {w}");
                }
                assert!(h.levels[l].a.is_shared(), "level {l} stays shared");
            }
        }
        for (level, before) in h.levels.iter().zip(&untruncated) {
            assert_eq!(&level.a, before);
            assert_eq!(level.a.stored_values(), before.stored_values());
        }
    }
}
