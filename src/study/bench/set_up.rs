//! The measurements every mesh of the benchmark starts with: the assembly,
//! writing its output (the floor under it), and the unit of every ratio,
//! the best factorization here (faer's numeric LLᵀ and one solve, the
//! symbolic analysis apart, on one thread and on both cores, whichever is
//! faster on this mesh; and the whole on one thread), with the rows they
//! make.
//!
//! Both thread counts are timed because neither always wins: on a 2-core
//! VM (Intel Xeon) faer's two-thread factorization was slower than its
//! sequential one at every h from 1/64 to 1/1024 (2.9× at 1/64, 1.7× at
//! 1/256, 1.14× at 1/1024, in `results/performance.csv` of 553ea0c), and
//! a unit slower than the machine's best flatters every ratio measured in
//! it.

use std::time::Instant;

use anyhow::Result;
use contactlab_solvers::numerics::linalg::{CholeskyAnalysis, SparseCholesky};
use nalgebra_sparse::{CooMatrix, CsrMatrix};

use super::PerfRow;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::study::runner::median;

/// A measurement whose timed runs add up to less than this is repeated
/// (up to [`MAX_SET_UP_RUNS`] runs) until they reach it: one run of a few
/// milliseconds on a shared machine is one sample of its noise (the
/// assembly at 1/64 read 0.20, 0.90, 0.34 and 0.46 × the factorization in
/// four `reproduce` runs of one sample each).
pub(super) const MIN_TIMED_SECONDS: f64 = 0.2;

/// The most runs of one short measurement.
pub(super) const MAX_SET_UP_RUNS: usize = 51;

/// Times `f` once as a warm-up and then at least `runs` more times, more
/// while the timed runs add up to less than [`MIN_TIMED_SECONDS`] (with
/// `runs` = 0: the warm-up alone, cold); returns (first result, times).
pub(super) fn timed<T>(runs: usize, mut f: impl FnMut() -> Result<T>) -> Result<(T, Vec<f64>)> {
    let t = Instant::now();
    let first = f()?;
    let warm = t.elapsed().as_secs_f64();
    if runs == 0 {
        return Ok((first, vec![warm]));
    }
    let mut times: Vec<f64> = Vec::with_capacity(runs);
    while times.len() < runs
        || (times.iter().sum::<f64>() < MIN_TIMED_SECONDS && times.len() < MAX_SET_UP_RUNS)
    {
        let t = Instant::now();
        f()?;
        times.push(t.elapsed().as_secs_f64());
    }
    Ok((first, times))
}

/// A with one jump pinned by a spring: the stiffness with the semicoercive
/// mode removed, same size and pattern.
pub fn pinned(d: &Discretization) -> CsrMatrix<f64> {
    let a = d.problem.a();
    let t = d.problem.contacts()[0].t;
    let k = d.problem.scales().stiffness;
    let mut coo = CooMatrix::new(a.nrows(), a.ncols());
    for (i, j, &v) in a.triplet_iter() {
        coo.push(i, j, v);
    }
    coo.push(t, t, k);
    CsrMatrix::from(&coo)
}

/// Seconds of one mesh's set-up measurements, each timed at least `runs`
/// times after a warm-up, more if short ([`timed`]; 0: the warm-up alone,
/// cold).
pub(super) struct SetUp {
    /// Assembly: both matrices, the loads and the problem with its checks.
    pub(super) assembly: Vec<f64>,
    /// A fresh copy of A and of M's values on its pattern: the memory the assembly must at least write
    /// (allocation, first touch of its pages, the copy), the floor under it.
    pub(super) output: Vec<f64>,
    /// The best factorization here, the unit: numeric LLᵀ of A (rigid mode
    /// pinned) and one solve on [`SetUp::factorization_threads`] threads,
    /// the faster of [`FACTORIZATION_THREADS`] by median, the symbolic
    /// analysis done once apart.
    pub(super) factorization: Vec<f64>,
    pub(super) factorization_threads: usize,
    /// The same on the other thread count: the slower, not the unit.
    pub(super) slower: Vec<f64>,
    pub(super) slower_threads: usize,
    /// That symbolic analysis (AMD, supernodes).
    pub(super) symbolic: Vec<f64>,
    /// Symbolic and numeric factorization and one solve on one thread.
    pub(super) sequential: Vec<f64>,
}

/// The solver column of the best factorization's rows (their variant
/// column says on how many threads).
pub const FACTORIZATION: &str = "faer LLᵀ";

/// The thread counts the best factorization is chosen from: one, and the
/// machine's two cores.
pub const FACTORIZATION_THREADS: [usize; 2] = [1, 2];

/// "1 thread", "2 threads".
pub fn threads_label(threads: usize) -> String {
    format!("{threads} thread{}", if threads == 1 { "" } else { "s" })
}

