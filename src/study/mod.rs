//! Studies of the solvers: the comparison, parameter sweeps, the stability
//! map, the benchmark, the paper's Table 1, and the report of `reproduce`.

pub mod bench;
pub mod compare;
pub mod report;
pub mod reproduce;
pub mod stability;
pub mod sweep;
pub mod table1;
