//! The CSV readers: contact nodes, contact forces, benchmark rows.
#![no_main]

use contactlab::formats::instance::{contacts_from, forces_from};
use contactlab::study::benchmark::merge::rows_from;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(c) = contacts_from(data, 5, "contact.csv") {
        assert_eq!((c.nodes.len(), c.g.len(), c.gap.len(), c.slip_offset.len()), (5, 5, 5, 5));
    }
    if let Ok((p, q)) = forces_from(data, 5, "forces.csv") {
        assert_eq!((p.len(), q.len()), (5, 5));
    }
    let _ = rows_from(data, "benchmark.csv");
});
