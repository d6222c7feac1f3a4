//! Adding a solver is one file and one registration: a toy accelerated
//! proximal-gradient solver (FISTA, Beck & Teboulle 2009, on the primal
//! given-friction problem), defined here and registered at run time, flows
//! through the settings, the command line's flags, the comparison, the
//! work-precision chart and the stability map without any other file
//! knowing its name. The studies study it by their default plan; one line
//! on the study side (`plans::register`) gives it a stress condition of
//! its own.

use clap::Parser;
use contactlab::cli::Cli;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solvers::registry::{self, Accuracy, Entry, Knob, Role, StageInfo};
use contactlab::solvers::settings::{Kind, Validate, from_tree, to_tree};
use contactlab::solvers::{
    ContactProblem, Control, Friction, Iterations, Law, Observer, Progress, Solution, Solver,
    Start, Status, Timing,
};
use contactlab::study::lab::{Lab, Quiet};
use contactlab::study::plans::{self, Plan, Variation};
use contactlab::study::stability::classify::Class;
use contactlab::study::stability::{StabilitySpec, run as stability};
use contactlab::study::sweep::charts::sweep_charts;
use contactlab::study::sweep::{Sweep, SweepSpec};
use contactlab::study::{compare::Compare, trial::Trial};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ToySettings {
    /// Stop when max|Δv| ≤ tolerance · U.
    tolerance: f64,
    max_iter: usize,
}

impl Default for ToySettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iter: 200_000,
        }
    }
}

impl Validate for ToySettings {
    fn validate(&self) -> Result<(), String> {
        TOY.check(&to_tree(self))
    }
}

struct Toy(ToySettings);

impl Solver for Toy {
    fn solve(
        &mut self,
        p: &ContactProblem,
        friction: Friction<'_>,
        _start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let n = p.n();
        let g = match Solution::given_bound(p, friction, Ok(())) {
            Ok(g) => g,
            Err(refused) => return *refused,
        };
        let a = p.a();
        let grad = |v: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let (cols, vals) = a.row(i);
                    cols.iter()
                        .zip(vals)
                        .map(|(j, a_ij)| a_ij * v[j])
                        .sum::<f64>()
                        - p.f()[i]
                })
                .collect()
        };
        // Step 1/L with L a Gershgorin bound on the largest eigenvalue of A.
        let l = (0..n)
            .map(|i| a.row(i).1.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0f64, f64::max);
        let alpha = 1.0 / l;
        let prox = |v: &mut [f64]| {
            for (c, g) in p.contacts().iter().zip(g) {
                v[c.t] = v[c.t].min(0.0);
                let k = alpha * c.weight * g;
                v[c.s] = v[c.s].signum() * (v[c.s].abs() - k).max(0.0);
            }
        };
        let tol = self.0.tolerance * p.scales().displacement;
        let (mut v, mut prev) = (vec![0.0; n], vec![0.0; n]);
        let mut status = Status::MaxIterations;
        let mut steps = 0;
        for k in 1..=self.0.max_iter {
            steps = k;
            let beta = (k as f64 - 1.0) / (k as f64 + 2.0);
            let y: Vec<f64> = v
                .iter()
                .zip(&prev)
                .map(|(a, b)| a + beta * (a - b))
                .collect();
            let g = grad(&y);
            let mut next: Vec<f64> = y.iter().zip(&g).map(|(a, b)| a - alpha * b).collect();
            prox(&mut next);
            let change = next
                .iter()
                .zip(&v)
                .fold(0.0f64, |a, (x, z)| a.max((x - z).abs()));
            prev = std::mem::replace(&mut v, next);
            let control = observer.observe(&Progress {
                stage: "gradient",
                iteration: k,
                residual: change,
                seconds: 0.0,
            });
            if change <= tol {
                status = Status::Converged;
                break;
            }
            if let Control::Stop(s) = control {
                status = s;
                break;
            }
        }
        let r = grad(&v);
        let pressure = p
            .contacts()
            .iter()
            .map(|c| (-r[c.t]).max(0.0) / c.weight)
            .collect();
        let friction_traction = p
            .contacts()
            .iter()
            .zip(g)
            .map(|(c, &g)| (r[c.s] / c.weight).clamp(-g, g))
            .collect();
        Solution {
            v,
            pressure,
            friction_traction,
            status,
            detail: format!("toy FISTA: {steps} steps"),
            iterations: Iterations {
                outer: steps,
                inner: 0,
            },
            timing: Timing::default(),
            diagnostics: Vec::new(),
        }
    }
}

