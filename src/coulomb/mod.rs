//! The Coulomb problem around a given-friction solver: the successive
//! approximations g^{m+1} = 𝓕 p(u^m) of paper (9), mesh continuation
//! (Algorithm 1), and the budget a study gives a solve.

pub mod budget;
pub mod continuation;
pub mod fixed_point;
pub mod single_level;
