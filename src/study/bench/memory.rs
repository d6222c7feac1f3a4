//! Where a large solve's memory goes: the peak resident memory of one
//! Coulomb solve in a fresh process (the hidden `bench-one` command), split
//! into the assembly's peak, the assembled problem, and what the solver
//! reports keeping (the factor of A_II and the Schur complement S).
//!
//! Resident figures are the kernel's (`/proc/self/status`, Linux); the
//! solver's are exact byte counts of its arrays, from its diagnostics.

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use contactlab_solvers::{Friction, Law};

use crate::coulomb::continuation::Schedule;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::solve::{Assembled, Caps, level_for, solve, solver_entry};
use crate::study::runner::median;

/// One solve's memory, measured in a fresh process.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MemoryUse {
    pub h: MeshSize,
    pub solver: String,
    pub status: String,
    pub seconds: f64,
    /// Peak resident memory of the whole process (VmHWM), KiB.
    pub peak_kb: u64,
    /// Peak resident memory once the problem is assembled, before any
    /// solve: the assembly with its temporaries, KiB.
    pub assembly_peak_kb: u64,
    /// Resident memory the assembled problem holds (A, f, mesh and
    /// unknowns, M only for a solver that reads it: the growth of VmRSS
    /// across the assembly), KiB.
    pub problem_kb: u64,
    /// The values of the factor of A_II, as the solver reports (bytes).
    pub factor_values_bytes: Option<f64>,
    /// The dense Schur complement S, as the solver reports (bytes).
    pub schur_bytes: Option<f64>,
    /// Seconds of one product A·v with the finest level's A as the solve
    /// got it (its storage) and the machine's cores, the median of
    /// [`PRODUCTS`] timed before the solve and as many after it: the work
    /// unit of [`MemoryUse::phases`]. Both sides, because this host's
    /// speed drifts within a run: timed after the solve alone, the product
    /// took 30.3 ms in one committed run and 7.9-12.5 ms in others, and
    /// the work units moved with it (197 against 306-386).
    #[serde(default)]
    pub product_seconds: Option<f64>,
    /// The medians of the products timed before and after the solve
    /// (seconds): how far the machine's speed moved meanwhile.
    #[serde(default)]
    pub product_sides: Option<(f64, f64)>,
    /// The solver's seconds by phase, as it reports them (its diagnostics
    /// ending in `_seconds`), in its order.
    #[serde(default)]
    pub phases: Vec<(String, f64)>,
}

/// Products timed for [`product_seconds`], after one warm-up (and for
/// [`MemoryUse::product_seconds`] on each side of the solve).
pub const PRODUCTS: usize = 11;

/// The seconds of [`PRODUCTS`] products A·v (x all ones), after a warm-up.
fn product_times(a: &contactlab_solvers::Csr) -> Vec<f64> {
    let x = vec![1.0; a.ncols()];
    let mut y = vec![0.0; a.nrows()];
    contactlab_solvers::numerics::linalg::spmv_into(a, &x, &mut y);
    let times = (0..PRODUCTS)
        .map(|_| {
            let t = std::time::Instant::now();
            contactlab_solvers::numerics::linalg::spmv_into(a, &x, &mut y);
            t.elapsed().as_secs_f64()
        })
        .collect();
    std::hint::black_box(&y);
    times
}

/// The median seconds of one product A·v (x all ones) over [`PRODUCTS`],
/// after a warm-up.
pub fn product_seconds(a: &contactlab_solvers::Csr) -> f64 {
    median(&product_times(a))
}

