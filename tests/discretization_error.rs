//! The discretization-error study measures what P1 theory predicts, and
//! nothing where there is no error.

use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::settings::Settings;
use contactlab::study::discretization_error::{ErrorSpec, run};

fn level(k: u32) -> MeshSize {
    MeshSize::from_level(k).unwrap()
}

/// A mesh against itself: the interpolation is the identity, so every error
/// is zero (a wrong node map, a wrong body or a lost contact unknown in the
/// transfer would show here).
#[test]
fn a_mesh_against_itself_has_no_error() {
    let spec = ErrorSpec {
        problems: vec![1],
        meshes: vec![level(4)],
        reference: level(4),
        solver: None,
    };
    let rows = run(&spec, &Settings::default(), &|_| {}).unwrap();
    let r = &rows[0];
    assert!(r.l2_error <= 1e-12, "{r:?}");
    assert!(r.energy_error <= 1e-12, "{r:?}");
    assert!(r.pressure_error <= 1e-12, "{r:?}");
    assert_eq!(r.zone_start_error, 0.0);
}

/// Against a finer mesh the errors fall at P1's orders: about h² in L2 and
/// h in the energy norm (problem 1, h = 1/8 → 1/16 → 1/32 against 1/64).
#[test]
fn errors_fall_at_the_orders_of_p1_elements() {
    let spec = ErrorSpec {
        problems: vec![1],
        meshes: vec![level(3), level(4), level(5)],
        reference: level(6),
        solver: None,
    };
    let rows = run(&spec, &Settings::default(), &|_| {}).unwrap();
    for r in &rows[1..] {
        assert!((1.6..=2.4).contains(&r.l2_rate), "L2 order: {r:?}");
        assert!((0.8..=1.3).contains(&r.energy_rate), "energy order: {r:?}");
        assert_eq!(r.status, "converged");
    }
}
