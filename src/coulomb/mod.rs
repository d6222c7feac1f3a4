//! The Coulomb problem around a given-friction solver: the successive
//! approximations g^{m+1} = 𝓕 p(u^m) of paper (9), mesh continuation
//! (Algorithm 1), and solving a scene with a registered solver.

pub mod budget;
pub mod continuation;
pub mod driver;
pub mod fixed_point;