static TOY: Entry = Entry {
    name: "toy",
    about: "a toy accelerated proximal gradient on the primal problem (a test's)",
    source: "Beck & Teboulle (2009), FISTA",
    laws: &[Law::GivenFriction],
    warm_starts: false,
    schedule: contactlab_solvers::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: "gradient",
        about: "one proximal gradient step; residual max|Δv|",
        history: true,
    }],
    work_stage: "gradient",
    knobs: &[
        Knob {
            name: "tolerance",
            fields: &["tolerance"],
            help: "stop when max|Δv| ≤ tolerance·U",
            kind: Kind::Positive,
        },
        Knob {
            name: "max_iter",
            fields: &["max_iter"],
            help: "step cap",
            kind: Kind::Count,
        },
    ],
    defaults: |_| to_tree(&ToySettings::default()),
    build: contactlab::solvers::registry::Build::Fn(|tree| Ok(Box::new(Toy(from_tree(tree)?)))),
    accuracy: Accuracy {
        knob: "tolerance",
        reference: 1e-12,
        exact: false,
    },
    role: Role::Other,
    kernel: None,
    max_unknowns: None,
    uses_mass: false,
    memory: contactlab::solvers::entry::Memory {
        per_unknown: 400.0,
        per_unknown_log2: 0.0,
    },
};

fn register() {
    // Tests share the process: register once.
    if registry::by_name("toy").is_none() {
        registry::register(&TOY).unwrap();
    }
}

fn scene() -> Scene {
    let mut s = Scene::paper_problem(1).unwrap();
    s.set_finest(MeshSize::from_level(3).unwrap());
    s
}

