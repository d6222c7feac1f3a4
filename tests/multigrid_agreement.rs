//! Multigrid against the independent solvers: `tnnmg` inside the friction
//! fixed point gives semismooth Newton's Coulomb answer on problems 1-3
//! and on a scene in full contact; from a start where every contact node
//! is open (the rigid mode free) it closes the gap exactly; its energy
//! never increases; and the paper's method with `relaxation.inner =
//! multigrid` reaches its certified target with a few hundred inner
//! iterations where the sweeps need tens of thousands.

use contactlab::certificate::certify_solution;
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::{Scene, Traction};
use contactlab::settings::Settings;
use contactlab::solve::{solve_scene, solver_entry};
use contactlab::solvers::{ContactProblem, Friction, Silent, Start, registry};
use serde_json::json;

fn problem(number: u32, k: u32) -> Scene {
    Scene::paper_problem_to(number, MeshSize::from_level(k).unwrap()).unwrap()
}

/// The Coulomb answer of `solver` with `overrides`, certified.
fn coulomb(scene: &Scene, solver: &str, overrides: &[(&str, serde_json::Value)]) -> Vec<f64> {
    let mut settings = Settings::default();
    for (path, value) in overrides {
        settings.set(path, value.clone()).unwrap();
    }
    let entry = solver_entry(solver).unwrap();
    let solved = solve_scene(scene, Friction::Coulomb, entry, &settings, &mut Silent).unwrap();
    let o = &solved.outcome;
    assert!(
        o.status.is_converged(),
        "{solver} on {}: {} ({})",
        scene.name,
        o.detail,
        o.certificate.summary()
    );
    o.solution.pressure.clone()
}

/// Largest pressure difference over the problem's pressure scale.
fn pressure_gap(scene: &Scene, a: &[f64], b: &[f64]) -> f64 {
    let d = Discretization::new(scene, scene.finest()).unwrap();
    let p = d.problem.scales().pressure;
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / p
}

/// The fixed point around tnnmg, tightened, and semismooth Newton on the
/// Coulomb problem agree to 1e-8 of the pressure scale: problems 1-3, and
/// problem 1 loaded over all of the top (contact everywhere).
#[test]
fn tnnmg_gives_newtons_coulomb_answer() {
    let mut full = problem(1, 5);
    full.name = "problem 1 loaded over the whole top".into();
    full.loads = vec![Traction {
        from: 0.0,
        to: 1.0,
        p2: -20.0,
        p1: 0.0,
    }];
    let scenes = [problem(1, 5), problem(2, 5), problem(3, 5), full];
    for scene in &scenes {
        let mg = coulomb(
            scene,
            "tnnmg",
            &[
                ("tnnmg.tolerance", json!(1e-13)),
                ("coulomb.epsilon", json!(1e-11)),
            ],
        );
        let newton = coulomb(scene, "newton-coulomb", &[]);
        let gap = pressure_gap(scene, &mg, &newton);
        assert!(gap <= 1e-8, "{}: pressures differ by {gap:e}·P", scene.name);
    }
}

/// J(v) = ½vᵀAv − fᵀv + Σ w g |s|, +∞ where some t > 0.
fn energy(problem: &ContactProblem, g: &[f64], v: &[f64]) -> f64 {
    let a = problem.a();
    let quad: f64 = a.triplet_iter().map(|(r, c, x)| v[r] * x * v[c]).sum();
    let load: f64 = problem.f().iter().zip(v).map(|(f, x)| f * x).sum();
    let mut j = 0.5 * quad - load;
    for (c, g) in problem.contacts().iter().zip(g) {
        if v[c.t] > 0.0 {
            return f64::INFINITY;
        }
        j += c.weight * g * v[c.s].abs();
    }
    j
}

