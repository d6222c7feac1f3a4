//! `reproduce --quick`: every file, the documented headers, accuracy figures
//! against a committed reference, certified statuses, valid charts; trials
//! that do not converge are kept and marked.

mod common;

use std::path::Path;
use std::process::Command;

use contactlab::io::csv::header_of;
use contactlab::mechanics::contact_zone::PROFILE_COLUMNS;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solvers::{Law, Status, registry};
use contactlab::study::reference::References;
use contactlab::study::reproduce::{ReproduceSpec, studies};
use contactlab::study::runner::{Keep, measure_all};
use contactlab::study::trial::{Trial, TrialSpec};

/// Files a reproduce run must write (besides profiles and charts): one or
/// more per study, the manifest and the README.
const FILES: [&str; 39] = [
    "README.md",
    "manifest.json",
    "table1.csv",
    "table1.tex",
    "table1_trials.csv",
    "compare.csv",
    "compare_given_friction.tex",
    "compare_coulomb.tex",
    "compare_timing.csv",
    "references.csv",
    "separation.csv",
    "sweep.csv",
    "sweep_timing.csv",
    "sweep_references.csv",
    "stability.csv",
    "stability_friction.csv",
    "stability_uniqueness.csv",
    "stability_references.csv",
    "performance.csv",
    "performance_goals.md",
    "benchmark.csv",
    "benchmark.md",
    "benchmark_trials.csv",
    "benchmark_trials_timing.csv",
    "benchmark_summary.csv",
    "benchmark_1e-4.tex",
    "benchmark_1e-8.tex",
    "discretization_error.csv",
    "oracle.csv",
    "oracle_timing.csv",
    "error_bound.csv",
    "error_bound_sharpness.csv",
    "error_bound_trials.csv",
    "side_by_side.csv",
    "side_by_side_relaxation_clarabel.csv",
    "side_by_side_relaxation_reference.csv",
    "tuning_map_relaxation_given_friction_h16.csv",
    "tuning_map_relaxation_coulomb_h128.csv",
    "verification.csv",
];

/// The committed reference: `compare.csv` of `reproduce --quick`.
const REFERENCE: &str = include_str!("reference/quick_compare.csv");

/// Figures are deterministic on one machine; across machines floating-point
/// library functions may differ in the last bits, and a stopping test may
/// then flip by one iteration. So: statuses exactly, iteration counts within
/// 2%, floats within 1e-3 relative (or 1e-10 absolute).
fn float_close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-3 * a.abs().max(b.abs()) || (a - b).abs() <= 1e-10
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

fn svg_texts(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text)
        .unwrap_or_else(|e| panic!("{} is not valid XML: {e}", path.display()));
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    doc.descendants()
        .filter(|n| n.tag_name().name() == "text")
        .filter_map(|n| n.text().map(|t| t.to_string()))
        .collect()
}

/// The legend is a framed box, and nothing drawn on the plot (dots, line
/// vertices: data, axes, grid) lies right of its left edge outside it: the
/// legend never covers data.
fn legend_beside_the_data(path: &Path) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let num = |n: &roxmltree::Node, a: &str| n.attribute(a).and_then(|v| v.parse::<f64>().ok());
    let legend = doc
        .descendants()
        .rfind(|n| n.tag_name().name() == "rect" && n.attribute("fill") == Some("none"))
        .unwrap_or_else(|| panic!("{}: no framed legend", path.display()));
    let (x0, y0) = (num(&legend, "x").unwrap(), num(&legend, "y").unwrap());
    let (x1, y1) = (
        x0 + num(&legend, "width").unwrap(),
        y0 + num(&legend, "height").unwrap(),
    );
    let inside = |x: f64, y: f64| (x0..=x1).contains(&x) && (y0..=y1).contains(&y);
    let mut points: Vec<(f64, f64)> = Vec::new();
    for n in doc.descendants() {
        match n.tag_name().name() {
            "circle" => points.push((num(&n, "cx").unwrap(), num(&n, "cy").unwrap())),
            "polyline" => points.extend(
                n.attribute("points")
                    .unwrap_or("")
                    .split_whitespace()
                    .filter_map(|p| {
                        let (x, y) = p.split_once(',')?;
                        Some((x.parse().ok()?, y.parse().ok()?))
                    }),
            ),
            _ => {}
        }
    }
    for (x, y) in points {
        assert!(
            x < x0 || inside(x, y),
            "{}: a point at ({x}, {y}) is right of the legend's edge {x0}",
            path.display()
        );
    }
}

