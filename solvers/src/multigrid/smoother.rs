//! Gauss-Seidel sweeps: the paper's pointwise relaxation with exact local
//! minimizers of the nonsmooth energy (the TNNMG smoother), and the linear
//! symmetric Gauss-Seidel of the V-cycle.
//!
//! Along coordinate k the energy J(v) = ½ vᵀAv − bᵀv + Σ_k φ_k(v_k) is
//! ½A_kk x² − c x + φ_k(x), c = b_k − Σ_{j≠k} A_kj v_j. For the given-
//! friction problem (paper (10)) φ_k is the constraint t_i ≤ 0 or
//! w_i g_i |s_i|, and the exact minimizers are c/A_kk without a law, the
//! projection min(0, c/A_kk) for a jump (paper (12)'s projection), and the
//! soft thresholding sign(c) max(|c| − w_i g_i, 0)/A_kk for a slip (no
//! smoothing of |s|: Gräser & Sander 2019, section 5.1, Example 5.3). For
//! the inner problem of the paper's Algorithm 1 (the modified Lagrangian at
//! fixed l, paper (11) and (15)) φ_k is the penalty w_i/(2r)((l_i + r t_i)⁺)²
//! or the Huber smoothing of w_i g_i |s_i|; their minimizers are the
//! relaxation's own ([`crate::relaxation::pointwise`]).

use crate::numerics::linalg::{Csr, RowColumns, RowValues};
use crate::with_values;

use super::laws::Laws;
use super::parts::{Largest, Parts, RowUpdate, Shared, sweep};
use crate::relaxation::pointwise::{minimize_jump, minimize_slip_huber};

/// The contact law along one coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Local {
    /// No contact law: the energy is quadratic along it.
    Free,
    /// A jump t_i: the constraint t_i ≤ d_i, d_i ≥ 0 the initial gap
    /// ([`crate::ContactProblem::gap`]; 0 in the paper's scene).
    Jump(f64),
    /// A slip s_i with its nodal friction bound w_i g_i.
    Slip(f64),
    /// A jump under the modified Lagrangian's penalty
    /// (w/(2r))((l + r t)⁺)², paper (11): C¹, piecewise quadratic.
    Penalty { w: f64, l: f64, r: f64 },
    /// A slip under the Huber smoothing w g φ_δ(s): C¹, piecewise quadratic.
    Huber { wg: f64, delta: f64 },
}

impl Local {
    /// Whether v_k sits at a kink of φ_k, where the truncated Newton step
    /// keeps it fixed: a closed jump, a sticking slip. The C¹ laws have none.
    pub(crate) fn at_kink(self, x: f64) -> bool {
        match self {
            Local::Jump(d) => x >= d,
            Local::Slip(b) => b > 0.0 && x == 0.0,
            _ => false,
        }
    }

    /// φ_k''(x), the curvature the Newton step adds to A_kk (zero at a kink
    /// and along the laws that are piecewise linear).
    pub(crate) fn curvature(self, x: f64) -> f64 {
        match self {
            Local::Penalty { w, l, r } if l + r * x > 0.0 => w * r,
            Local::Huber { wg, delta } if x.abs() < delta => wg / delta,
            _ => 0.0,
        }
    }

    /// The right derivative of φ_k at x in the direction c (the constraint
    /// of a jump excluded: the line search bounds the step instead).
    pub(crate) fn slope(self, x: f64, c: f64) -> f64 {
        match self {
            Local::Free | Local::Jump(_) => 0.0,
            Local::Slip(b) => {
                b * if x > 0.0 || (x == 0.0 && c > 0.0) {
                    c
                } else {
                    -c
                }
            }
            Local::Penalty { w, l, r } => w * (l + r * x).max(0.0) * c,
            Local::Huber { wg, delta } => wg * (x / delta).clamp(-1.0, 1.0) * c,
        }
    }
}

/// The position of row k's diagonal entry among A's stored entries, if it
/// is stored and above `floor`.
pub(crate) fn diagonal_position(a: &Csr, k: usize, floor: f64) -> Option<usize> {
    a.position(k, k).filter(|&p| a.value_at(k, p) > floor)
}

/// The place of a row's diagonal entry within the row (its k-th stored
/// entry), in 16 bits. A sweep reads row k from its offset anyway, so the
/// absolute position (32 bits) was 2 bytes per unknown more than the place
/// (67 MB at h = 1/4096). A row whose diagonal lies past its 65 536th entry
/// is refused ([`diagonal_places`]); a mesh's rows hold a few dozen.
pub(crate) type Place = u16;