/// From a start that lifts the upper body off the lower one (every contact
/// node open: the rigid mode is free), each TNNMG iteration lowers the
/// energy or keeps it, and the answer is certified and Newton's. A lost
/// line search, a projection that lets t > 0, or a rigid mode left
/// unresolved breaks one of the three.
#[test]
fn tnnmg_energy_never_increases_from_an_open_start() {
    let scene = problem(1, 5);
    let d = Discretization::new(&scene, scene.finest()).unwrap();
    let p = &d.problem;
    let g = vec![5.0; p.contacts().len()];
    let z = p.rigid_modes()[0].clone();
    // The rigid mode moves every jump alike; lift along the sign that opens.
    let opening = -z[p.contacts()[0].t].signum();
    let lift: Vec<f64> = z
        .iter()
        .map(|zk| opening * 10.0 * p.scales().displacement * zk)
        .collect();
    assert!(
        p.contacts().iter().all(|c| lift[c.t] < 0.0),
        "every node open"
    );
    let entry = registry::by_name("tnnmg").unwrap();
    let pressure = vec![0.0; p.contacts().len()];
    let mut energies = vec![energy(p, &g, &lift)];
    for iterations in 1..=25 {
        let mut tree = (entry.defaults)(Default::default());
        tree["max_iter"] = json!(iterations);
        tree["tolerance"] = json!(1e-12);
        let mut solver = entry.build.call(&tree).unwrap();
        let start = Start {
            v: std::borrow::Cow::Borrowed(&lift),
            pressure: &pressure,
            accuracy: None,
        };
        let s = solver.solve(p, Friction::Given(&g), Some(start), &mut Silent);
        energies.push(energy(p, &g, &s.v));
    }
    let scale = energies[0].abs();
    for (k, w) in energies.windows(2).enumerate() {
        assert!(
            w[1] <= w[0] + 1e-13 * scale,
            "iteration {}: energy rose from {} to {}",
            k + 1,
            w[0],
            w[1]
        );
    }
    let mut solver = entry
        .build
        .call(&(entry.defaults)(Default::default()))
        .unwrap();
    let start = Start {
        v: std::borrow::Cow::Borrowed(&lift),
        pressure: &pressure,
        accuracy: None,
    };
    let s = solver.solve(p, Friction::Given(&g), Some(start), &mut Silent);
    eprintln!("from the open start: {}", s.detail);
    assert!(s.iterations.outer <= 50, "{}", s.detail);
    let c = certify_solution(p, Friction::Given(&g), &s, 1e-8);
    assert!(c.passed(), "{} ({})", c.summary(), s.detail);
    let newton = registry::by_name("newton").unwrap();
    let mut exact = newton
        .build
        .call(&(newton.defaults)(Default::default()))
        .unwrap();
    let e = exact.solve(p, Friction::Given(&g), None, &mut Silent);
    let gap = pressure_gap(&scene, &s.pressure, &e.pressure);
    assert!(gap <= 1e-7, "pressures differ from Newton's by {gap:e}·P");
}

/// The paper's method with TNNMG as its inner minimizer reaches the
/// certified target 1e-6 at h = 1/16 and 1/64, in far fewer inner
/// iterations than the paper's sweeps need for the same target at 1/16
/// (a multigrid step that did nothing would need as many as the sweeps).
#[test]
fn the_papers_method_with_multigrid_reaches_its_target() {
    let run = |k: u32, inner: &str| {
        let scene = problem(1, k);
        let mut settings = Settings::default();
        settings.set("relaxation.inner", json!(inner)).unwrap();
        settings.set("relaxation.target", json!(1e-6)).unwrap();
        let entry = solver_entry("relaxation").unwrap();
        let solved = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent).unwrap();
        let o = solved.outcome;
        assert!(o.status.is_converged(), "1/2^{k} {inner}: {}", o.detail);
        let c = certify_solution(&solved.finest.problem, Friction::Coulomb, &o.solution, 1e-5);
        assert!(c.passed(), "1/2^{k} {inner}: {}", c.summary());
        o.solution.iterations.inner
    };
    let sweeps = run(4, "sweeps");
    let multigrid: Vec<usize> = [4, 6].iter().map(|&k| run(k, "multigrid")).collect();
    eprintln!("inner iterations: sweeps at 1/16 {sweeps}, multigrid at 1/16, 1/64 {multigrid:?}");
    assert!(multigrid.iter().all(|&m| m <= 1000), "{multigrid:?}");
    assert!(multigrid[0] * 10 <= sweeps, "{multigrid:?} vs {sweeps}");
}

