//! The readers of every file format contactlab takes, fed mutated copies of
//! real files (the seeds of the cargo-fuzz targets in `fuzz/`): Matrix
//! Market, the CSV files (contact nodes, contact forces, benchmark rows) and
//! whole instance folders. A bounded run of what `fuzz/` runs without bound
//! (see README.md, "Fuzzing"): never a panic, and what is accepted keeps
//! the readers' promises (indices in range, finite values, the declared
//! counts).

use std::path::Path;

use contactlab::formats::instance::{contacts_from, forces_from, import};
use contactlab::io::guarded::Lines;
use contactlab::io::matrix_market::{Expect, parse};
use contactlab::study::benchmark::merge::rows_from;
use proptest::prelude::*;

fn seed(target: &str, name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fuzz/seeds")
            .join(target)
            .join(name),
    )
    .unwrap()
}

/// An edit of a file: overwrite a byte, delete a run, insert text that
/// readers of these formats must meet (signs, exponents, separators).
#[derive(Clone, Debug)]
enum Edit {
    Set(usize, u8),
    Delete(usize, usize),
    Insert(usize, &'static str),
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let piece = prop::sample::select(vec![
        "-",
        "1e308",
        "nan",
        "inf",
        "0",
        "\n",
        ",",
        " ",
        "%%MatrixMarket",
        "99999999999999999999",
        "\u{feff}",
        "\"",
        "1/3",
        "-1",
        "\r\n",
        "\n@@\n",
    ]);
    prop::collection::vec(
        prop_oneof![
            (any::<usize>(), any::<u8>()).prop_map(|(k, b)| Edit::Set(k, b)),
            (any::<usize>(), 1usize..40).prop_map(|(k, n)| Edit::Delete(k, n)),
            (any::<usize>(), piece).prop_map(|(k, p)| Edit::Insert(k, p)),
        ],
        1..6,
    )
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let len = bytes.len().max(1);
        match *e {
            Edit::Set(k, b) => {
                if !bytes.is_empty() {
                    bytes[k % len] = b;
                }
            }
            Edit::Delete(k, n) => {
                let at = k % len;
                let end = (at + n).min(bytes.len());
                bytes.drain(at.min(end)..end);
            }
            Edit::Insert(k, p) => {
                let at = k % (bytes.len() + 1);
                bytes.splice(at..at, p.bytes());
            }
        }
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn matrix_market_files_edited_at_random(file in 0usize..4, e in edits()) {
        let name = ["A.mtx", "f.mtx", "rigid_modes.mtx", "array.mtx"][file];
        let data = apply(seed("matrix_market", name), &e);
        for expect in [
            Expect { rows: None, cols: None, what: "any" },
            Expect { rows: Some(17), cols: Some(1), what: "a vector" },
        ] {
            if let Ok(t) = parse(Lines::new(&data[..]), data.len() as u64, expect) {
                prop_assert!(t.entries.len() <= 2 * data.len());
                prop_assert!(t.entries.iter().all(|&(i, j, x)| i < t.rows && j < t.cols && x.is_finite()));
            }
        }
    }

    #[test]
    fn csv_files_edited_at_random(file in 0usize..3, e in edits()) {
        let name = ["contact.csv", "forces.csv", "benchmark.csv"][file];
        let data = apply(seed("csv", name), &e);
        if let Ok(c) = contacts_from(&data[..], 3, "contact.csv") {
            prop_assert_eq!((c.nodes.len(), c.g.len(), c.gap.len(), c.slip_offset.len()), (3, 3, 3, 3));
        }
        if let Ok((p, q)) = forces_from(&data[..], 5, "forces.csv") {
            prop_assert_eq!((p.len(), q.len()), (5, 5));
        }
        let _ = rows_from(&data[..], "benchmark.csv");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    /// A whole instance folder with its files edited: read back, or refused
    /// with an error; never a panic.
    #[test]
    fn instance_folders_edited_at_random(e in edits()) {
        let data = apply(seed("instance", "p1_h4"), &e);
        let dir = tempfile::tempdir().unwrap();
        write_instance(dir.path(), &data);
        if let Ok(instance) = import(dir.path()) {
            let p = instance.problem;
            prop_assert!(p.n() > 0 && p.scales().pressure.is_normal());
        }
    }
}

/// An instance folder from one input cut at each "\n@@\n": problem.json,
/// A.mtx (also M.mtx), f.mtx, rigid_modes.mtx, contact.csv.
fn write_instance(dir: &Path, data: &[u8]) {
    let sep = b"\n@@\n";
    let mut parts = Vec::new();
    let mut rest = data;
    while let Some(k) = rest.windows(sep.len()).position(|w| w == sep) {
        parts.push(&rest[..k]);
        rest = &rest[k + sep.len()..];
    }
    parts.push(rest);
    let part = |k: usize| parts.get(k).copied().unwrap_or_default();
    for (k, name) in [
        "problem.json",
        "A.mtx",
        "f.mtx",
        "rigid_modes.mtx",
        "contact.csv",
    ]
    .iter()
    .enumerate()
    {
        std::fs::write(dir.join(name), part(k)).unwrap();
    }
    std::fs::write(dir.join("M.mtx"), part(1)).unwrap();
}

/// The seeds themselves read: the instance is problem 1 at h = 1/4 (at h = 1/2 the roller holds one node, and the upper body's rotation about it is a second kernel vector of A that the scene does not declare: the import refuses it).
#[test]
fn the_seeds_read() {
    let data = seed("matrix_market", "A.mtx");
    let t = parse(
        Lines::new(&data[..]),
        data.len() as u64,
        Expect {
            rows: None,
            cols: None,
            what: "A",
        },
    )
    .unwrap();
    assert_eq!((t.rows, t.cols), (17, 17));
    let dir = tempfile::tempdir().unwrap();
    write_instance(dir.path(), &seed("instance", "p1_h4"));
    assert_eq!(import(dir.path()).unwrap().problem.n(), 48);
    assert_eq!(
        contacts_from(&seed("csv", "contact.csv")[..], 3, "contact.csv")
            .unwrap()
            .nodes
            .len(),
        3
    );
    assert_eq!(
        forces_from(&seed("csv", "forces.csv")[..], 5, "forces.csv")
            .unwrap()
            .0
            .len(),
        5
    );
    assert_eq!(
        rows_from(&seed("csv", "benchmark.csv")[..], "benchmark.csv")
            .unwrap()
            .len(),
        2
    );
}
