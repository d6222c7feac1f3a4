//! Every invalid input gets a one-line error naming the problem and a
//! non-zero exit, never a panic; scene files load exactly; the parser never
//! panics on random input.

use std::process::Command;

use contactlab::formats::scene_file;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use proptest::prelude::*;

enum Input<'a> {
    Args(&'a [&'a str]),
    /// A scene file (raw bytes) passed to `solve --scene`, plus extra args.
    Scene(&'a [u8], &'a [&'a str]),
}

fn run(input: &Input<'_>, dir: &std::path::Path) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_contactlab"));
    match input {
        Input::Args(args) => {
            cmd.args(*args);
        }
        Input::Scene(bytes, extra) => {
            let path = dir.join("scene.toml");
            std::fs::write(&path, bytes).unwrap();
            cmd.args(["solve", "--h", "1/8", "--scene", path.to_str().unwrap()])
                .args(*extra);
        }
    }
    cmd.output().unwrap()
}

const GOOD: &str = "name = \"x\"\n[[loads]]\nfrom = 0.0\nto = \"1/3\"\np2 = -60.0\n";

#[test]
fn every_bad_input_gets_a_one_line_error_and_a_nonzero_exit() {
    let dir = tempfile::tempdir().unwrap();
    let bad_load_outside = GOOD.replace("to = \"1/3\"", "to = 1.5");
    let bad_load_reversed = GOOD.replace("from = 0.0", "from = 0.5");
    let upward = GOOD.replace("-60.0", "60.0");
    let truncated = &GOOD[..GOOD.len() - 12];
    let unknown_key = format!("{GOOD}colour = \"red\"\n");
    let bad_setting = format!("{GOOD}[solver.relaxation]\nr = -1.0\n");
    let bad_level = format!("levels = [\"1/3\"]\n{GOOD}");
    // A certificate switched off by its tolerance, with a fixed point that
    // stops at once.
    let no_certificate =
        format!("{GOOD}[coulomb]\nepsilon = 1e10\n[certificate]\ntolerance = 1e300\n");
    // Condition (13) decided by rounding: -5 on [3/5, 4/5] and 1 on [0, 1]
    // balance exactly, summed as -4.4e-16.
    let balanced = "name = \"x\"\n[[loads]]\nfrom = \"3/5\"\nto = \"4/5\"\np2 = -5.0\n[[loads]]\nfrom = 0.0\nto = 1.0\np2 = 1.0\n";
    let huge_load = GOOD.replace("-60.0", "-1e308");
    let name_nul = GOOD.replace("name = \"x\"", "name = \"a\\u0000b\"");
    // A lower body of its own material: out of range, of another plane
    // model, or changed by a flag that cannot say which body it meant.
    let lower_soft = format!("{GOOD}[lower_material]\nyoung = 0.0\n");
    let lower_plane = format!("{GOOD}[lower_material]\nplane = \"stress\"\n");
    let lower_ok = format!("{GOOD}[lower_material]\nyoung = 200e3\n");
    let name_newline = GOOD.replace("name = \"x\"", "name = \"a\\nb\"");
    let name_rlo = GOOD.replace("name = \"x\"", "name = \"abc\\u202Efed\"");
    let cases: Vec<(Input<'_>, &str)> = vec![
        (
            Input::Args(&["info", "--problem", "4"]),
            "unknown problem 4",
        ),
        (
            Input::Args(&[
                "sweep",
                "--problem",
                "7",
                "--out",
                "/tmp/contactlab-never-written",
            ]),
            "unknown problem 7",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--solver", "simplex"]),
            "invalid value 'simplex' for '--solver",
        ),
        (
            Input::Args(&["compare", "--problem", "1", "--solvers", "simplex"]),
            "possible values: clarabel",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--h", "1/60"]),
            "power-of-two",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--h", "1/16384"]),
            "out of range",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--h", "abc"]),
            "--h",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--young", "0"]),
            "material.young",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--young", "-5"]),
            "material.young",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--young", "nan"]),
            "material.young",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--poisson", "0.5"]),
            "material.poisson",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--poisson", "-1"]),
            "material.poisson",
        ),
        (
            Input::Args(&["info", "--problem", "1", "--friction", "-0.1"]),
            "friction",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--set", "relaxation.r=0"]),
            "relaxation.r = '0' is invalid",
        ),
        // The flags once generated per knob: refused, with the --set
        // they stand for.
        (
            Input::Args(&["solve", "--problem", "1", "--relaxation-r", "0"]),
            "--relaxation-r is no longer a flag: write --set relaxation.r=0",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--clarabel-max-iter=5"]),
            "write --set clarabel.max_iter=5",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--set", "relaxation.r=-1e12"]),
            "relaxation.r = '-1e12' is invalid",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--epsilon", "0"]),
            "--epsilon",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--epsilon", "-1e-4"]),
            "--epsilon",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--max-friction-iterations", "0"]),
            "--max-friction-iterations",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--max-friction-iterations", "-3"]),
            "--max-friction-iterations",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--set", "relaxation.max_uzawa=0"]),
            "relaxation.max_uzawa",
        ),
        (
            Input::Args(&[
                "solve",
                "--problem",
                "1",
                "--set",
                "relaxation.max_sweeps=0",
            ]),
            "relaxation.max_sweeps",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--set", "clarabel.max_iter=0"]),
            "clarabel.max_iter",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--set", "clarabel.tol=-1e-8"]),
            "clarabel.tol",
        ),
        // A valid setting of a solver the run does not use would be
        // ignored: an error that names the flag for the solver run.
        (
            Input::Args(&[
                "solve",
                "--problem",
                "1",
                "--solver",
                "clarabel-faer",
                "--set",
                "clarabel.tol=1e-8",
            ]),
            "use --set clarabel-faer.tol= instead",
        ),
        (
            Input::Args(&[
                "solve",
                "--problem",
                "1",
                "--solver",
                "newton",
                "--set",
                "relaxation.omega=1.5",
            ]),
            "--set relaxation.omega sets a setting of relaxation",
        ),
        // The same for commands that run a chosen list of solvers.
        (
            Input::Args(&[
                "compare",
                "--problem",
                "1",
                "--solvers",
                "newton",
                "--set",
                "relaxation.omega=1.5",
            ]),
            "--set relaxation.omega sets a setting of relaxation, but this run uses newton",
        ),
        (
            Input::Args(&[
                "sweep",
                "--solvers",
                "newton,nsgs",
                "--set",
                "clarabel.tol=1e-9",
                "--out",
                "/tmp/contactlab-never-written",
            ]),
            "--set clarabel.tol sets a setting of clarabel, but this run uses newton, nsgs",
        ),
        (
            Input::Args(&[
                "benchmark",
                "--solvers",
                "clarabel-faer",
                "--set",
                "clarabel.tol=1e-9",
                "--out",
                "/tmp/contactlab-never-written",
            ]),
            "use --set clarabel-faer.tol= instead",
        ),
        (
            Input::Args(&[
                "solve",
                "--problem",
                "1",
                "--set",
                "relaxation.smoothing=abc",
            ]),
            "relaxation.smoothing",
        ),
        (
            Input::Args(&["solve", "--problem", "1", "--set", "relaxation.proximal=-1"]),
            "relaxation.proximal",
        ),
        (
            Input::Args(&[
                "sweep",
                "--vary",
                "relaxation.r=1e4,-1",
                "--out",
                "/tmp/contactlab-never-written",
            ]),
            "relaxation.r",
        ),
        (
            Input::Args(&[
                "solve",
                "--problem",
                "1",
                "--h",
                "1/8",
                "--out",
                "/dev/null/x",
            ]),
            "--out",
        ),
        (
            Input::Args(&["solve", "--scene", "/nonexistent/scene.toml"]),
            "cannot read scene file",
        ),
        (
            Input::Scene(bad_load_outside.as_bytes(), &[]),
            "loads[0].to",
        ),
        (
            Input::Scene(bad_load_reversed.as_bytes(), &[]),
            "loads[0].to",
        ),
        (Input::Scene(upward.as_bytes(), &[]), "condition (13)"),
        (
            Input::Scene(lower_soft.as_bytes(), &[]),
            "lower_material.young",
        ),
        (
            Input::Scene(lower_plane.as_bytes(), &[]),
            "lower_material.plane",
        ),
        (
            Input::Scene(lower_ok.as_bytes(), &["--young", "1e5"]),
            "each body its own material",
        ),
        (Input::Scene(b"name = \n", &[]), "line 1"),
        (Input::Scene(truncated.as_bytes(), &[]), "scene file"),
        (Input::Scene(b"name = \"x\"\n\xff\xfe\n", &[]), "not UTF-8"),
        (
            Input::Scene(unknown_key.as_bytes(), &[]),
            "unknown field `colour`",
        ),
        (Input::Scene(bad_setting.as_bytes(), &[]), "relaxation.r"),
        (Input::Scene(bad_level.as_bytes(), &[]), "power-of-two"),
        (Input::Scene(b"", &[]), "missing field"),
        (
            Input::Scene(no_certificate.as_bytes(), &["--solver", "relaxation"]),
            "certificate.tolerance = 1e300 is invalid",
        ),
        (
            Input::Args(&[
                "solve",
                "--problem",
                "1",
                "--h",
                "1/8",
                "--certify-tol",
                "1e300",
            ]),
            "--certify-tol",
        ),
        (Input::Scene(balanced.as_bytes(), &[]), "nearly balance"),
        (Input::Scene(huge_load.as_bytes(), &[]), "loads[0].p2"),
        (Input::Scene(name_nul.as_bytes(), &[]), "U+0000"),
        (Input::Scene(name_newline.as_bytes(), &[]), "U+000A"),
        (Input::Scene(name_rlo.as_bytes(), &[]), "U+202E"),
        (
            Input::Args(&[
                "benchmark",
                "--quick",
                "--time-limit",
                "1e19",
                "--out",
                "/tmp/contactlab-never-written",
            ]),
            "--time-limit",
        ),
        (
            Input::Args(&[
                "benchmark",
                "--quick",
                "--time-limit",
                "1e20",
                "--out",
                "/tmp/contactlab-never-written",
            ]),
            "--time-limit",
        ),
        (
            Input::Args(&[
                "bench",
                "--quick",
                "--budget",
                "1e19",
                "--out",
                "/tmp/contactlab-never-written",
            ]),
            "--time-limit",
        ),
    ];
    for (input, expected) in &cases {
        let o = run(input, dir.path());
        let stderr = String::from_utf8_lossy(&o.stderr);
        let what = match input {
            Input::Args(a) => a.join(" "),
            Input::Scene(b, _) => format!("scene file {:?}", String::from_utf8_lossy(b)),
        };
        assert!(!o.status.success(), "{what}: exit code 0");
        assert!(!stderr.contains("panicked"), "{what}: {stderr}");
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "{what}: not one line: {stderr}");
        assert!(
            stderr.contains(expected),
            "{what}: message does not name '{expected}': {stderr}"
        );
        let parts: Vec<&str> = stderr.trim().split(": ").filter(|p| p.len() > 20).collect();
        for (k, p) in parts.iter().enumerate() {
            assert!(
                !parts[k + 1..].contains(p),
                "{what}: message repeats itself: {stderr}"
            );
        }
    }
}