/// The nested schedule (the Coulomb problem on each level in turn, each
/// started from the level below) gives newton-coulomb's answer and needs
/// fewer TNNMG iterations on the finest mesh than the paper's continuation
/// in the first friction step only: problem 1 at 1/64, default settings.
#[test]
fn the_nested_schedule_needs_less_work_on_the_finest_mesh() {
    let scene = problem(1, 6);
    let finest_work = |schedule: &str| {
        let mut settings = Settings::default();
        settings.set_text("schedule", schedule).unwrap();
        let entry = solver_entry("tnnmg").unwrap();
        let solved = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent).unwrap();
        let o = solved.outcome;
        assert!(o.status.is_converged(), "{schedule}: {}", o.detail);
        let finest = o.levels.last().unwrap().uzawa;
        (finest, o.solution.pressure)
    };
    let (nested, p_nested) = finest_work("nested");
    let (finest_only, _) = finest_work("finest-only");
    let newton = coulomb(&scene, "newton-coulomb", &[]);
    let gap = pressure_gap(&scene, &p_nested, &newton);
    eprintln!(
        "finest-mesh tnnmg iterations: nested {nested}, finest-only {finest_only}; gap {gap:e}·P"
    );
    assert!(gap <= 1e-5, "nested: pressures differ by {gap:e}·P");
    assert!(nested < finest_only, "{nested} vs {finest_only}");
}

/// tnnmg's defaults are its fastest schedule: without a schedule chosen it
/// runs the nested one (the same work, level by level), and that does less
/// work over all levels than either of the paper's readings, problem 1 at
/// 1/64: iterations weighted by the level's unknowns (a quarter of the
/// next finer level's), in finest-level iterations. Fails if the registry's default schedule is not the one used, or
/// stops being the cheapest.
#[test]
fn tnnmg_runs_its_cheapest_schedule_by_default() {
    let scene = problem(1, 6);
    let work = |schedule: Option<&str>| {
        let mut settings = Settings::default();
        if let Some(s) = schedule {
            settings.set_text("schedule", s).unwrap();
        }
        let entry = solver_entry("tnnmg").unwrap();
        let o = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent)
            .unwrap()
            .outcome;
        assert!(o.status.is_converged(), "{schedule:?}: {}", o.detail);
        o.levels.iter().map(|l| l.uzawa).collect::<Vec<_>>()
    };
    let default = work(None);
    assert_eq!(default, work(Some("nested")));
    let total = |w: &[usize]| {
        w.iter()
            .rev()
            .enumerate()
            .map(|(below, &k)| k as f64 / 4f64.powi(below as i32))
            .sum::<f64>()
    };
    for other in ["revisit", "finest-only"] {
        let w = work(Some(other));
        eprintln!(
            "tnnmg iterations per level: default {default:?} ({:.1}), {other} {w:?} ({:.1})",
            total(&default),
            total(&w)
        );
        assert!(total(&default) < total(&w), "{default:?} vs {other} {w:?}");
    }
}