/// The place within row k of its diagonal entry at position `p`, if it fits
/// a [`Place`].
pub(crate) fn place_in_row(a: &Csr, k: usize, p: usize) -> Result<Place, String> {
    Place::try_from(p - a.row_range(k).0).map_err(|_| {
        format!(
            "row {k} has its diagonal past its {}th stored entry, more than a sweep indexes",
            u32::from(Place::MAX) + 1
        )
    })
}

/// The place of each row's diagonal entry within its row.
///
/// Filled into a vector of its final size: collected from an iterator of
/// `Result`s it grew by doubling, to twice its size at h = 1/2048.
pub(crate) fn diagonal_places(a: &Csr) -> Result<Vec<Place>, String> {
    let mut places = Vec::with_capacity(a.nrows());
    for k in 0..a.nrows() {
        let p = diagonal_position(a, k, 0.0)
            .ok_or_else(|| format!("row {k} has no positive diagonal entry"))?;
        places.push(place_in_row(a, k, p)?);
    }
    Ok(places)
}

/// Row k of A as a sweep reads it: its columns and values, and the place
/// of its diagonal among them.
#[derive(Clone, Copy)]
pub(crate) struct Row<'a> {
    k: usize,
    cols: RowColumns<'a>,
    vals: &'a [f64],
    diag: usize,
}

impl<'a> Row<'a> {
    /// Row k, whose diagonal is its entry `diag` (its [`Place`]); `vals`
    /// are a's values (matched once per sweep: [`with_values`]).
    #[inline(always)]
    pub(crate) fn of(a: &'a Csr, vals: impl RowValues<'a>, k: usize, diag: usize) -> Self {
        let (lo, hi) = a.row_range(k);
        Row {
            k,
            cols: a.columns().row(k, lo, hi),
            vals: vals.row(k, lo, hi),
            // A place past row k's end makes `diagonal` panic rather than
            // read another row's value.
            diag,
        }
    }

    /// A_kk.
    #[inline(always)]
    fn diagonal(self) -> f64 {
        self.vals[self.diag]
    }
}

/// c_k = b_k − Σ_{j≠k} A_kj x_j, the row's sum in the order of the
/// product's ([`crate::numerics::linalg::row_dot`]).
///
/// # Safety
/// A's column indices are below x's length, and no other thread writes the
/// unknowns of row k's pattern meanwhile (see [`Parts`]).
#[inline]
unsafe fn off_diagonal_rhs(row: Row<'_>, b: f64, x: Shared) -> f64 {
    // SAFETY: by the contract.
    let sum = unsafe { x.row_dot(row.cols, row.vals) };
    b - (sum - row.diagonal() * unsafe { x.get(row.k) })
}

/// D_kk of the diagonal shift D, which is kept as an empty vector while
/// every curvature is zero (the given-friction laws).
#[inline(always)]
pub(crate) fn shift_at(shift: &[f64], k: usize) -> f64 {
    shift.get(k).copied().unwrap_or(0.0)
}

/// The exact minimizer of ½ a x² − c x + φ(x).
#[inline]
pub(crate) fn local_minimizer(law: Local, a: f64, c: f64) -> f64 {
    match law {
        Local::Free => c / a,
        Local::Jump(d) => (c / a).min(d),
        Local::Slip(bound) => c.signum() * (c.abs() - bound).max(0.0) / a,
        Local::Penalty { w, l, r } => minimize_jump(a, -c, w, l, r),
        Local::Huber { wg, delta } => minimize_slip_huber(a, -c, wg, delta),
    }
}

/// A's row count against the vectors of a sweep: the sweeps read x at A's
/// column indices without bounds checks.
fn check_sizes(a: &Csr, diag: &[Place], b: &[f64], x: &[f64]) {
    assert!(
        a.nrows() == x.len() && a.ncols() == x.len() && diag.len() == x.len() && b.len() == x.len(),
        "a sweep: A, its diagonal, b and x of one size"
    );
}

/// r_j = b_j − ((A + D) x)_j afresh for the separator's rows: after a
/// backward sweep on several threads, whose parts leave them alone (see
/// [`scatter_to_swept`]). The separator is O(h⁻¹) rows of O(h⁻²): the
/// sums cost a small fraction of the sweep. Fixed rows are zeroed after.
fn separator_residuals(a: &Csr, parts: &Parts, shift: &[f64], b: &[f64], x: &[f64], r: &mut [f64]) {
    for &j in parts.separator() {
        let row = a.row(j);
        // SAFETY: a Csr keeps its column indices below ncols =
        // x.len() (checked by the sweep).
        let ax = unsafe { crate::numerics::linalg::row_dot_at(row.0, row.1, x) };
        r[j] = b[j] - ax - shift_at(shift, j) * x[j];
    }
}

