//! `bench-one` (the fresh process in which the bench measures memory)
//! reports where a solve's memory goes, consistently with the problem.

use std::process::Command;

use contactlab::study::bench::memory::MemoryUse;

#[test]
fn bench_one_splits_the_peak_into_assembly_factor_and_schur_complement() {
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args([
            "bench-one",
            "--problem",
            "1",
            "--h",
            "1/16",
            "--solver",
            "newton-coulomb",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let used: MemoryUse = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(used.status, "converged");
    // h = 1/16 has 17 contact nodes: S is (2·17)² doubles.
    assert_eq!(used.schur_bytes, Some((8 * 34 * 34) as f64));
    // The factor of A_II holds at least its diagonal: one value per
    // interior unknown (570 unknowns at 1/16, 34 of them at the contact).
    let factor = used.factor_values_bytes.unwrap();
    assert!(factor >= (8 * (570 - 34)) as f64, "{used:?}");
    // The peak includes the assembly's, which includes what it keeps.
    assert!(used.problem_kb > 0, "{used:?}");
    assert!(used.assembly_peak_kb >= used.problem_kb, "{used:?}");
    assert!(used.peak_kb >= used.assembly_peak_kb, "{used:?}");
}