#[test]
fn example_scene_files_load_to_exactly_the_built_in_scenes() {
    for n in 1..=3 {
        let path = format!("{}/scenes/problem{n}.toml", env!("CARGO_MANIFEST_DIR"));
        let (scene, settings) = scene_file::load(std::path::Path::new(&path)).unwrap();
        assert_eq!(scene, Scene::paper_problem(n).unwrap(), "problem {n}");
        assert_eq!(settings, Settings::default(), "problem {n}");
    }
}

#[test]
fn a_good_scene_file_overrides_what_it_sets() {
    let text = format!(
        "{GOOD}friction = 0.25\n[material]\nplane = \"stress\"\n[solver.relaxation]\nr = 1e8\nsmoothing = \"exact\"\n"
    );
    // TOML tables end at the next table header, so put top-level keys first.
    let text = text.replace("friction = 0.25\n", "");
    let text = format!("friction = 0.25\n{text}");
    let (scene, settings) = scene_file::parse(&text).unwrap().split().unwrap();
    assert_eq!(scene.friction, 0.25);
    assert_eq!(
        scene.material.plane,
        contactlab::mechanics::material::PlaneModel::Stress
    );
    assert_eq!(
        settings.get("relaxation.r"),
        Some(serde_json::Value::from(1e8))
    );
    assert_eq!(
        settings.get("relaxation.smoothing"),
        Some(serde_json::Value::from("exact"))
    );
    assert_eq!(settings.coulomb(), Settings::default().coulomb());
}