/// Assembles `scene` at `h`, copies its matrices and factors its stiffness
/// (rigid mode pinned) with one solve; see [`SetUp`].
pub(super) fn assemble_and_factor(
    scene: &Scene,
    h: MeshSize,
    runs: usize,
    factorization_runs: usize,
) -> Result<(Discretization, SetUp)> {
    let (d, assembly) = timed(runs, || Ok(Discretization::new(scene, h)?))?;
    let (_, output) = timed(runs, || {
        let m = d.problem.mass_on_stiffness_pattern().map(<[f64]>::to_vec);
        let copy = (d.problem.a().clone(), m);
        Ok(std::hint::black_box(copy).0.nnz())
    })?;
    let a = pinned(&d);
    let (_, sequential) = timed(runs, || {
        let c = SparseCholesky::new(&a)?;
        let mut b = d.problem.f().to_vec();
        c.solve_vec(&mut b);
        Ok(b[0])
    })?;
    let (analysis, symbolic) = timed(runs, || Ok(CholeskyAnalysis::new(&a)?))?;
    let mut numeric = Vec::with_capacity(FACTORIZATION_THREADS.len());
    for threads in FACTORIZATION_THREADS {
        let (_, times) = timed(factorization_runs, || {
            let mut b = d.problem.f().to_vec();
            analysis.factor_and_solve(threads, &mut b)?;
            Ok(b[0])
        })?;
        numeric.push((threads, times));
    }
    // The faster by median is the unit; on a tie, the first (one thread).
    numeric.sort_by(|x, y| median(&x.1).total_cmp(&median(&y.1)));
    let [
        (factorization_threads, factorization),
        (slower_threads, slower),
    ]: [(usize, Vec<f64>); 2] = numeric.try_into().expect("two thread counts");
    let times = SetUp {
        assembly,
        output,
        factorization,
        factorization_threads,
        slower,
        slower_threads,
        symbolic,
        sequential,
    };
    Ok((d, times))
}

/// Pushes one mesh's set-up rows.
pub(super) fn push_set_up(mesh: &mut MeshRows<'_>, times: &SetUp, large: bool) {
    let once = |note: &str| match (large, note) {
        (true, "") => "once".to_string(),
        (true, _) => format!("{note}, once"),
        (false, _) => note.to_string(),
    };
    let runs = |t: &[f64], what: String| match (large, t.len()) {
        (true, n) if n > 1 => format!("{what}, median of {n} after a warm-up"),
        (true, 1) => format!("{what}, once after a warm-up"),
        _ => once(&what),
    };
    let (best, other) = (
        threads_label(times.factorization_threads),
        threads_label(times.slower_threads),
    );
    let unit = format!(
        "the unit of every ratio: numeric LLᵀ + one solve on {best}, the faster here of 1 and 2 threads, the symbolic analysis done once (row symbolic)"
    );
    let f = runs(&times.factorization, unit);
    mesh.push(
        "factorization",
        FACTORIZATION,
        &times.factorization,
        "done",
        f,
    )
    .variant = best.clone();
    let slower =
        format!("numeric LLᵀ + one solve on {other}: slower here than on {best}, not the unit");
    let f = runs(&times.slower, slower);
    mesh.push(
        "factorization_slower",
        FACTORIZATION,
        &times.slower,
        "done",
        f,
    )
    .variant = other;
    let f = once("AMD ordering and supernodal analysis, once per pattern");
    mesh.push("symbolic", "faer", &times.symbolic, "done", f);
    let f = once("symbolic + numeric + one solve on one thread");
    mesh.push(
        "factorization_sequential",
        "faer LLᵀ, 1 thread",
        &times.sequential,
        "done",
        f,
    );
    mesh.push("assembly", "-", &times.assembly, "done", once(""));
    let copy = once("a fresh copy of A and M: what the assembly must write");
    mesh.push("output", "-", &times.output, "done", copy);
}

/// Rows of one mesh's measurements, with the factorization as the unit.
pub(super) struct MeshRows<'a> {
    pub(super) rows: &'a mut Vec<PerfRow>,
    pub(super) h: MeshSize,
    pub(super) unknowns: usize,
    pub(super) factorization: f64,
    /// One product A·v on the mesh (median seconds): the work unit.
    pub(super) product: f64,
}

impl MeshRows<'_> {
    /// Pushes a row of `times` (median, ratio and work units in this mesh's
    /// units) and returns it, for a caller to fill in what else it knows.
    pub(super) fn push(
        &mut self,
        what: &str,
        solver: &str,
        times: &[f64],
        status: &str,
        note: String,
    ) -> &mut PerfRow {
        let m = median(times);
        self.rows.push(PerfRow {
            what: what.into(),
            solver: solver.into(),
            variant: String::new(),
            h: self.h.to_string(),
            unknowns: self.unknowns,
            runs: times.len(),
            median_seconds: m,
            min_seconds: times.iter().copied().fold(f64::INFINITY, f64::min),
            ratio_to_factorization: m / self.factorization,
            work_units: m / self.product,
            status: status.into(),
            certificate: f64::NAN,
            pressure_error: f64::NAN,
            work: 0,
            note,
        });
        self.rows.last_mut().expect("just pushed")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short measurement is repeated until its runs add up (counts, not
    /// speed); a cold one is the warm-up alone; a long one is not repeated
    /// beyond the runs asked for.
    #[test]
    fn short_measurements_are_repeated_and_long_ones_are_not() {
        let mut calls = 0;
        let (_, times) = timed(1, || {
            calls += 1;
            Ok(())
        })
        .unwrap();
        assert_eq!(times.len(), MAX_SET_UP_RUNS);
        assert_eq!(calls, MAX_SET_UP_RUNS + 1);
        let (_, times) = timed(0, || Ok(())).unwrap();
        assert_eq!(times.len(), 1);
        let (_, times) = timed(2, || {
            std::thread::sleep(std::time::Duration::from_secs_f64(MIN_TIMED_SECONDS));
            Ok(())
        })
        .unwrap();
        assert_eq!(times.len(), 2);
    }
}
