//! Files that `certify` reads, as a careless or hostile user gives them: an
//! instance whose files disagree with each other or with problem.json, a
//! Matrix Market file that declares sizes it does not hold, a FIFO or a
//! device in place of any file, a byte-order mark. Each must end in one
//! line on stderr and a non-zero exit (or, for a BOM, the right verdict),
//! never a panic, an abort on a huge allocation, or a hang.

use std::path::{Path, PathBuf};
mod common;

use std::process::{Command, Output};

use common::{contactlab, one_line_error, run_with_deadline};

use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solve::{solve_scene, solver_entry};
use contactlab::solvers::{Friction, Silent};

/// Runs contactlab with `args` and a deadline.
fn run(args: &[&str]) -> Output {
    let mut cmd = contactlab();
    cmd.args(args);
    run_with_deadline(cmd, 30)
}

struct Fixture {
    _dir: tempfile::TempDir,
    root: PathBuf,
    instance: PathBuf,
    /// The true answer's displacements, one per line, and contact forces.
    v: PathBuf,
    forces: PathBuf,
}

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

fn fixture() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().to_path_buf();
    let instance = root.join("instance");
    let o = run(&[
        "export",
        "--problem",
        "1",
        "--h",
        "1/8",
        "--out",
        &s(&instance),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let scene = Scene::paper_problem_to(1, MeshSize::from_level(3).unwrap()).unwrap();
    let run = solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("newton-coulomb").unwrap(),
        &Settings::default(),
        &mut Silent,
    )
    .unwrap();
    let sol = run.outcome.solution;
    let v = root.join("v.txt");
    std::fs::write(
        &v,
        sol.v.iter().map(|x| format!("{x:e}\n")).collect::<String>(),
    )
    .unwrap();
    let forces = root.join("forces.csv");
    let mut text = String::from("pressure,friction_traction\n");
    for (p, q) in sol.pressure.iter().zip(&sol.friction_traction) {
        text += &format!("{p:e},{q:e}\n");
    }
    std::fs::write(&forces, text).unwrap();
    Fixture {
        _dir: dir,
        root,
        instance,
        v,
        forces,
    }
}

impl Fixture {
    /// A copy of the instance with `file` replaced by `bytes`.
    fn variant(&self, name: &str, file: &str, bytes: &[u8]) -> PathBuf {
        let dir = self.root.join(name);
        std::fs::create_dir(&dir).unwrap();
        for e in std::fs::read_dir(&self.instance).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), dir.join(e.file_name())).unwrap();
        }
        std::fs::write(dir.join(file), bytes).unwrap();
        dir
    }

    fn read(&self, file: &str) -> String {
        std::fs::read_to_string(self.instance.join(file)).unwrap()
    }

    fn certify(&self, instance: &Path, extra: &[&str]) -> Output {
        let mut args = vec!["certify".to_string(), "--instance".into(), s(instance)];
        args.extend(extra.iter().map(|x| x.to_string()));
        run(&args.iter().map(String::as_str).collect::<Vec<_>>())
    }
}

/// The text of a Matrix Market file with its size line replaced.
fn with_size(text: &str, size: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    let k = lines.iter().position(|l| !l.starts_with('%')).unwrap();
    lines[k] = size;
    lines.join("\n") + "\n"
}