/// A field of `/proc/self/status` in KiB (Linux), e.g. `VmHWM` or `VmRSS`.
fn status_kb(field: &str) -> Option<u64> {
    std::fs::read_to_string("/proc/self/status")
        .ok()?
        .lines()
        .find(|l| l.strip_prefix(field).is_some_and(|r| r.starts_with(':')))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

/// Memory the kernel could give a new process now (`MemAvailable` of
/// `/proc/meminfo`), in KiB (Linux).
pub fn available_memory_kb() -> Option<u64> {
    std::fs::read_to_string("/proc/meminfo")
        .ok()?
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Peak resident memory of this process so far, in KiB (Linux).
fn peak_memory_kb() -> Option<u64> {
    status_kb("VmHWM")
}

/// Measures `solver` on the whole Coulomb problem of `scene` (its finest
/// mesh) in this process: the assembly's peak and the problem's size first,
/// then the solve on that assembly (a solver that warm-starts along the
/// continuation gets the coarser levels assembled beside it, as `solve`
/// does: the finest mesh is assembled once). Meaningful only in a fresh
/// process.
pub fn measure_here(scene: &Scene, solver: &str, settings: &Settings) -> Result<MemoryUse> {
    let unread =
        || anyhow::anyhow!("/proc/self/status is unreadable: memory is measured on Linux only");
    let entry = solver_entry(solver)?;
    // Refused before anything is assembled, as `solve` is.
    crate::solve::refuse_too_large(scene, entry)?;
    crate::allocator::return_freed_memory();
    let before = status_kb("VmRSS").ok_or_else(unread)?;
    // Assembled as the solve gets it (with M only for a solver that reads
    // it), so that the problem's size is the one the solve holds.
    let d = level_for(scene, scene.finest(), entry)?;
    let assembly_peak_kb = peak_memory_kb().ok_or_else(unread)?;
    // The assembly's freed temporaries are kept by the allocator policy:
    // return them, so that the resident size grows by the problem alone.
    crate::allocator::return_freed_memory();
    let problem_kb = status_kb("VmRSS")
        .ok_or_else(unread)?
        .saturating_sub(before);
    // The work unit's first half, on the A the solve gets (the other half
    // follows the solve), after the problem's size was read.
    let products_before = product_times(d.problem.a());
    let silent = &mut contactlab_solvers::Silent;
    let problem = if entry.solves(Law::Coulomb) {
        Assembled::one_level(d)
    } else {
        Assembled::with_finest_checked(scene, entry, d)?
    };
    let solved = solve(
        problem,
        Friction::Coulomb,
        entry,
        settings,
        Caps::default(),
        silent,
    )?;
    let peak_kb = peak_memory_kb().ok_or_else(unread)?;
    let products_after = product_times(solved.finest.problem.a());
    let sides = (median(&products_before), median(&products_after));
    let product = median(&[products_before, products_after].concat());
    let run = solved.outcome;
    let diagnostic = |name: &str| {
        run.solution
            .diagnostics
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| *v)
    };
    Ok(MemoryUse {
        h: scene.finest(),
        solver: solver.to_string(),
        status: run.status.to_string(),
        seconds: run.timing.total(),
        peak_kb,
        assembly_peak_kb,
        problem_kb,
        factor_values_bytes: diagnostic("factor_values_bytes"),
        schur_bytes: diagnostic("schur_bytes"),
        product_seconds: Some(product),
        product_sides: Some(sides),
        phases: run
            .solution
            .diagnostics
            .iter()
            .filter(|(k, _)| k.ends_with(crate::study::trial::SECONDS_SUFFIX))
            .map(|&(k, v)| (k.to_string(), v))
            .collect(),
    })
}

/// The binary a fresh process runs: `CONTACTLAB_BIN` if set (a program
/// built on the library, Python among them, is not `contactlab`), else
/// this one.
fn fresh_process_binary() -> Result<std::path::PathBuf> {
    match std::env::var_os("CONTACTLAB_BIN") {
        Some(bin) if !bin.is_empty() => Ok(bin.into()),
        _ => Ok(std::env::current_exe()?),
    }
}

/// Runs `bench-one` for `solver` on problem `problem` at `h` in a fresh
/// process and reads its answer.
pub fn measure_in_fresh_process(
    problem: u32,
    h: MeshSize,
    solver: &str,
    schedule: Schedule,
    set: &[&str],
) -> Result<MemoryUse> {
    let o = std::process::Command::new(fresh_process_binary()?)
        .args([
            "bench-one",
            "--problem",
            &problem.to_string(),
            "--h",
            &h.to_string(),
            "--solver",
            solver,
            "--schedule",
            schedule.name(),
        ])
        .args(set.iter().flat_map(|s| ["--set", s]))
        .output()?;
    anyhow::ensure!(
        o.status.success(),
        "bench-one for {solver} at h = {h} failed: {}",
        String::from_utf8_lossy(&o.stderr).trim()
    );
    serde_json::from_slice(&o.stdout)
        .with_context(|| format!("bench-one for {solver} at h = {h} printed no measurement"))
}

/// A memory that could not be measured, and why.
#[derive(Serialize)]
pub struct Unmeasured {
    pub h: String,
    pub error: String,
}

/// One measurement in MiB, as the table shows it: the peak, the
/// assembly's, the problem's, what the solver reports (none if it does
/// not), and the rest of the peak.
#[derive(Serialize)]
struct Row<'a> {
    h: String,
    solver: &'a str,
    status: &'a str,
    peak: f64,
    assembly_peak: f64,
    problem: f64,
    factor: Option<f64>,
    schur: Option<f64>,
    rest: f64,
}

/// The table of where memory goes, one row per measured solve.
pub fn markdown(uses: &[MemoryUse], unmeasured: &[Unmeasured]) -> Result<String> {
    const MIB: f64 = 1048576.0;
    let rows: Vec<Row> = uses
        .iter()
        .map(|u| {
            let known = u.problem_kb as f64 * 1024.0
                + u.factor_values_bytes.unwrap_or(0.0)
                + u.schur_bytes.unwrap_or(0.0);
            Row {
                h: u.h.to_string(),
                solver: &u.solver,
                status: &u.status,
                peak: u.peak_kb as f64 / 1024.0,
                assembly_peak: u.assembly_peak_kb as f64 / 1024.0,
                problem: u.problem_kb as f64 / 1024.0,
                factor: u.factor_values_bytes.map(|b| b / MIB),
                schur: u.schur_bytes.map(|b| b / MIB),
                rest: (u.peak_kb as f64 * 1024.0 - known).max(0.0) / MIB,
            }
        })
        .collect();
    crate::study::template::render(
        "bench_memory",
        include_str!("../templates/bench_memory.md"),
        crate::study::template::facts! { uses => rows, unmeasured },
    )
}