/// The nested schedule solves the coarse levels only to
/// `coulomb.coarse_epsilon` (their answers start the next level), the
/// finest to ε: fewer friction steps below the finest than with the coarse
/// levels at ε, and the finest answer the same to well within ε. Fails if
/// the coarse tolerance is not used (equal steps) or reaches the finest
/// level (its answer would move by about the coarse tolerance).
#[test]
fn the_nested_schedule_solves_the_coarse_levels_to_their_own_epsilon() {
    let scene = problem(1, 6);
    let run = |coarse_epsilon: f64| {
        let mut settings = Settings::default();
        settings.set_text("schedule", "nested").unwrap();
        settings
            .set("coulomb.coarse_epsilon", json!(coarse_epsilon))
            .unwrap();
        let entry = solver_entry("tnnmg").unwrap();
        let solved = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent).unwrap();
        let o = solved.outcome;
        assert!(o.status.is_converged(), "{coarse_epsilon}: {}", o.detail);
        let (coarse, _) = o.levels.split_at(o.levels.len() - 1);
        let steps: usize = coarse.iter().map(|l| l.visits).sum();
        (steps, o.solution.pressure)
    };
    let (tight, p_tight) = run(1e-7);
    let (loose, p_loose) = run(1e-3);
    let gap = pressure_gap(&scene, &p_loose, &p_tight);
    eprintln!("coarse friction steps: {tight} at 1e-7, {loose} at 1e-3; finest gap {gap:e}·P");
    assert!(loose < tight, "{loose} vs {tight}");
    assert!(gap <= 1e-6, "the finest answers differ by {gap:e}·P");
}

/// A solver that records what it is asked: the unknowns of each problem and
/// where the harness released what it keeps.
#[derive(Default)]
struct Recording {
    inner: contactlab::solvers::multigrid::Tnnmg,
    log: Vec<Option<usize>>,
    /// (unknowns, the accuracy asked, iterations) of each solve.
    asked: Vec<(usize, Option<f64>, usize)>,
}

/// Every level of the continuation of paper problem `k` at h = 1/2^`level`.
fn continuation_levels(k: u32, level: u32) -> Vec<Discretization> {
    levels_of(&problem(k, level))
}

/// Every level of `scene`'s continuation.
fn levels_of(scene: &Scene) -> Vec<Discretization> {
    scene
        .levels
        .iter()
        .map(|&h| Discretization::new(scene, h).unwrap())
        .collect()
}

impl contactlab::solvers::Solver for Recording {
    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        start: Option<Start<'_>>,
        observer: &mut dyn contactlab::solvers::Observer,
    ) -> contactlab::solvers::Solution {
        self.log.push(Some(problem.n()));
        let accuracy = start.as_ref().and_then(|s| s.accuracy);
        let solution = self.inner.solve(problem, friction, start, observer);
        self.asked
            .push((problem.n(), accuracy, solution.iterations.outer));
        solution
    }

    fn release(&mut self) {
        self.log.push(None);
        self.inner.release();
    }
}

/// The nested schedule releases what the solver keeps for the coarse levels
/// (their multigrid hierarchies) once it is done with them, and solves only
/// the finest level after: a release missing, too early or repeated shows.
#[test]
fn the_nested_schedule_releases_the_coarse_levels_once_done_with_them() {
    use contactlab::coulomb::continuation::{Continuation, Schedule};
    use contactlab::coulomb::fixed_point::{CoulombSettings, friction_fixed_point};

    let levels = continuation_levels(1, 5);
    let finest = levels.last().unwrap().problem.n();
    let finest_h = levels.last().unwrap().h();
    let mut solver = Recording::default();
    let mut step = Continuation::new(levels, &mut solver, Schedule::Nested);
    let out = friction_fixed_point(&mut step, &CoulombSettings::default(), &mut Silent);
    // The coarse levels themselves are dropped too, not only what the
    // solver kept for them.
    assert_eq!(step.kept_levels(), vec![finest_h]);
    drop(step);
    assert!(out.status.is_converged(), "{}", out.detail);
    let released: Vec<usize> = (0..solver.log.len())
        .filter(|&k| solver.log[k].is_none())
        .collect();
    assert_eq!(released.len(), 1, "{:?}", solver.log);
    let (before, after) = solver.log.split_at(released[0]);
    assert!(
        before.iter().all(|n| n.is_some_and(|n| n < finest)),
        "{before:?}"
    );
    assert!(after[1..].iter().all(|&n| n == Some(finest)), "{after:?}");
    assert!(after.len() > 1, "the finest level is solved after");
}

