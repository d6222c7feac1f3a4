//! The domain's enums offered on the command line, by the names they
//! carry themselves: the domain types know nothing of clap.

use clap::builder::{PossibleValuesParser, TypedValueParser};

use crate::coulomb::continuation::Schedule;
use crate::mechanics::material::PlaneModel;

/// `--plane strain|stress`.
pub fn plane() -> impl TypedValueParser<Value = PlaneModel> {
    PossibleValuesParser::new(PlaneModel::ALL.map(PlaneModel::name)).map(|s| {
        PlaneModel::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .expect("one of the names offered")
    })
}

/// `--schedules revisit,finest-only`.
pub fn schedule() -> impl TypedValueParser<Value = Schedule> {
    PossibleValuesParser::new(Schedule::ALL.map(Schedule::name)).map(|s| {
        Schedule::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .expect("one of the names offered")
    })
}
