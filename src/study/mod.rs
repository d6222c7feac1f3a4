//! The study engine and the studies: every experiment is a plan of trials
//! ([`trial`]), measured by one runner ([`runner`]) against an earned
//! reference ([`reference`]); tables, charts and the report are views of the
//! trials.

pub mod agreement;
pub mod bench;
pub mod benchmark;
pub mod catalog;
pub mod class;
pub mod compare;
pub mod cores;
pub mod discretization_error;
pub mod error_bound;
pub mod lab;
pub mod oracle;
pub mod parallel;
pub mod plans;
pub mod reference;
pub mod reproduce;
pub mod runner;
pub mod side_by_side;
pub mod stability;
pub mod studies;
pub mod sweep;
pub mod table1;
pub mod template;
pub mod trial;
pub mod tuning_map;
pub mod verify;
pub mod work_precision;
