//! `contactlab certify`: the certificate of an answer computed elsewhere,
//! for a problem written by `contactlab export`. The answer is the
//! displacements (contact forces then follow from stationarity at the
//! contact rows), the contact forces per node (displacements then follow
//! from the elastic response, [`contactlab_solvers::reduction::dual::displacements_from_forces`]),
//! or both. An answer that fails is a non-zero exit.

use anyhow::{Result, bail};
use contactlab_solvers::Friction;

use crate::certificate::{BoundReport, bound_room, certify};
use crate::cli::CertifyArgs;
use crate::formats::instance::{complete_answer, import_for, read_forces, read_vector};
use crate::io::output::print;

pub fn run(args: &CertifyArgs) -> Result<()> {
    // The whole run's memory checked once: with the forces alone, the
    // displacements follow from a condensation onto the contact unknowns.
    let completes = args.displacements.is_none() && args.forces.is_some();
    let instance = import_for(&args.instance, |n| {
        if completes {
            crate::memory::forces_completion(n)
        } else {
            0.0
        }
    })?;
    let problem = &instance.problem;
    let (n, m) = (problem.n(), problem.contacts().len());
    let v = args
        .displacements
        .as_deref()
        .map(|path| read_vector(path, n))
        .transpose()?;
    let forces = args
        .forces
        .as_deref()
        .map(|path| read_forces(path, m))
        .transpose()?;
    if v.is_none() && forces.is_none() {
        bail!("no answer given: add --displacements FILE and/or --forces FILE");
    }
    let how = match (&v, &forces) {
        (Some(_), Some(_)) => "displacements and contact forces as given",
        (Some(_), None) => {
            "displacements as given; contact forces from stationarity at the contact rows"
        }
        _ => "contact forces as given; displacements from the elastic response to them",
    };
    let (v, p, q) = complete_answer(problem, v, forces)?;
    let friction = if args.given_friction {
        match &instance.g {
            Some(g) => Friction::Given(g),
            None => bail!(
                "--given-friction: {}/contact.csv states no friction bound (its column g is empty); export with --friction-bound G, fill the column with the bound of the subproblem you solved, or certify the Coulomb law (drop --given-friction)",
                args.instance.display()
            ),
        }
    } else {
        Friction::Coulomb
    };
    let law = friction.law();
    let c = certify(problem, friction, &v, &p, &q, args.tolerance);
    let mut text = format!(
        "instance {} ({n} unknowns, {m} contact nodes), law {}: {how}\n",
        args.instance.display(),
        law.as_str()
    );
    text += &format!(
        "problem: {}; A z = 0, the modes independent, a positive diagonal and the load along each mode carried by the contact (condition (13)): checked\n",
        instance.definiteness.line()
    );
    for (cond, x) in c.measures() {
        let mark = if x <= c.tolerance { "ok" } else { "FAILS" };
        text += &format!("  {:<16} {x:.3e}  {mark}\n", cond.as_str());
    }
    text += &format!("certificate: {}\n", c.summary());
    let bound = BoundReport::of(problem, friction, &v, &p, &q, bound_room());
    text += &format!("error bound: {}\n", bound.line());
    print(&text)?;
    if !c.passed() {
        bail!("the answer is not certified: {}", c.summary());
    }
    Ok(())
}
