//! The instance loader: the input, cut at each "\n@@\n", gives
//! problem.json, A.mtx (also M.mtx), f.mtx, rigid_modes.mtx and
//! contact.csv of a folder, which `import` reads. Never a panic, and a
//! problem it accepts is one the certificate can be taken on.
#![no_main]

use contactlab::certificate::{DEFAULT_TOLERANCE, certify};
use contactlab::formats::instance::import;
use contactlab::solvers::Friction;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = tempfile_dir();
    let mut parts = split(data);
    parts.resize(5, &[]);
    for (name, bytes) in [
        "problem.json",
        "A.mtx",
        "f.mtx",
        "rigid_modes.mtx",
        "contact.csv",
    ]
    .iter()
    .zip(&parts)
    {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    std::fs::write(dir.join("M.mtx"), parts[1]).unwrap();
    if let Ok(instance) = import(&dir) {
        let p = &instance.problem;
        let m = p.contacts().len();
        let c = certify(
            p,
            Friction::Coulomb,
            &vec![0.0; p.n()],
            &vec![0.0; m],
            &vec![0.0; m],
            DEFAULT_TOLERANCE,
        );
        assert!(c.residual() >= 0.0);
    }
    let _ = std::fs::remove_dir_all(&dir);
});

fn split(data: &[u8]) -> Vec<&[u8]> {
    let sep = b"\n@@\n";
    let mut out = Vec::new();
    let mut rest = data;
    while let Some(k) = rest.windows(sep.len()).position(|w| w == sep) {
        out.push(&rest[..k]);
        rest = &rest[k + sep.len()..];
    }
    out.push(rest);
    out
}

fn tempfile_dir() -> std::path::PathBuf {
    let base = if std::path::Path::new("/dev/shm").is_dir() {
        "/dev/shm"
    } else {
        "/tmp"
    };
    let dir = std::path::Path::new(base).join(format!("contactlab-fuzz-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