/// Without friction the fixed point is one solve per level and asks no
/// accuracy of its own: the nested schedule asks each coarse level's solve
/// (but the coarsest's, from zero) for the coarse ε instead (its answer
/// only starts the next level), and the finest for nothing but the
/// solver's own tolerance. The coarse levels
/// then take fewer iterations than when asked for ε itself, and the finest
/// answer is the same. Fails if the coarse ε is not asked (the same
/// iterations) or reaches the finest level (its answer would move by about
/// that ε).
#[test]
fn a_frictionless_nested_schedule_asks_the_coarse_levels_for_the_coarse_epsilon() {
    use contactlab::coulomb::continuation::{Continuation, Schedule};
    use contactlab::coulomb::fixed_point::{CoulombSettings, friction_fixed_point};

    let run = |coarse_epsilon: f64| {
        let mut scene = problem(1, 7);
        scene.friction = 0.0;
        let levels = levels_of(&scene);
        let finest = levels.last().unwrap().problem.n();
        let mut solver = Recording::default();
        let mut step = Continuation::new(levels, &mut solver, Schedule::Nested);
        let settings = CoulombSettings {
            coarse_epsilon,
            ..CoulombSettings::default()
        };
        let out = friction_fixed_point(&mut step, &settings, &mut Silent);
        drop(step);
        assert!(out.status.is_converged(), "{}", out.detail);
        let (coarse, fine): (Vec<_>, Vec<_>) =
            solver.asked.iter().partition(|(n, _, _)| *n < finest);
        assert!(fine.iter().all(|(_, asked, _)| asked.is_none()), "{fine:?}");
        // The coarsest level starts from zero, without a start to carry
        // an accuracy; every other coarse level starts from the one below.
        let epsilon = settings.epsilon.max(coarse_epsilon);
        assert!(coarse.len() > 2, "{coarse:?}");
        assert!(
            coarse[1..]
                .iter()
                .all(|(_, asked, _)| *asked == Some(epsilon)),
            "{coarse:?}"
        );
        let iterations: usize = coarse.iter().map(|(_, _, k)| k).sum();
        (iterations, out.solution.pressure, scene)
    };
    let (loose, p_loose, scene) = run(1e-3);
    let (tight, p_tight, _) = run(1e-7);
    let gap = pressure_gap(&scene, &p_loose, &p_tight);
    eprintln!("coarse iterations: {loose} at 1e-3, {tight} at 1e-7; finest gap {gap:e}·P");
    assert!(loose < tight, "{loose} vs {tight}");
    assert!(gap <= 1e-8, "the finest answers differ by {gap:e}·P");
}

/// A nested continuation stepped by hand, without its answers handed back
/// (`keep`), solves each step on the finest level from zero, since its
/// coarse levels are gone (it once went back to the dropped coarsest level
/// and panicked), and reaches the same answer each time.
#[test]
fn a_nested_step_not_handed_its_predecessor_starts_on_the_finest() {
    use contactlab::coulomb::continuation::{Continuation, Schedule};
    use contactlab::coulomb::fixed_point::{CoulombSettings, GivenFrictionStep};

    let levels = continuation_levels(1, 4);
    let finest = levels.last().unwrap().problem.n();
    let mut solver = Recording::default();
    let mut step = Continuation::new(levels, &mut solver, Schedule::Nested);
    let g = step
        .initial_bound(&CoulombSettings::default(), &mut Silent)
        .expect("the coarse levels give a first bound");
    let first = step.solve_step(&g, None, &mut Silent);
    let second = step.solve_step(&g, None, &mut Silent);
    drop(step);
    assert!(first.status.is_converged(), "{}", first.detail);
    assert!(second.status.is_converged(), "{}", second.detail);
    let scale = first.pressure.iter().fold(0.0f64, |m, p| m.max(p.abs()));
    for (a, b) in first.pressure.iter().zip(&second.pressure) {
        assert!((a - b).abs() <= 1e-8 * scale, "{a} vs {b}");
    }
    let last_two = &solver.log[solver.log.len() - 2..];
    assert_eq!(last_two, [Some(finest), Some(finest)], "{:?}", solver.log);
}