#[test]
fn a_toy_solver_registered_at_run_time_flows_through_every_study() {
    register();
    assert!(registry::register(&TOY).is_err(), "names are unique");
    // Settings by path, and a scene file's section.
    let mut settings = Settings::default();
    settings.set_text("toy.tolerance", "1e-11").unwrap();
    assert!(settings.set_text("toy.nosuch", "1").is_err());
    let (_, from_file) = contactlab::formats::scene_file::parse(
        "name = \"x\"\n[[loads]]\nfrom = 0.0\nto = 0.5\np2 = -1.0\n[solver.toy]\ntolerance = 1e-9\n",
    )
    .unwrap()
    .split()
    .unwrap();
    assert_eq!(
        from_file.get("toy.tolerance"),
        Some(serde_json::Value::from(1e-9))
    );
    // The command line sets its settings by path, from the registry
    // (`--set toy.tolerance=`), and the per-solver flag it once had is
    // refused with that hint.
    let cli = Cli::try_parse_from([
        "contactlab",
        "solve",
        "--problem",
        "1",
        "--solver",
        "toy",
        "--set",
        "toy.tolerance=1e-9",
    ]);
    assert!(cli.is_ok());
    let old: Vec<String> = ["--toy-tolerance", "1e-9"].map(String::from).to_vec();
    let hint = contactlab::cli::old_spelling(&old).expect("a hint for the old flag");
    assert!(hint.contains("write --set toy.tolerance=1e-9"), "{hint}");
    // The comparison: the toy's subproblem and Coulomb trials, certified,
    // against the earned reference.
    let settings = Settings::default();
    let mut lab = Lab::new(settings.clone(), &|_| {}, &Quiet);
    let study = Compare {
        scene: scene(),
        solvers: registry::solvers(),
        repeats: 0,
        reference: None,
    };
    let measured = &lab.run(&study).unwrap().findings;
    let toy: Vec<&Trial> = measured
        .iter()
        .map(|m| &m.trial)
        .filter(|t| t.solver.name == "toy")
        .collect();
    assert_eq!(toy.len(), 2, "{toy:?}");
    for t in &toy {
        assert!(t.certified(), "{t:?}");
        assert!(t.pressure_error().unwrap() < 1e-4, "{t:?}");
        assert_ne!(t.reference, Some("toy"), "not exact: never the reference");
    }
    // Sweeps and the work-precision chart.
    let spec = SweepSpec {
        scenes: vec![Scene::paper_problem(1).unwrap()],
        meshes: vec![MeshSize::from_level(3).unwrap()],
        solvers: vec![registry::by_name("toy").unwrap()],
        quick: true,
        repeats: 0,
        ..SweepSpec::default()
    };
    let study = Sweep {
        spec,
        extra: Vec::new(),
        references_file: "references.csv",
    };
    let mut lab = Lab::new(settings.clone(), &|_| {}, &Quiet);
    let swept = &lab.run(&study).unwrap().findings;
    assert!(swept.iter().any(|m| m.trial.knob().0 == "toy.tolerance"));
    let pairs: Vec<_> = swept.iter().map(|m| (&m.trial, &m.timing)).collect();
    let charts = sweep_charts(&pairs);
    let wp = charts
        .iter()
        .find(|(n, _)| n.starts_with("work_precision"))
        .expect("a work-precision chart");
    assert!(wp.1.series.iter().any(|s| s.name == "toy"));
    // The stability map: at its defaults, and, once the studies are given a
    // plan for it (one more line, on the study side), its stress condition.
    plans::register(
        "toy",
        Plan {
            stress: &[Variation {
                knob: "max_iter",
                values: &["10"],
                quick: &["10"],
            }],
            ..plans::DEFAULT
        },
    );
    let mut quick = StabilitySpec::quick();
    quick.friction_values = vec![0.5];
    quick.load_totals = vec![];
    quick.violating_totals = vec![];
    let mut lab = Lab::new(settings, &|_| {}, &Quiet);
    let map = stability(&quick, &mut lab).unwrap();
    let default = map
        .trials
        .iter()
        .find(|t| t.solver.name == "toy" && t.group == "default")
        .unwrap();
    assert_eq!(default.class, Some(Class::Converged), "{default:?}");
    let capped = map
        .trials
        .iter()
        .find(|t| t.solver.name == "toy" && t.knob().0 == "toy.max_iter")
        .unwrap();
    assert_eq!(capped.class, Some(Class::Stalled), "{capped:?}");
}

/// A solver with a cap on its unknowns is refused a larger problem with a
/// one-line error naming the cap and the way out, before any solve; within
/// the cap it runs. Fails if `Entry::max_unknowns` is not read.
#[test]
fn a_solver_is_refused_a_mesh_beyond_its_cap_on_unknowns() {
    use contactlab::solve::Assembled;
    static CAPPED: Entry = Entry {
        name: "toy-capped",
        max_unknowns: Some(200),
        uses_mass: false,
        memory: contactlab::solvers::entry::Memory {
            per_unknown: 400.0,
            per_unknown_log2: 0.0,
        },
        ..TOY
    };
    let s = scene();
    let at = |k: u32| {
        let mut s = s.clone();
        s.set_finest(MeshSize::from_level(k).unwrap());
        s
    };
    // h = 1/8 has 158 unknowns, 1/16 has 570.
    let small = Assembled::for_solver(&at(3), &CAPPED).expect("within the cap");
    assert_eq!(small.finest().problem.n(), 158);
    let e = Assembled::for_solver(&at(4), &CAPPED)
        .err()
        .expect("beyond the cap")
        .to_string();
    assert!(
        e.contains("570 unknowns")
            && e.contains("200")
            && e.contains("toy-capped")
            && !e.contains('\n'),
        "{e}"
    );
    assert!(Assembled::for_solver(&at(4), &TOY).is_ok(), "no cap: runs");
}