/// r_j −= A_jk·δ for the rows j ≠ k of row k's pattern that a sweep
/// (`forward` or backward) visits before k (A symmetric: A_jk = A_kj):
/// after x_k moved by δ, the residuals those rows left are brought up to
/// date, so that a sweep leaves b − A x behind without a product of its
/// own. In the ordering of `separator` ([`Parts::in_separator`]) a forward
/// sweep visits a half's rows ascending, then the separator's; a backward
/// one the separator's descending, then each half's. Without one, the
/// natural order. Column indices ascend within a row, so the rows below k
/// end at its diagonal and those above start after it. (A row not yet
/// visited may be written too: its own visit sets its residual afresh.)
///
/// # Safety
/// A's column indices are below r's length, and no other thread touches r
/// at the rows written (the parts' own rows: see [`Parts`]).
#[inline(always)]
unsafe fn scatter_to_swept(
    row: Row<'_>,
    delta: f64,
    (separator, forward): (Option<&[bool]>, bool),
    r: Shared,
) {
    if delta == 0.0 {
        return;
    }
    let Row {
        k,
        cols,
        vals,
        diag,
    } = row;
    let (below, above) = (0..diag, diag + 1..cols.len());
    // SAFETY: by the contract.
    let update = |q: usize| {
        let j = cols.get(q);
        unsafe { r.set(j, r.get(j) - vals[q] * delta) }
    };
    match separator {
        None if forward => below.for_each(update),
        None => above.for_each(update),
        // A separator's row, forward: every part's row and the separator's
        // rows below it. Backward, none: the separator's residuals are
        // recomputed after the parts ([`separator_residuals`]).
        Some(sep) if sep[k] => {
            if forward {
                below
                    .chain(above)
                    .filter(|&q| !sep[cols.get(q)] || cols.get(q) < k)
                    .for_each(update);
            }
        }
        // A part's row: its part's rows below it (forward); backward, its
        // part's rows above it (a row of another part that it couples to is
        // in the separator, see [`Parts`]), and not the separator's rows, although swept
        // before: the parts' rows reach them, and their threads would
        // race on their residuals (lost updates: the residuals, and the
        // runs, differed from one run to the next). The sweep recomputes
        // them once all parts are done ([`separator_residuals`]).
        Some(sep) if forward => below.filter(|&q| !sep[cols.get(q)]).for_each(update),
        Some(sep) => above.filter(|&q| !sep[cols.get(q)]).for_each(update),
    }
}

/// A row of the nonlinear sweep ([`nonlinear_sweep`]).
struct NonlinearRow<'a, V> {
    a: &'a Csr,
    vals: V,
    diag: &'a [Place],
    f: &'a [f64],
    laws: &'a Laws,
    /// Where f − A v is left, if anywhere.
    defect: Option<Shared>,
    separator: Option<&'a [bool]>,
}

impl<'a, V: RowValues<'a>> RowUpdate for NonlinearRow<'a, V> {
    type Out = Largest;

    /// v_k the exact minimizer along coordinate k; its move.
    #[inline(always)]
    unsafe fn update(&self, k: usize, x: Shared) -> Largest {
        // SAFETY: sizes checked by the sweep; the parts' ordering keeps the
        // other thread off row k's pattern and off the defects it writes.
        unsafe {
            let row = Row::of(self.a, self.vals, k, self.diag[k] as usize);
            let c = off_diagonal_rhs(row, self.f[k], x);
            let akk = row.diagonal();
            let new = local_minimizer(self.laws[k], akk, c);
            let delta = new - x.get(k);
            x.set(k, new);
            if let Some(rs) = self.defect {
                rs.set(k, c - akk * new);
                scatter_to_swept(row, delta, (self.separator, true), rs);
            }
            Largest(delta.abs())
        }
    }
}

/// A row of the linear sweep ([`linear_sweep`]).
struct LinearRow<'a, V> {
    a: &'a Csr,
    vals: V,
    diag: &'a [Place],
    shift: &'a [f64],
    b: &'a [f64],
    fixed: &'a [bool],
    /// Where b − (A + D) x is left, if anywhere.
    residual: Option<Shared>,
    /// The separator, and whether the sweep is forward.
    scatter: (Option<&'a [bool]>, bool),
}

