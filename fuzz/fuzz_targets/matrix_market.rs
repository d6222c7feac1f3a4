//! Matrix Market text, read with no expected size and as a vector of 7
//! rows: never a panic, and never an allocation beyond what the input's
//! length allows.
#![no_main]

use contactlab::io::guarded::Lines;
use contactlab::io::matrix_market::{Expect, parse};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for expect in [
        Expect {
            rows: None,
            cols: None,
            what: "any",
        },
        Expect {
            rows: Some(7),
            cols: Some(1),
            what: "a vector",
        },
    ] {
        if let Ok(t) = parse(Lines::new(data), data.len() as u64, expect) {
            assert!(t.entries.len() <= 2 * data.len());
            assert!(
                t.entries
                    .iter()
                    .all(|&(i, j, x)| i < t.rows && j < t.cols && x.is_finite())
            );
        }
    }
});