/// Fragments that look like scene files, to reach deeper into the parser
/// than random text does.
fn fragment() -> impl Strategy<Value = String> {
    let key = prop::sample::select(vec![
        "name",
        "friction",
        "levels",
        "schedule",
        "young",
        "poisson",
        "plane",
        "from",
        "to",
        "p2",
        "epsilon",
        "r",
        "smoothing",
        "max_uzawa",
        "tol_feas",
        "colour",
    ]);
    let value = prop_oneof![
        any::<f64>().prop_map(|x| format!("{x:?}")),
        any::<i64>().prop_map(|x| x.to_string()),
        "[a-z0-9/ .\"-]{0,12}".prop_map(|s| format!("\"{s}\"")),
        Just("[\"1/8\", \"1/16\"]".to_string()),
        Just("inf".to_string()),
        Just("nan".to_string()),
        Just("{ huber = { delta = 1e-9 } }".to_string()),
    ];
    let header = prop::sample::select(vec![
        "",
        "[material]\n",
        "[lower_material]\n",
        "[[loads]]\n",
        "[coulomb]\n",
        "[solver.relaxation]\n",
        "[solver.clarabel]\n",
        "[solver]\n",
    ]);
    (header, key, value).prop_map(|(h, k, v)| format!("{h}{k} = {v}\n"))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn the_parser_never_panics_on_random_text(text in "\\PC{0,200}") {
        let _ = scene_file::parse(&text);
    }

    #[test]
    fn scene_like_files_parse_validate_and_build_without_panicking(parts in prop::collection::vec(fragment(), 0..12)) {
        let text: String = format!("name = \"x\"\n{}", parts.concat());
        if let Ok(Ok((scene, settings))) = scene_file::parse(&text).map(|f| f.split()) {
            let _ = settings.validate();
            if scene.validate().is_ok() {
                let h = contactlab::mechanics::mesh_size::MeshSize::from_level(2).unwrap();
                let _ = contactlab::mechanics::discretization::Discretization::new(&scene, h);
            }
        }
    }
}