/// The coarsest mesh, h = 1/2, has no mesh below it: the multigrid solvers
/// solve it on one level, with the coarsest level's exact solve as the
/// coarse correction, and give newton-coulomb's pressures. They used to
/// return `not_run` and a profile of zeros, blaming "an imported instance"
/// (issue 47).
#[test]
fn the_multigrid_solvers_solve_the_coarsest_mesh_on_one_level() {
    for k in 1..=3 {
        let scene = problem(k, 1);
        let newton = coulomb(&scene, "newton-coulomb", &[]);
        let tight = [
            ("coulomb.epsilon", json!(1e-11)),
            ("tnnmg.tolerance", json!(1e-13)),
        ];
        let mg = coulomb(&scene, "tnnmg", &tight);
        let gap = pressure_gap(&scene, &mg, &newton);
        assert!(gap <= 1e-8, "{}: tnnmg off by {gap:e}·P", scene.name);
        let relaxation = coulomb(
            &scene,
            "relaxation",
            &[
                ("relaxation.inner", json!("multigrid")),
                ("relaxation.target", json!(1e-7)),
            ],
        );
        let gap = pressure_gap(&scene, &relaxation, &newton);
        assert!(gap <= 1e-5, "{}: relaxation off by {gap:e}·P", scene.name);
    }
}

/// A problem without a mesh hierarchy and too large for one level (an
/// imported instance) is refused by tnnmg with the reason, before any work.
#[test]
fn an_instance_without_a_hierarchy_is_refused_with_the_reason() {
    let d = Discretization::new(&problem(1, 4), MeshSize::from_level(4).unwrap()).unwrap();
    let p = d
        .problem
        .clone()
        .with_hierarchy(Vec::<contactlab::solvers::Csr>::new())
        .unwrap();
    let mut solver = Settings::default()
        .build(registry::by_name("tnnmg").unwrap())
        .unwrap();
    let g = vec![1.0; p.contacts().len()];
    let s = solver.solve(&p, Friction::Given(&g), None, &mut Silent);
    assert_eq!(s.status, contactlab::solvers::Status::NotRun);
    assert!(
        s.detail.contains("mesh hierarchy") && s.detail.contains("imported instance"),
        "{}",
        s.detail
    );
}

/// The split Gauss-Seidel on several threads is the same method: problem 1
/// at 1/256 (above the size from which the sweeps split) on 1, 2 and 3
/// threads, each certified, their pressures within the solver's accuracy
/// of each other (1e-8 P) and their TNNMG iterations within 20 % of the
/// sequential ones. The answers are not the same bits, so the split was
/// used: fails if `tnnmg.threads` were ignored, or if a split sweep broke
/// the smoother (a race, or a row read before its neighbour wrote it).
#[test]
fn the_split_sweeps_give_the_sequential_answer() {
    let scene = problem(1, 8);
    let run = |threads: usize| {
        let mut settings = Settings::default();
        settings.set("tnnmg.threads", json!(threads)).unwrap();
        let entry = solver_entry("tnnmg").unwrap();
        let o = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent)
            .unwrap()
            .outcome;
        assert!(
            o.status.is_converged(),
            "{threads} threads: {} ({})",
            o.detail,
            o.certificate.summary()
        );
        let work: usize = o.levels.iter().map(|l| l.uzawa).sum();
        (o.solution.pressure, work)
    };
    let (sequential, work) = run(1);
    for threads in [2, 3] {
        let (p, w) = run(threads);
        let gap = pressure_gap(&scene, &p, &sequential);
        eprintln!("{threads} threads: {w} iterations (1 thread: {work}), gap {gap:e}·P");
        assert!(
            gap <= 1e-8,
            "{threads} threads: pressures differ by {gap:e}·P"
        );
        assert_ne!(p, sequential, "{threads} threads: the same bits, no split");
        assert!(
            w.abs_diff(work) * 5 <= work,
            "{threads} threads: {w} iterations vs {work}"
        );
    }
}
