//! Exports that other codes read: scipy.io.mmread reads every exported
//! Matrix Market file (banner `%%MatrixMarket`, symmetric matrices marked
//! so), and what it reads is the problem bit for bit.
//!
//! Needs a Python with scipy (`.ci/run` installs Debian's python3-scipy and
//! then sets CONTACTLAB_REQUIRE_SCIPY=1, which makes a missing scipy a
//! failure rather than a skip).

use std::process::Command;

use contactlab::formats::instance::export;
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;

const READER: &str = r#"
import sys, scipy.io, scipy.sparse
for name in sys.argv[2:]:
    x = scipy.sparse.coo_matrix(scipy.io.mmread(f"{sys.argv[1]}/{name}.mtx"))
    print(name, x.shape[0], x.shape[1])
    for i, j, v in sorted(zip(x.row.tolist(), x.col.tolist(), x.data.tolist())):
        print(i, j, float(v).hex())
"#;

fn python() -> Option<&'static str> {
    ["/usr/bin/python3", "python3"].into_iter().find(|p| {
        Command::new(p)
            .args(["-c", "import scipy.io"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// A matrix as scipy reads it: rows, columns, entries sorted by (row, col).
type Read = (usize, usize, Vec<(usize, usize, f64)>);

/// Each file, as scipy reads it.
fn read_with_scipy(py: &str, dir: &std::path::Path, names: &[&str]) -> Vec<Read> {
    let o = Command::new(py)
        .arg("-c")
        .arg(READER)
        .arg(dir)
        .args(names)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let mut out: Vec<Read> = Vec::new();
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        if names.contains(&w[0]) {
            out.push((w[1].parse().unwrap(), w[2].parse().unwrap(), Vec::new()));
        } else {
            let v = hexf(w[2]);
            out.last_mut()
                .unwrap()
                .2
                .push((w[0].parse().unwrap(), w[1].parse().unwrap(), v));
        }
    }
    out
}

/// Python's float.hex() back to the same double.
fn hexf(s: &str) -> f64 {
    let (sign, s) = s.strip_prefix('-').map_or((1.0, s), |r| (-1.0, r));
    let s = s.strip_prefix("0x").unwrap();
    let (mantissa, exponent) = s.split_once('p').unwrap();
    let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
    let mut m = u64::from_str_radix(int, 16).unwrap() as f64;
    let mut scale = 1.0 / 16.0;
    for c in frac.chars() {
        m += c.to_digit(16).unwrap() as f64 * scale;
        scale /= 16.0;
    }
    sign * m * 2f64.powi(exponent.parse().unwrap())
}

#[test]
fn scipy_reads_every_export_bit_for_bit() {
    let Some(py) = python() else {
        assert!(
            std::env::var_os("CONTACTLAB_REQUIRE_SCIPY").is_none(),
            "scipy is required here but python3 cannot import it"
        );
        eprintln!("skipped: no python3 with scipy on this machine");
        return;
    };
    let scene = Scene::paper_problem(1).unwrap();
    let d = Discretization::new(&scene, MeshSize::from_level(3).unwrap()).unwrap();
    let dir = std::env::temp_dir().join(format!("contactlab-scipy-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    export(&dir, &scene, &d, None, "test").unwrap();
    let read = read_with_scipy(py, &dir, &["A", "M", "f", "rigid_modes"]);
    let p = &d.problem;
    let n = p.n();
    let mass = p.mass().expect("export assembles M");
    let a = p.a().to_nalgebra();
    for (k, (what, matrix)) in [("A", &a), ("M", &*mass)].into_iter().enumerate() {
        let (rows, cols, entries) = &read[k];
        assert_eq!((*rows, *cols), (n, n), "{what}");
        let mut expected: Vec<(usize, usize, f64)> =
            matrix.triplet_iter().map(|(i, j, &v)| (i, j, v)).collect();
        expected.sort_by_key(|e| (e.0, e.1));
        // scipy gives a symmetric file's both triangles.
        assert_eq!(entries.len(), expected.len(), "{what}");
        for (a, b) in entries.iter().zip(&expected) {
            assert_eq!((a.0, a.1), (b.0, b.1), "{what}");
            assert_eq!(a.2.to_bits(), b.2.to_bits(), "{what} at ({}, {})", a.0, a.1);
        }
    }
    for (k, column) in [(2, p.f()), (3, &p.rigid_modes()[0][..])] {
        let (rows, cols, entries) = &read[k];
        assert_eq!((*rows, *cols), (n, 1));
        let mut dense = vec![0.0; n];
        for &(i, _, v) in entries {
            dense[i] = v;
        }
        for (a, b) in dense.iter().zip(column) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