impl<'a, V: RowValues<'a>> RowUpdate for LinearRow<'a, V> {
    type Out = ();

    /// x_k from row k of (A + D) x = b, or kept at zero where fixed.
    #[inline(always)]
    unsafe fn update(&self, k: usize, x: Shared) {
        // SAFETY: as in the nonlinear sweep.
        unsafe {
            if self.fixed[k] {
                if let Some(rs) = self.residual {
                    rs.set(k, 0.0);
                }
                return;
            }
            // The reciprocal first: it depends on nothing the sweep moves,
            // so it leaves the chain of rows (each waits for the unknown
            // the row before set) a multiplication instead of a division.
            let row = Row::of(self.a, self.vals, k, self.diag[k] as usize);
            let inverse = 1.0 / (row.diagonal() + shift_at(self.shift, k));
            let c = off_diagonal_rhs(row, self.b[k], x);
            let new = c * inverse;
            let delta = new - x.get(k);
            x.set(k, new);
            if let Some(rs) = self.residual {
                rs.set(k, 0.0);
                scatter_to_swept(row, delta, self.scatter, rs);
            }
        }
    }
}

/// One forward sweep of the nonlinear Gauss-Seidel on J (see the module),
/// on several threads in the ordering of `parts` when given. With `defect`
/// it also leaves f − A v of the swept v there, in the same pass over A:
/// row k's defect is c − A_kk v_k when it is swept, and each later move of
/// a neighbour is scattered into it ([`scatter_to_swept`]); this replaced
/// the product that followed the presmoothing. Returns the largest move
/// |v_k − v_k before| of the sweep.
pub(crate) fn nonlinear_sweep(
    a: &Csr,
    diag: &[Place],
    parts: Option<&Parts>,
    f: &[f64],
    laws: &Laws,
    v: &mut [f64],
    defect: Option<&mut [f64]>,
) -> f64 {
    check_sizes(a, diag, f, v);
    if let Some(r) = &defect {
        assert_eq!(r.len(), v.len(), "a sweep: one defect per unknown");
    }
    let (separator, defect) = (parts.map(Parts::in_separator), defect.map(Shared::of));
    let Largest(moved) = with_values!(a.values(), vals => sweep(parts, v, true, &NonlinearRow {
        a,
        vals,
        diag,
        f,
        laws,
        defect,
        separator,
    }));
    moved
}

/// Forward (`forward`) or backward linear Gauss-Seidel on (A + D) x = b,
/// D = diag(`shift`) (empty: none), keeping x_k = 0 where `fixed` says so
/// (the truncated coordinates); on several threads in the ordering of `parts`
/// when given. With `residual` it also leaves b − (A + D) x of the swept x
/// there (zero where `fixed`), in the same pass over A (see
/// [`nonlinear_sweep`]): the V-cycle's presmoothing and its residual, one
/// pass instead of two; and after its last postsmoothing (A + D) x = b − r,
/// the product the conjugate gradients need.
#[allow(clippy::too_many_arguments)]
pub(crate) fn linear_sweep(
    a: &Csr,
    diag: &[Place],
    parts: Option<&Parts>,
    shift: &[f64],
    b: &[f64],
    x: &mut [f64],
    fixed: &[bool],
    forward: bool,
    mut residual: Option<&mut [f64]>,
) {
    check_sizes(a, diag, b, x);
    assert_eq!(fixed.len(), x.len(), "a sweep: one flag per unknown");
    if let Some(r) = &residual {
        assert_eq!(r.len(), x.len(), "a sweep: one residual per unknown");
    }
    let (rs, separator) = (
        residual.as_deref_mut().map(Shared::of),
        parts.map(Parts::in_separator),
    );
    with_values!(a.values(), vals => sweep(parts, x, forward, &LinearRow {
        a,
        vals,
        diag,
        shift,
        b,
        fixed,
        residual: rs,
        scatter: (separator, forward),
    }));
    if let (Some(h), Some(r), false) = (parts, residual.as_deref_mut(), forward) {
        separator_residuals(a, h, shift, b, x, r);
    }
    // A later row's move reached the fixed rows' residuals too.
    if let Some(r) = residual {
        for (rk, &cut) in r.iter_mut().zip(fixed) {
            if cut {
                *rk = 0.0;
            }
        }
    }
}

#[cfg(test)]
#[path = "smoother_tests.rs"]
mod tests;