#[test]
fn an_instance_whose_files_disagree_is_refused_before_anything_is_allocated() {
    let fx = fixture();
    let v = s(&fx.v);
    // The true answer is certified.
    let o = fx.certify(&fx.instance, &["--displacements", &v]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    let f = fx.read("f.mtx");
    let a = fx.read("A.mtx");
    let contact = fx.read("contact.csv");
    let json = fx.read("problem.json");
    let modes = fx.read("rigid_modes.mtx");
    let lines = |t: &str| t.lines().map(String::from).collect::<Vec<_>>();
    let cases: Vec<(&str, &str, String, &str)> = vec![
        (
            "huge_f",
            "f.mtx",
            with_size(&f, "1000000000000 1 158"),
            "must be 158 × 1",
        ),
        (
            "huge_a",
            "A.mtx",
            with_size(&a, "100000000000 100000000000 10"),
            "must be 158 × 158",
        ),
        (
            "many_entries",
            "f.mtx",
            with_size(&f, "158 1 100000000000"),
            "more than its",
        ),
        (
            "two_columns",
            "f.mtx",
            with_size(&f, "158 2 158"),
            "must be 158 × 1",
        ),
        (
            "missing_row",
            "contact.csv",
            lines(&contact)[..lines(&contact).len() - 1].join("\n") + "\n",
            "8 rows, but problem.json declares 9",
        ),
        (
            "extra_row",
            "contact.csv",
            contact.clone() + &lines(&contact)[1].replacen("0,", "9,", 1) + "\n",
            "more than the 9 rows",
        ),
        (
            "wrong_n",
            "problem.json",
            json.replace("\"n\": 158", "\"n\": 157"),
            "must be 157",
        ),
        ("no_format", "problem.json", "{}".into(), "does not state"),
        (
            "inf_mode",
            "rigid_modes.mtx",
            modes
                .replacen(" 1e0\n", " inf\n", 1)
                .replacen(" 1\n", " inf\n", 1),
            "finite",
        ),
        (
            "zero_mode",
            "rigid_modes.mtx",
            modes
                .lines()
                .map(|l| match l.split_whitespace().collect::<Vec<_>>()[..] {
                    [i, j, _] if !l.starts_with('%') && l != "158 1 158" => format!("{i} {j} 0"),
                    _ => l.to_string(),
                })
                .collect::<Vec<_>>()
                .join("\n")
                + "\n",
            "rigid mode 0 holds a non-finite value or is zero",
        ),
    ];
    for (name, file, text, expected) in cases {
        let inst = fx.variant(name, file, text.as_bytes());
        let o = fx.certify(&inst, &["--displacements", &v]);
        one_line_error(&o, name, expected);
    }
    // Answers of the wrong size, and a displacement file declaring 1e12 rows.
    let mtx = fx.root.join("v.mtx");
    std::fs::write(
        &mtx,
        "%%MatrixMarket matrix coordinate real general\n1000000000000 1 1\n1 1 0.5\n",
    )
    .unwrap();
    one_line_error(
        &fx.certify(&fx.instance, &["--displacements", &s(&mtx)]),
        "1e12 rows",
        "must be 158 × 1",
    );
    let short = fx.root.join("short.csv");
    std::fs::write(&short, "pressure,friction_traction\n1,0\n").unwrap();
    one_line_error(
        &fx.certify(&fx.instance, &["--forces", &s(&short)]),
        "one row of forces",
        "1 rows, the problem has 9",
    );
}

#[test]
fn a_fifo_or_a_device_in_place_of_any_file_is_refused_at_once() {
    let fx = fixture();
    let fifo = fx.root.join("fifo");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    for (flag, path) in [
        ("--displacements", fifo.clone()),
        ("--forces", fifo.clone()),
        ("--forces", PathBuf::from("/dev/zero")),
        ("--displacements", PathBuf::from("/dev/zero")),
    ] {
        let o = fx.certify(&fx.instance, &[flag, &s(&path)]);
        one_line_error(
            &o,
            &format!("{flag} {}", path.display()),
            "not a regular file",
        );
    }
    for file in ["M.mtx", "contact.csv", "problem.json"] {
        let inst = fx.variant(&format!("fifo_{file}"), file, b"");
        std::fs::remove_file(inst.join(file)).unwrap();
        assert!(
            Command::new("mkfifo")
                .arg(inst.join(file))
                .status()
                .unwrap()
                .success()
        );
        let o = fx.certify(&inst, &["--displacements", &s(&fx.v)]);
        one_line_error(
            &o,
            file,
            if file == "problem.json" {
                "no problem.json"
            } else {
                "not a regular file"
            },
        );
    }
}

#[test]
fn a_byte_order_mark_is_read_past_and_long_lines_are_refused() {
    let fx = fixture();
    let bom = fx.root.join("bom.txt");
    let mut bytes = "\u{feff}".as_bytes().to_vec();
    bytes.extend(std::fs::read(&fx.v).unwrap());
    std::fs::write(&bom, bytes).unwrap();
    let o = fx.certify(&fx.instance, &["--displacements", &s(&bom)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let forces = fx.root.join("bom.csv");
    let mut bytes = "\u{feff}".as_bytes().to_vec();
    bytes.extend(std::fs::read(&fx.forces).unwrap());
    std::fs::write(&forces, bytes).unwrap();
    let o = fx.certify(&fx.instance, &["--forces", &s(&forces)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A file of one endless line is refused, not held whole.
    let long = fx.root.join("long.csv");
    std::fs::write(
        &long,
        "pressure,friction_traction\n".to_string() + &"1".repeat(1 << 20),
    )
    .unwrap();
    one_line_error(
        &fx.certify(&fx.instance, &["--forces", &s(&long)]),
        "one endless line",
        "longer than",
    );
}

/// Instances that have no solution are refused with one line naming the
/// reason, before any answer is judged: a negated A (the energy unbounded
/// below: −v* passed every pointwise condition), an A made indefinite at
/// one entry of its diagonal's size, a second rigid mode in A's kernel
/// left undeclared (a spring of the roller removed is not available in a
/// file, so the rigid mode is given twice: dependent), a load that lifts
/// the body off (condition (13)), and no contact node at all.
#[test]
fn an_instance_without_a_solution_is_refused() {
    let fx = fixture();
    let v = s(&fx.v);
    let a = fx.read("A.mtx");
    let f = fx.read("f.mtx");
    let modes = fx.read("rigid_modes.mtx");
    let contact = fx.read("contact.csv");
    let matrix_lines = |text: &str, edit: &dyn Fn(usize, usize, f64) -> f64| -> String {
        let mut out = String::new();
        let mut size_seen = false;
        for line in text.lines() {
            if line.starts_with('%') || !size_seen {
                size_seen |= !line.starts_with('%');
                out += line;
                out.push('\n');
                continue;
            }
            let parts: Vec<&str> = line.split_whitespace().collect();
            let (i, j, x): (usize, usize, f64) = (
                parts[0].parse().unwrap(),
                parts[1].parse().unwrap(),
                parts[2].parse().unwrap(),
            );
            out += &format!("{i} {j} {:e}\n", edit(i, j, x));
        }
        out
    };
    let negated = matrix_lines(&a, &|_, _, x| -x);
    // Entry (2, 1) raised far beyond √(A_11 A_22): indefinite, with a
    // positive diagonal.
    let indefinite = matrix_lines(&a, &|i, j, x| {
        if (i, j) == (2, 1) {
            1e3 * x.abs() + 1e9
        } else {
            x
        }
    });
    // f negated: the load pulls the upper body off Γ_K.
    let lifted = matrix_lines(&f, &|_, _, x| -x);
    let twice = {
        let json = fx
            .read("problem.json")
            .replace("\"rigid_modes\": 1", "\"rigid_modes\": 2");
        let mut lines: Vec<String> = modes.lines().map(String::from).collect();
        let k = lines.iter().position(|l| !l.starts_with('%')).unwrap();
        let size: Vec<usize> = lines[k]
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        lines[k] = format!("{} 2 {}", size[0], 2 * size[2]);
        let second: Vec<String> = lines[k + 1..]
            .iter()
            .map(|l| {
                let p: Vec<&str> = l.split_whitespace().collect();
                format!("{} 2 {}", p[0], p[2])
            })
            .collect();
        lines.extend(second);
        (json, lines.join("\n") + "\n")
    };
    let cases: Vec<(&str, PathBuf, &str)> = vec![
        (
            "negated",
            fx.variant("negated", "A.mtx", negated.as_bytes()),
            "diagonal entry",
        ),
        (
            "indefinite",
            fx.variant("indefinite", "A.mtx", indefinite.as_bytes()),
            "not positive semidefinite",
        ),
        (
            "lifted",
            fx.variant("lifted", "f.mtx", lifted.as_bytes()),
            "condition (13)",
        ),
        (
            "twice",
            {
                let dir = fx.variant("twice", "rigid_modes.mtx", twice.1.as_bytes());
                std::fs::write(dir.join("problem.json"), &twice.0).unwrap();
                dir
            },
            "combination of the modes before it",
        ),
    ];
    assert!(
        twice.0.contains("\"rigid_modes\": 2"),
        "problem.json names the modes' count"
    );
    for (what, dir, expected) in cases {
        let o = fx.certify(&dir, &["--displacements", &v]);
        one_line_error(&o, what, expected);
    }
    // No contact node: problem.json declares none, contact.csv its header.
    let header = contact.lines().next().unwrap().to_string() + "\n";
    let dir = fx.variant("no_contact", "contact.csv", header.as_bytes());
    let json = fx.read("problem.json");
    let re = without_contact_nodes(&json);
    std::fs::write(dir.join("problem.json"), re).unwrap();
    let o = fx.certify(&dir, &["--displacements", &v]);
    one_line_error(&o, "no contact node", "no contact node");
    // The certify report states the check of A it made.
    let o = fx.certify(&fx.instance, &["--displacements", &v]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("checked by Cholesky with the modes pinned"),
        "{out}"
    );
}

/// problem.json with `"contact_nodes": 0`.
fn without_contact_nodes(json: &str) -> String {
    let k = json.find("\"contact_nodes\"").unwrap();
    let rest = &json[k..];
    let end = rest.find(',').unwrap();
    format!("{}\"contact_nodes\": 0{}", &json[..k], &rest[end..])
}