fn trial_header() -> Vec<String> {
    let spec = TrialSpec::new(
        "x",
        "x",
        &Scene::paper_problem(1).unwrap(),
        registry::solvers()[0],
        Law::Coulomb,
        &Settings::default(),
    );
    header_of(&Trial::not_run(&spec, Status::NotRun, String::new()).row()).unwrap()
}

/// Run without --out where a committed study lies: the smoke run goes to
/// results-quick and leaves results/ as it was (it once replaced 130
/// committed files without a word).
#[test]
fn reproduce_quick_writes_every_file_and_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let committed = dir.path().join("results");
    std::fs::create_dir(&committed).unwrap();
    std::fs::write(committed.join("README.md"), "the committed study\n").unwrap();
    let out = dir.path().join("results-quick");
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(["reproduce", "--quick"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(committed.join("README.md")).unwrap(),
        "the committed study\n",
        "a quick run wrote over results/"
    );
    assert_eq!(std::fs::read_dir(&committed).unwrap().count(), 1);
    for f in FILES {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    // The README's list of files is the run's: every file it names exists,
    // and every file written (besides charts and profiles, listed by
    // pattern) is named.
    common::readme_lists_every_file(&out);
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    // A smoke run says so at the top of its README and in every chart's
    // title, and says what the default run would be.
    assert!(
        readme.contains("\n> **A smoke run (`reproduce --quick`), not results.**"),
        "{}",
        &readme[..200.min(readme.len())]
    );
    for entry in std::fs::read_dir(out.join("charts")).unwrap() {
        let path = entry.unwrap().path();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(
            svg.contains("SMOKE RUN (--quick), not results"),
            "{} is not marked as a smoke run",
            path.display()
        );
    }
    // Every LaTeX table of the run compiles, as a paper would include it.
    common::latex_tables_compile(&out);
    // The memory probe ran in its fresh process and its table was written.
    let goals = std::fs::read_to_string(out.join("performance_goals.md")).unwrap();
    assert!(goals.contains("### Where the memory goes"), "{goals}");
    assert!(!goals.contains("was not measured"), "{goals}");
    for p in [1, 2, 3] {
        for solver in registry::names() {
            for kind in ["friction", "frictionless"] {
                let path = out.join(format!("profiles/p{p}_{solver}_{kind}.csv"));
                assert_eq!(read_csv(&path).0, PROFILE_COLUMNS, "{}", path.display());
            }
        }
    }
    for f in [
        "compare.csv",
        "sweep.csv",
        "stability.csv",
        "table1_trials.csv",
        "error_bound_trials.csv",
    ] {
        assert_eq!(read_csv(&out.join(f)).0, trial_header(), "{f}");
    }
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    let study_seconds = manifest["run"]["study_seconds"]
        .as_object()
        .expect("the manifest records each study's seconds");
    let planned = studies(&ReproduceSpec::quick(), &Settings::default()).len();
    assert_eq!(study_seconds.len(), planned, "{study_seconds:?}");
    for key in [
        "git_commit",
        "git_dirty",
        "rustc",
        "cpu",
        "cores",
        "date",
        "settings",
    ] {
        assert!(manifest.get(key).is_some(), "manifest lacks {key}");
    }
    // Every solver's answers at the relative defaults are certified.
    let (header, rows) = read_csv(&out.join("compare.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for r in rows.iter().filter(|r| r[col("study")] == "compare") {
        assert_eq!(r[col("status")], "converged", "{r:?}");
        assert_eq!(r[col("failing")], "", "{r:?}");
        assert!(
            !r[col("reference")].is_empty(),
            "a reference was earned: {r:?}"
        );
    }
    // Accuracy figures against the committed reference, row by row.
    let reference: Vec<Vec<String>> = csv::Reader::from_reader(REFERENCE.as_bytes())
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    assert!(!reference.is_empty());
    let key = |r: &Vec<String>| {
        ["study", "scene", "law", "solver"]
            .map(|c| r[col(c)].clone())
            .to_vec()
    };
    for want in &reference {
        let have = rows
            .iter()
            .find(|g| key(g) == key(want))
            .unwrap_or_else(|| panic!("no row for {:?}", key(want)));
        for (i, column) in header.iter().enumerate() {
            let (a, b) = (&have[i], &want[i]);
            if column == "detail" {
                continue;
            }
            match (a.parse::<f64>(), b.parse::<f64>()) {
                _ if column.ends_with("iterations") || column == "work" => {
                    let (a, b): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
                    assert!(
                        (a - b).abs() <= 0.02 * b.max(1.0),
                        "{:?} {column}: {a} vs reference {b}",
                        key(want)
                    );
                }
                (Ok(x), Ok(y)) => {
                    assert!(
                        float_close(x, y),
                        "{:?} {column}: {x} vs reference {y}",
                        key(want)
                    )
                }
                _ => assert_eq!(a, b, "{:?} {column}", key(want)),
            }
        }
    }
    // The bench's comparison at a certified accuracy: on each of its meshes
    // the paper's method with and without over-relaxation and with its
    // inner minimization by multigrid, each certified
    // within the target it was given (the shared certificate's measure), and
    // the oracle at its own settings; and the oracle's row on its goal's mesh.
    let (header, rows) = read_csv(&out.join("performance.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let paper = registry::with_role(registry::Role::PapersMethod).unwrap();
    let compared: Vec<&Vec<String>> = rows
        .iter()
        .filter(|r| r[col("what")] == "equal_accuracy")
        .collect();
    let ours: Vec<&&Vec<String>> = compared
        .iter()
        .filter(|r| r[col("solver")] == paper.name)
        .collect();
    assert_eq!(ours.len(), 3, "{compared:?}");
    let variants: std::collections::BTreeSet<&String> =
        ours.iter().map(|r| &r[col("variant")]).collect();
    assert_eq!(variants.len(), 3, "{variants:?}");
    assert!(
        variants.iter().any(|v| v.contains(".inner=multigrid")),
        "{variants:?}"
    );
    for r in &ours {
        let variant = &r[col("variant")];
        assert!(variant.contains(".target=1e-6"), "{variant}");
        assert_eq!(r[col("status")], "converged", "{r:?}");
        let certificate: f64 = r[col("certificate")].parse().unwrap();
        assert!(certificate <= 1e-6, "{r:?}");
    }
    assert!(
        compared
            .iter()
            .any(|r| r[col("solver")] != paper.name && r[col("variant")].is_empty()),
        "no oracle row: {compared:?}"
    );
    assert!(rows.iter().any(|r| r[col("what")] == "oracle_goal"));
    // Beside each mesh's assembly, the floor under it: a fresh copy of its
    // output, timed in the same run.
    for assembly in rows.iter().filter(|r| r[col("what")] == "assembly") {
        let output = rows
            .iter()
            .find(|r| r[col("what")] == "output" && r[col("h")] == assembly[col("h")])
            .unwrap_or_else(|| panic!("no output row beside {assembly:?}"));
        let seconds: f64 = output[col("median_seconds")].parse().unwrap();
        assert!(seconds > 0.0 && seconds.is_finite(), "{output:?}");
    }
    // The unit of every ratio is the faster factorization of the two
    // thread counts timed on the mesh, and the slower one is beside it.
    let seconds = |r: &Vec<String>| r[col("median_seconds")].parse::<f64>().unwrap();
    for unit in rows.iter().filter(|r| r[col("what")] == "factorization") {
        let slower = rows
            .iter()
            .find(|r| r[col("what")] == "factorization_slower" && r[col("h")] == unit[col("h")])
            .unwrap_or_else(|| panic!("no slower factorization beside {unit:?}"));
        assert!(seconds(unit) <= seconds(slower), "{unit:?} {slower:?}");
        let threads = [&unit[col("variant")], &slower[col("variant")]];
        assert!(
            threads.contains(&&"1 thread".to_string())
                && threads.contains(&&"2 threads".to_string()),
            "{threads:?}"
        );
        assert_eq!(
            unit[col("ratio_to_factorization")].parse::<f64>().unwrap(),
            1.0
        );
    }
    // Charts: valid SVG, title, axis labels, one series per solver where drawn per solver.
    let mut seen = 0;
    let mut per_law: Vec<(String, Vec<String>)> = Vec::new();
    for entry in std::fs::read_dir(out.join("charts")).unwrap() {
        let path = entry.unwrap().path();
        let texts = svg_texts(&path);
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let has = |t: &str| texts.iter().any(|x| x.contains(t));
        assert!(texts.len() >= 4, "{name}: too little text");
        let (title, x, y, per_solver) = if name.starts_with("work_precision") {
            (
                "Work-precision",
                "max pressure error",
                "solver time [s]",
                true,
            )
        } else if name.starts_with("profile_") {
            // The oracle's profile, the paper's method's on top (the zoom:
            // the oracle with and without friction).
            let roles: &[registry::Role] = if name.ends_with("_zoom") {
                &[registry::Role::Oracle]
            } else {
                &[registry::Role::Oracle, registry::Role::PapersMethod]
            };
            for &role in roles {
                let e = registry::with_role(role).unwrap();
                assert!(has(e.name), "{name}: no series for {}", e.name);
            }
            ("problem", "x along Γ_K", "[", false)
        } else if name.starts_with("convergence_inner") {
            // Every solver run inside the fixed point.
            for e in registry::solvers()
                .iter()
                .filter(|e| !e.solves(Law::Coulomb))
            {
                assert!(has(e.name), "{name}: no series for {}", e.name);
            }
            (
                "Convergence histories of the inner loops",
                "iteration",
                "residual",
                false,
            )
        } else if name.starts_with("convergence") {
            (
                "Convergence of the Coulomb problem",
                "iteration",
                "residual",
                true,
            )
        } else if name.starts_with("sweep_") {
            ("problem 1", "", "", false)
        } else if name.starts_with("performance_") {
            ("time against unknowns", "unknowns", "median time [s]", true)
        } else if name.starts_with("benchmark_profile") {
            // Dolan–Moré: every registered solver, its fraction solved
            // (certified) against the time ratio τ.
            (
                "Performance profile",
                "τ: time within",
                "fraction of instances solved",
                true,
            )
        } else if name.starts_with("error_bound_ratio") {
            (
                "Error bound over measured error against h",
                "mesh size h",
                "bound / error",
                false,
            )
        } else if name.starts_with("error_bound_") || name.starts_with("bound_vs_error_p") {
            ("Error bound", "measured error", "error bound", false)
        } else if name.starts_with("discretization_error") {
            ("Discretization error", "h", "relative error", false)
        } else if name.starts_with("stability_friction") {
            (
                "Coulomb fixed point",
                "friction coefficient",
                "contraction",
                false,
            )
        } else if name.starts_with("stability_") {
            ("Stability", "", "", false)
        } else if name.starts_with("side_by_side_") {
            // Both answers named in the title, the x axis along Γ_K.
            let paper = registry::with_role(registry::Role::PapersMethod).unwrap();
            assert!(has(paper.name), "{name}");
            ("problem 1", "x along the contact boundary", "", false)
        } else if name.starts_with("tuning_map_") {
            // Every value of both axes a label, the colour scale named.
            for v in ["1e5", "1e7", "1e-5", "1e-6"] {
                assert!(has(v), "{name}: no label {v}");
            }
            ("relaxation", "relaxation.r", "relaxation.epsilon", false)
        } else if name.starts_with("verify_") && name.ends_with("_pressure") {
            // The computed profiles over the closed form, named with its source.
            assert!(has("closed form"), "{name}");
            (
                "contact pressure against the closed form",
                "x",
                "pressure p",
                false,
            )
        } else if name.starts_with("verify_") && name.ends_with("_traction") {
            // Cattaneo–Mindlin's traction, at the Q the answer carries.
            assert!(has("closed form at Q"), "{name}");
            (
                "tangential traction against the closed form",
                "x",
                "traction q",
                false,
            )
        } else if name.starts_with("verify_") {
            ("L2 error of the pressure", "h", "‖p_h − p‖ / ‖p‖", false)
        } else {
            panic!("unexpected chart {name}");
        };
        assert!(
            has(title) && has(x) && has(y),
            "{name}: title or axis label missing in {texts:?}"
        );
        if per_solver && name.starts_with("performance_") {
            // Split by family: every solver in one of the law's charts.
            per_law.push((name.to_string(), texts.clone()));
        } else if per_solver {
            // Charts of the given-friction subproblem: the solvers of that
            // law only.
            let subproblem = name == "performance_given_friction"
                || (name.starts_with("work_precision")
                    && !name.starts_with("work_precision_coulomb"));
            let drawn = registry::solvers()
                .into_iter()
                .filter(|e| !subproblem || e.solves(Law::GivenFriction));
            for e in drawn {
                assert!(has(e.name), "{name}: no series for {}", e.name);
            }
        }
        // Small multiples name each panel in its title and heat maps have a
        // colour bar: neither has a legend.
        let legendless = name.starts_with("convergence_inner") || name.starts_with("tuning_map_");
        if !legendless {
            legend_beside_the_data(&path);
        }
        seen += 1;
    }
    // The performance charts of each law, split by family: every solver of
    // the law in one of them.
    for law in ["coulomb", "given_friction"] {
        let texts: Vec<&String> = per_law
            .iter()
            .filter(|(n, _)| n.starts_with(&format!("performance_{law}_")))
            .flat_map(|(_, t)| t)
            .collect();
        assert!(!texts.is_empty(), "no performance chart of {law}");
        for e in registry::solvers()
            .into_iter()
            .filter(|e| law == "coulomb" || e.solves(Law::GivenFriction))
        {
            assert!(
                texts.iter().any(|t| t.contains(e.name)),
                "performance_{law}: no series for {}",
                e.name
            );
        }
    }
    assert!(seen >= 12 + 3 + 1 + 2 + 3 + 2 + 2, "only {seen} charts");
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(readme.contains("## Does the paper's solver agree with the reference?"));
    // Each study's section opens with its own heading, in the run's order:
    // the classical scenes once had none and read as the last tuning map's.
    let at = |heading: &str| {
        readme
            .find(&format!("\n## {heading}"))
            .unwrap_or_else(|| panic!("no section {heading:?}"))
    };
    let order = [
        at("Speed"),
        at("Benchmark over a problem collection"),
        at("Discretization error"),
        at("The oracle at every h"),
        at("The error bound: does it hold"),
        at("Tuning map"),
        at("Verification against closed forms"),
        at("Files"),
    ];
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{order:?}");
    assert!(readme.find("\n### hertz").unwrap() > order[6]);
    assert!(
        !readme.contains("{{") && !readme.contains("{%"),
        "unrendered template"
    );
}

#[test]
fn trials_that_do_not_converge_are_marked_not_dropped() {
    let mut scene = Scene::paper_problem(1).unwrap();
    scene.set_finest(MeshSize::from_level(3).unwrap());
    let relaxation = registry::with_role(registry::Role::PapersMethod).unwrap();
    let settings = Settings::default();
    let trial = |path: &str, value: &str| {
        TrialSpec::new("sweep", path, &scene, relaxation, Law::Coulomb, &settings)
            .with_work(Some(20_000))
            .varying(path, value)
            .unwrap()
    };
    // Relative values: r in units of K/L, ε of P.
    let specs = vec![
        trial("relaxation.r", "1e-8"),
        trial("relaxation.r", "1e7"),
        trial("relaxation.epsilon", "1e-15"),
        trial("relaxation.epsilon", "1e-6"),
    ];
    let mut references = References::default();
    let measured = measure_all(&specs, &mut references, Keep::default(), &|_| Ok(())).unwrap();
    assert_eq!(measured.len(), 4, "one row per planned trial");
    let reference = references.all().next().unwrap();
    // The reference is the most accurate exact solver, and the oracle is a
    // candidate like any other.
    let candidates = references.candidates();
    assert!(candidates.iter().any(|c| c.solver == "clarabel"));
    let best = candidates
        .iter()
        .filter(|c| c.law == Law::Coulomb && c.status == Status::Converged)
        .min_by(|a, b| a.certificate.total_cmp(&b.certificate))
        .unwrap();
    assert_eq!(reference.solver, best.solver);
    assert!(
        candidates
            .iter()
            .any(|c| c.chosen && c.solver == reference.solver)
    );
    let row = |knob: &str, value: &str| {
        &measured
            .iter()
            .find(|m| m.trial.knob() == (knob, value))
            .unwrap()
            .trial
    };
    // r = 1e-8 is slow (the cap); ε = 1e-15 is below what the arithmetic
    // can resolve, which the relaxation notices and says (issue 47).
    for (knob, value, status) in [
        ("relaxation.r", "1e-8", Status::MaxIterations),
        ("relaxation.epsilon", "1e-15", Status::InsufficientProgress),
    ] {
        let r = row(knob, value);
        assert!(
            !r.certified() && r.status == status,
            "{knob} = {value}: {:?} ({})",
            r.status,
            r.detail
        );
    }
    for (knob, value) in [("relaxation.r", "1e7"), ("relaxation.epsilon", "1e-6")] {
        assert!(row(knob, value).certified(), "{knob} = {value}");
    }
}

/// The committed `results/` hold the tables a paper would include: each
/// compiles into a default one-column article without an overfull box
/// (issue 75), as a fresh run's do above. A table format changed without
/// regenerating `results/` fails here.
#[test]
fn the_committed_latex_tables_compile() {
    let results = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("results");
    common::latex_tables_compile(&results);
}
