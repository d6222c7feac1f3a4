//! Export and certify: an exported instance reads back as the same problem,
//! a solution computed from the read-back problem is certified by
//! `contactlab certify` (given as displacements or as contact forces), and
//! a deliberately wrong one is refused with a non-zero exit.

use std::path::Path;
use std::process::{Command, Output};

use contactlab::formats::instance::{export, import};
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solvers::{Friction, Silent, registry};

fn certify(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(["certify", "--instance", dir.to_str().unwrap()])
        .args(args)
        .output()
        .unwrap()
}

fn lines(x: &[f64]) -> String {
    x.iter().map(|v| format!("{v:e}\n")).collect()
}

#[test]
fn an_exported_problem_reads_back_and_certify_judges_answers_from_it() {
    let dir = tempfile::tempdir().unwrap();
    let inst = dir.path().join("instance");
    std::fs::create_dir(&inst).unwrap();
    let mut scene = Scene::paper_problem(1).unwrap();
    scene.set_finest(MeshSize::from_level(4).unwrap());
    let d = Discretization::new(&scene, scene.finest()).unwrap();
    export(&inst, &scene, &d, None, "test").unwrap();
    // The same problem, to the last bit.
    let p = import(&inst).unwrap().problem;
    assert_eq!(p.n(), d.problem.n());
    assert_eq!(p.f(), d.problem.f());
    assert_eq!(p.contacts(), d.problem.contacts());
    assert_eq!(p.rigid_modes(), d.problem.rigid_modes());
    let bits = |a: &contactlab::solvers::Csr| -> Vec<u64> {
        a.values()
            .iter(a.row_offsets())
            .map(|v| v.to_bits())
            .collect()
    };
    assert!(p.a().same_pattern(d.problem.a()));
    assert_eq!(bits(p.a()), bits(d.problem.a()));
    assert_eq!(
        p.mass().unwrap().csr_data(),
        d.problem.mass().unwrap().csr_data()
    );
    // Solve the read-back problem (as another code would) and certify.
    let entry = registry::by_name("newton-coulomb").unwrap();
    let mut solver = Settings::default().build(entry).unwrap();
    let s = solver.solve(&p, Friction::Coulomb, None, &mut Silent);
    assert!(s.status.is_converged(), "{}", s.detail);
    let v_file = dir.path().join("v.txt");
    std::fs::write(&v_file, lines(&s.v)).unwrap();
    let f_file = dir.path().join("forces.csv");
    let forces = |scale: f64| {
        let mut t = String::from("pressure,friction_traction\n");
        for (p, q) in s.pressure.iter().zip(&s.friction_traction) {
            t += &format!("{:e},{q:e}\n", p * scale);
        }
        t
    };
    std::fs::write(&f_file, forces(1.0)).unwrap();
    for args in [
        vec!["--displacements", v_file.to_str().unwrap()],
        vec!["--forces", f_file.to_str().unwrap()],
        vec![
            "--displacements",
            v_file.to_str().unwrap(),
            "--forces",
            f_file.to_str().unwrap(),
        ],
    ] {
        let o = certify(&inst, &args);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{args:?}: {out} {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(out.contains("certified at 1e-5"), "{out}");
    }
    // Wrong answers: displacements 1% too large; pressures 10% too small.
    let wrong_v: Vec<f64> = s.v.iter().map(|x| 1.01 * x).collect();
    std::fs::write(&v_file, lines(&wrong_v)).unwrap();
    let o = certify(&inst, &["--displacements", v_file.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("FAILS"));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not certified"));
    std::fs::write(&f_file, forces(0.9)).unwrap();
    let o = certify(&inst, &["--forces", f_file.to_str().unwrap()]);
    assert!(!o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("force_balance") && out.contains("FAILS"),
        "{out}"
    );
    // A wrong length is a one-line error naming the flag.
    std::fs::write(&v_file, lines(&s.v[1..])).unwrap();
    let o = certify(&inst, &["--displacements", v_file.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--displacements"));
}

/// An instance states a friction bound only when told: without
/// `--friction-bound`, contact.csv's column g is empty and `certify
/// --given-friction` refuses in one line (it once read zeros there and
/// silently checked the frictionless problem); with `--friction-bound 5`
/// every row says 5.
#[test]
fn the_friction_bound_of_an_instance_is_stated_or_refused() {
    let bin = env!("CARGO_BIN_EXE_contactlab");
    let dir = tempfile::tempdir().unwrap();
    let (plain, bounded) = (dir.path().join("plain"), dir.path().join("bounded"));
    for (out, extra) in [
        (&plain, &[][..]),
        (&bounded, &["--friction-bound", "5"][..]),
    ] {
        let o = Command::new(bin)
            .args(["export", "--problem", "1", "--h", "1/8", "--out"])
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let g_column = |folder: &Path| -> Vec<String> {
        let text = std::fs::read_to_string(folder.join("contact.csv")).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let at = header.iter().position(|h| *h == "g").unwrap();
        lines
            .map(|l| l.split(',').nth(at).unwrap().to_string())
            .collect()
    };
    assert!(g_column(&plain).iter().all(String::is_empty));
    assert!(g_column(&bounded).iter().all(|g| g == "5.0" || g == "5"));
    let n = import(&plain).unwrap().problem.n();
    let zeros = dir.path().join("v.txt");
    std::fs::write(&zeros, "0\n".repeat(n)).unwrap();
    let o = Command::new(bin)
        .args(["certify", "--given-friction", "--instance"])
        .arg(&plain)
        .arg("--displacements")
        .arg(&zeros)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("states no friction bound"), "{stderr}");
    assert_eq!(
        import(&bounded).unwrap().g,
        Some(vec![
            5.0;
            import(&bounded).unwrap().problem.contacts().len()
        ])
    );
}

/// `solve --out` writes its answer in the exported unknowns and node order:
/// `certify` certifies it from displacements.mtx and from forces.csv.
#[test]
fn a_solve_can_be_certified_from_its_own_files() {
    let bin = env!("CARGO_BIN_EXE_contactlab");
    let dir = tempfile::tempdir().unwrap();
    let (run, inst) = (dir.path().join("run"), dir.path().join("inst"));
    for args in [
        vec![
            "solve",
            "--problem",
            "1",
            "--h",
            "1/16",
            "--solver",
            "newton-coulomb",
            "--out",
        ],
        vec!["export", "--problem", "1", "--h", "1/16", "--out"],
    ] {
        let out = if args[0] == "solve" { &run } else { &inst };
        let o = Command::new(bin).args(&args).arg(out).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    for (flag, file) in [
        ("--displacements", "displacements.mtx"),
        ("--forces", "forces.csv"),
    ] {
        let o = Command::new(bin)
            .args(["certify", "--instance"])
            .arg(&inst)
            .arg(flag)
            .arg(run.join(file))
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{flag}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            stdout.contains("certificate: certified"),
            "{flag}: {stdout}"
        );
    }
}

/// An export folder explains itself: its README names every file written
/// beside it, the problem's sizes and how to hand an answer to `certify`,
/// and `problem.json` says of S what its header says (symmetric).
#[test]
fn the_export_folder_has_a_readme_that_names_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let inst = dir.path().join("instance");
    std::fs::create_dir(&inst).unwrap();
    let mut scene = Scene::paper_problem(1).unwrap();
    scene.set_finest(MeshSize::from_level(3).unwrap());
    let d = Discretization::new(&scene, scene.finest()).unwrap();
    export(&inst, &scene, &d, None, "test").unwrap();
    let readme = std::fs::read_to_string(inst.join("README.md")).unwrap();
    for entry in std::fs::read_dir(&inst).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name != "README.md" {
            assert!(
                readme.contains(&format!("`{name}`")),
                "{name} not in the README"
            );
        }
    }
    assert!(readme.contains(&format!("n = {} unknowns", d.problem.n())));
    assert!(readme.contains("contactlab certify --instance"));
    assert!(readme.contains("scipy.io.mmread"));
    let json = std::fs::read_to_string(inst.join("problem.json")).unwrap();
    assert!(!json.contains("every entry"));
    let s = std::fs::read_to_string(inst.join("S.mtx")).unwrap();
    assert!(s.lines().next().unwrap().contains("symmetric"));
}

/// A sheared, curved scene (Cattaneo–Mindlin: a gap and a slip offset)
/// reads back with both, to the bit: an instance that dropped either
/// column would be another problem, and its answers would be judged
/// against it.
#[test]
fn the_gap_and_the_slip_offset_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let inst = dir.path().join("instance");
    std::fs::create_dir(&inst).unwrap();
    let mut scene = contactlab::study::verify::scene("cattaneo_mindlin").unwrap();
    scene.set_finest(MeshSize::from_level(5).unwrap());
    let d = Discretization::new(&scene, scene.finest()).unwrap();
    assert!(d.problem.has_gap() && d.problem.has_slip_offset());
    export(&inst, &scene, &d, None, "test").unwrap();
    let p = import(&inst).unwrap().problem;
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(p.gap()), bits(d.problem.gap()));
    assert_eq!(bits(p.slip_offset()), bits(d.problem.slip_offset()));
    assert_eq!(p.scales(), d.problem.scales());
}
