//! Scenes: material, friction coefficient, tractions on the top side of the
//! upper body, and mesh levels. The paper's problems 1, 2 and 3 are built in.

use serde::{Deserialize, Deserializer, Serialize};
use thiserror::Error;

use contactlab_solvers::problem::MIN_NET_LOAD_FRACTION;

use crate::mechanics::material::Material;
use crate::mechanics::mesh_size::MeshSize;

/// A traction on the segment `from ≤ x ≤ to` of the top side y = 1 (force
/// per unit length, constant on the segment): vertical P''_2 (negative
/// pushes down) and, optionally, tangential P''_1 (positive pushes towards
/// x = 1; the roller on x = 1 holds the upper body sideways).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Traction {
    #[serde(deserialize_with = "fraction")]
    pub from: f64,
    #[serde(deserialize_with = "fraction")]
    pub to: f64,
    pub p2: f64,
    #[serde(default)]
    pub p1: f64,
}

/// The scene of one computation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scene {
    pub name: String,
    /// The upper (double-primed) body's material, and the lower's unless
    /// `lower_material` gives its own.
    pub material: Material,
    /// The lower (primed) body's material when it differs from the upper's
    /// (scene files: `[lower_material]`; None: `material` for both, as in
    /// the paper). The plane model must be the same.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lower_material: Option<Material>,
    /// Coulomb friction coefficient 𝓕 (paper: 0.5).
    pub friction: f64,
    pub loads: Vec<Traction>,
    /// Mesh continuation levels, coarse to fine; the last is the finest.
    pub levels: Vec<MeshSize>,
    /// The initial gap along Γ_K (None: the paper's flat bodies, touching
    /// everywhere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap: Option<crate::mechanics::gap::Gap>,
    /// How the upper body is held sideways (the paper: a roller on x = 1).
    #[serde(skip_serializing_if = "is_roller")]
    pub hold: crate::mechanics::dofs::Hold,
    /// The horizontal displacement u''_1 prescribed on the held sides (the
    /// paper: 0, a roller in place). Nonzero, it shears the upper body over
    /// the lower one, as Cattaneo–Mindlin's tangential load does: the
    /// tangential force Q it transmits is a reaction, read from the answer.
    #[serde(skip_serializing_if = "is_zero")]
    pub side_shift: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// The largest |side_shift|: the model is small-strain on bodies of unit
/// size, and 1e-2 is already a strain of a percent over them.
pub const MAX_SIDE_SHIFT: f64 = 1e-2;

fn is_roller(hold: &crate::mechanics::dofs::Hold) -> bool {
    *hold == crate::mechanics::dofs::Hold::Roller
}

/// The sizes that Young's modulus and each nonzero traction may have.
/// Within them no product the solvers and the certificate form (energies
/// F·U = F²/K, squared residuals) over- or underflows, and
/// `tests/scale_invariance.rs` shows every registered solver giving the
/// same answer at both ends; outside them, the claim that units change no
/// result is not made, so such input is refused (loads of −1e308 printed
/// an objective of NaN, loads × 1e150 once made the Newton solvers fail).
pub const MAGNITUDES: (f64, f64) = (1e-50, 1e50);

/// The largest friction coefficient a scene may have: physical
/// coefficients are below about 2 and the stability map studies up to 64;
/// at 1e300 the bound 𝓕p overflowed.
pub const MAX_FRICTION: f64 = 1e3;

/// The paper's friction coefficient.
pub fn default_friction() -> f64 {
    0.5
}

/// The paper's continuation levels 1/8 ... 1/64.
pub fn default_levels() -> Vec<MeshSize> {
    MeshSize::schedule_to(MeshSize::from_level(6).expect("1/64 is in range"))
}

/// An input that cannot define a solvable scene.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SceneError {
    #[error("{field} = {value} is invalid: {expected}")]
    Invalid {
        field: String,
        value: String,
        expected: String,
    },
    #[error(
        "the loads violate the paper's condition (13): their total vertical force on the upper body is {}, \
         but it must be strictly negative (pushing the upper body onto the lower one), \
         otherwise the semicoercive problem has no solution (Theorem 1); make the sum of p2·(to − from) negative",
        total.shown()
    )]
    NoSolution { total: f64 },
    #[error(
        "the loads nearly balance: their total vertical force on the upper body, {}, is {:.1e} of their gross force Σ|P|·length = {}, \
         below {MIN_NET_LOAD_FRACTION:e}; the contact must carry that net force (condition (13)), and one so small cannot be told from \
         rounding or certified in double precision; make the net downward load at least {MIN_NET_LOAD_FRACTION:e} of the gross",
        total.shown(), total.abs() / gross, gross.shown()
    )]
    NearlyBalanced { total: f64, gross: f64 },
    #[error("unknown problem {0}: the built-in problems are 1, 2 and 3 (or give a scene file)")]
    UnknownProblem(u32),
}

/// Young's modulus and Poisson's ratio of the table `table` in range;
/// `flag_e`, `flag_nu` name the command-line flags that set them, if any.
fn check_material(
    table: &str,
    flag_e: &str,
    flag_nu: &str,
    m: &Material,
) -> Result<(), SceneError> {
    if !(m.young >= MAGNITUDES.0 && m.young <= MAGNITUDES.1) {
        return Err(invalid(
            &format!("{table}.young{flag_e}"),
            m.young,
            &format!(
                "Young's modulus must lie in [{:e}, {:e}] (the paper: 73e3), the range of units in which every solver is shown to give the same answer",
                MAGNITUDES.0, MAGNITUDES.1
            ),
        ));
    }
    if !(m.poisson.is_finite() && m.poisson > -1.0 && m.poisson < 0.5) {
        return Err(invalid(
            &format!("{table}.poisson{flag_nu}"),
            m.poisson,
            "Poisson's ratio must lie in (-1, 0.5) (the paper: 0.34)",
        ));
    }
    Ok(())
}

fn invalid(field: &str, value: impl Shown, expected: &str) -> SceneError {
    SceneError::Invalid {
        field: field.to_string(),
        value: value.shown(),
        expected: expected.to_string(),
    }
}

/// A value as an error message shows it: numbers far from 1 in scientific
/// notation, not as hundreds of digits.
pub trait Shown {
    fn shown(&self) -> String;
}

impl Shown for f64 {
    fn shown(&self) -> String {
        let a = self.abs();
        if *self == 0.0 || !self.is_finite() || (1e-4..1e6).contains(&a) {
            format!("{self}")
        } else {
            format!("{self:e}")
        }
    }
}

impl Shown for &str {
    fn shown(&self) -> String {
        self.to_string()
    }
}

impl Shown for String {
    fn shown(&self) -> String {
        self.clone()
    }
}

/// Changes to a scene's mesh and material, as `--h`, `--young`,
/// `--poisson`, `--plane` and `--friction` give them (the command line and
/// the Python package apply them here, so both build the same scene).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overrides {
    pub h: Option<MeshSize>,
    pub young: Option<f64>,
    pub poisson: Option<f64>,
    pub plane: Option<crate::mechanics::material::PlaneModel>,
    pub friction: Option<f64>,
}

impl Overrides {
    /// `scene` with these changes, validated (condition (13) included). A
    /// scene whose bodies have two materials takes no material change: which
    /// body it meant is not said.
    pub fn apply(&self, mut scene: Scene) -> Result<Scene, SceneError> {
        if let Some(h) = self.h {
            scene.set_finest(h);
        }
        if scene.lower_material.is_some() {
            let given = [
                ("--young", self.young.map(|e| e.shown())),
                ("--poisson", self.poisson.map(|nu| nu.shown())),
                ("--plane", self.plane.map(|p| p.to_string())),
            ];
            if let Some((flag, Some(value))) = given.into_iter().find(|(_, v)| v.is_some()) {
                return Err(invalid(
                    flag,
                    value,
                    "this scene gives each body its own material ([material] for the upper, [lower_material] for the lower): change them in the scene file",
                ));
            }
        }
        if let Some(e) = self.young {
            scene.material.young = e;
        }
        if let Some(nu) = self.poisson {
            scene.material.poisson = nu;
        }
        if let Some(p) = self.plane {
            scene.material.plane = p;
        }
        if let Some(f) = self.friction {
            scene.friction = f;
        }
        scene.validate()?;
        Ok(scene)
    }
}

impl Scene {
    /// The paper's problems (section 5): P''_2 = −60 on the left third of the
    /// top side (1), −120 on the left third (2), −60 on the whole top (3).
    pub fn paper_problem(number: u32) -> Result<Self, SceneError> {
        let (p2, to) = match number {
            1 => (-60.0, 1.0 / 3.0),
            2 => (-120.0, 1.0 / 3.0),
            3 => (-60.0, 1.0),
            other => return Err(SceneError::UnknownProblem(other)),
        };
        Ok(Self {
            name: format!("problem {number}"),
            material: Material::default(),
            lower_material: None,
            friction: default_friction(),
            loads: vec![Traction {
                from: 0.0,
                to,
                p2,
                p1: 0.0,
            }],
            levels: default_levels(),
            gap: None,
            hold: crate::mechanics::dofs::Hold::Roller,
            side_shift: 0.0,
        })
    }

    /// Each body's material: the lower's own if given, else `material`.
    pub fn materials(&self) -> crate::mechanics::assembly::BodyMaterials {
        crate::mechanics::assembly::BodyMaterials {
            lower: self.lower_material.unwrap_or(self.material),
            upper: self.material,
        }
    }

    /// The paper's problem `number` with its continuation levels 1/8, ..., h.
    pub fn paper_problem_to(number: u32, h: MeshSize) -> Result<Self, SceneError> {
        let mut scene = Self::paper_problem(number)?;
        scene.set_finest(h);
        Ok(scene)
    }

    /// The finest mesh level.
    pub fn finest(&self) -> MeshSize {
        *self.levels.last().expect("validated scenes have levels")
    }

    /// Sets the continuation schedule 1/8, ..., h (or just h if h > 1/8).
    pub fn set_finest(&mut self, h: MeshSize) {
        self.levels = MeshSize::schedule_to(h);
    }

    /// Total vertical force of the loads on the upper body, Σ p2 · (to − from):
    /// the left side of the paper's condition (13) without body forces.
    pub fn total_vertical_load(&self) -> f64 {
        self.loads.iter().map(|l| l.p2 * (l.to - l.from)).sum()
    }

    /// Gross force of the loads on the upper body, Σ (|p2| + |p1|) · (to − from):
    /// the scale in which condition (13) is decided.
    pub fn gross_load(&self) -> f64 {
        self.loads
            .iter()
            .map(|l| (l.p2.abs() + l.p1.abs()) * (l.to - l.from))
            .sum()
    }

    /// Checks every field, then condition (13) with a margin: the net
    /// downward load must be at least [`MIN_NET_LOAD_FRACTION`] of the gross
    /// load, so that rounding cannot decide it (−5 on [3/5, 4/5] and 1 on
    /// [0, 1] sum to −4.4e-16, not 0).
    pub fn validate(&self) -> Result<(), SceneError> {
        if let Some(c) = self.name.chars().find(|&c| !printable(c)) {
            return Err(invalid(
                "name",
                format!("with U+{:04X}", c as u32),
                "a scene's name is printed and written into every output: give printable text without control or bidirectional-override characters",
            ));
        }
        if self.name.trim().is_empty() || self.name.chars().count() > MAX_NAME_CHARS {
            return Err(invalid(
                "name",
                format!("of {} characters", self.name.chars().count()),
                &format!("give a name of 1 to {MAX_NAME_CHARS} characters"),
            ));
        }
        check_material("material", " (--young)", " (--poisson)", &self.material)?;
        if let Some(lower) = &self.lower_material {
            check_material("lower_material", "", "", lower)?;
            if lower.plane != self.material.plane {
                return Err(invalid(
                    "lower_material.plane",
                    lower.plane.name(),
                    &format!(
                        "both bodies are one plane reduction: give plane = \"{}\" as in [material], or leave it out",
                        self.material.plane
                    ),
                ));
            }
        }
        if !(self.friction == 0.0
            || (self.friction >= MAGNITUDES.0 && self.friction <= MAX_FRICTION))
        {
            return Err(invalid(
                "friction (--friction)",
                self.friction,
                &format!(
                    "the friction coefficient must be 0 (frictionless) or lie in [{:e}, {MAX_FRICTION:e}] (the paper: 0.5; the stability map goes to 64)",
                    MAGNITUDES.0
                ),
            ));
        }
        if self.loads.is_empty() {
            return Err(invalid(
                "loads",
                "[]",
                "give at least one traction segment {from, to, p2} on the top side",
            ));
        }
        for (i, l) in self.loads.iter().enumerate() {
            let field = |name: &str| format!("loads[{i}].{name}");
            for (name, x) in [("from", l.from), ("to", l.to)] {
                if !(x.is_finite() && (0.0..=1.0).contains(&x)) {
                    return Err(invalid(&field(name), x, "segment ends must lie in [0, 1]"));
                }
            }
            if l.from >= l.to {
                return Err(invalid(
                    &field("to"),
                    l.to,
                    &format!("a segment must have from < to, here from = {}", l.from),
                ));
            }
            for (name, p) in [("p2", l.p2), ("p1", l.p1)] {
                if !(p == 0.0 || (p.abs() >= MAGNITUDES.0 && p.abs() <= MAGNITUDES.1)) {
                    return Err(invalid(
                        &field(name),
                        p,
                        &format!(
                            "a traction must be 0 or of size in [{:e}, {:e}], the range of units in which every solver is shown to give the same answer",
                            MAGNITUDES.0, MAGNITUDES.1
                        ),
                    ));
                }
            }
        }
        if self.levels.is_empty() {
            return Err(invalid(
                "levels",
                "[]",
                "give at least one mesh level, e.g. [\"1/64\"]",
            ));
        }
        for pair in self.levels.windows(2) {
            if pair[1].level() <= pair[0].level() {
                return Err(invalid(
                    "levels",
                    format!("{} then {}", pair[0], pair[1]),
                    "levels must go from coarse to fine, e.g. [\"1/8\", \"1/16\", \"1/32\", \"1/64\"]",
                ));
            }
        }
        if let Some(gap) = &self.gap {
            gap.validate()?;
        }
        if !(self.side_shift.is_finite() && self.side_shift.abs() <= MAX_SIDE_SHIFT) {
            return Err(invalid(
                "side_shift",
                self.side_shift,
                &format!(
                    "the held sides' prescribed u''_1 must be finite and at most {MAX_SIDE_SHIFT:e} in size (small strain on bodies of size 1; the paper: 0)"
                ),
            ));
        }
        if self.side_shift != 0.0 && self.hold == crate::mechanics::dofs::Hold::Sliding {
            return Err(invalid(
                "side_shift",
                self.side_shift,
                "a body free to slide (hold = \"sliding\") has no sides held in place to shift: load its top tangentially (p1) instead, or hold it by \"rollers\"",
            ));
        }
        let total = self.total_vertical_load();
        if !total.is_finite() {
            return Err(invalid(
                "loads",
                total,
                "the total vertical force of the tractions overflows; give tractions whose sum is a finite number",
            ));
        }
        if total >= 0.0 {
            return Err(SceneError::NoSolution { total });
        }
        let gross = self.gross_load();
        if -total < MIN_NET_LOAD_FRACTION * gross {
            return Err(SceneError::NearlyBalanced { total, gross });
        }
        Ok(())
    }
}

/// The longest scene name.
pub const MAX_NAME_CHARS: usize = 200;

/// Whether `c` may appear in a scene's name: not a control character (NUL,
/// a newline, an escape) and not one that reorders text when printed
/// (U+202E turns a terminal's line around).
fn printable(c: char) -> bool {
    !c.is_control()
        && !matches!(
            c,
            '\u{200E}' | '\u{200F}' | '\u{061C}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}'
        )
}

/// A coordinate given as a number or as a fraction string such as "1/3".
fn fraction<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Repr {
        Number(f64),
        Text(String),
    }
    match Repr::deserialize(d)? {
        Repr::Number(x) => Ok(x),
        Repr::Text(t) => parse_fraction(&t).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "'{t}' is not a number or a fraction such as \"1/3\""
            ))
        }),
    }
}

/// Parses "a/b" or a decimal.
pub fn parse_fraction(text: &str) -> Option<f64> {
    let t = text.trim();
    let value = match t.split_once('/') {
        Some((a, b)) => a.trim().parse::<f64>().ok()? / b.trim().parse::<f64>().ok()?,
        None => t.parse::<f64>().ok()?,
    };
    value.is_finite().then_some(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_problems_carry_the_papers_totals() {
        for (k, total) in [(1, -20.0), (2, -40.0), (3, -60.0)] {
            let s = Scene::paper_problem(k).unwrap();
            s.validate().unwrap();
            assert!((s.total_vertical_load() - total).abs() < 1e-12);
        }
        assert!(matches!(
            Scene::paper_problem(4),
            Err(SceneError::UnknownProblem(4))
        ));
    }

    #[test]
    fn upward_or_zero_total_load_has_no_solution() {
        let mut s = Scene::paper_problem(1).unwrap();
        s.loads[0].p2 = 60.0;
        assert!(matches!(s.validate(), Err(SceneError::NoSolution { total }) if total > 0.0));
        s.loads[0].p2 = 0.0;
        assert!(matches!(s.validate(), Err(SceneError::NoSolution { total }) if total == 0.0));
        // Mixed signs summing to zero: still no solution.
        s.loads = vec![
            Traction {
                from: 0.0,
                to: 0.5,
                p2: -10.0,

                p1: 0.0,
            },
            Traction {
                from: 0.5,
                to: 1.0,
                p2: 10.0,

                p1: 0.0,
            },
        ];
        assert!(matches!(s.validate(), Err(SceneError::NoSolution { .. })));
    }

    /// Condition (13) is decided with a margin relative to the gross load:
    /// −5 on [3/5, 4/5] and 1 on [0, 1] balance exactly, but their sum in
    /// floating point is −4.4e-16, which a test of the sign alone accepts.
    /// Problem 1 nearly balanced by an upward load keeps a net load of 5e-8
    /// of the gross, above the margin, and is accepted.
    #[test]
    fn condition_13_is_decided_with_a_margin_not_by_rounding() {
        let segment = |from: f64, to: f64, p2: f64| Traction {
            from,
            to,
            p2,
            p1: 0.0,
        };
        let mut s = Scene::paper_problem(1).unwrap();
        s.loads = vec![segment(0.6, 0.8, -5.0), segment(0.0, 1.0, 1.0)];
        let total = s.total_vertical_load();
        assert!(total < 0.0 && total > -1e-15, "rounding: {total:e}");
        assert!(matches!(
            s.validate(),
            Err(SceneError::NearlyBalanced { .. })
        ));
        let mut s = Scene::paper_problem(1).unwrap();
        s.loads.push(segment(2.0 / 3.0, 1.0, 59.999994));
        let fraction = -s.total_vertical_load() / s.gross_load();
        assert!((4e-8..6e-8).contains(&fraction), "{fraction:e}");
        s.validate().unwrap();
        s.loads[1].p2 = 59.99999999;
        assert!(matches!(
            s.validate(),
            Err(SceneError::NearlyBalanced { .. })
        ));
    }

    #[test]
    fn sizes_outside_the_tested_range_are_refused() {
        let bad = |f: fn(&mut Scene), field: &str| {
            let mut s = Scene::paper_problem(1).unwrap();
            f(&mut s);
            let msg = s.validate().unwrap_err().to_string();
            assert!(msg.contains(field) && msg.contains("1e50"), "{msg}");
        };
        bad(|s| s.loads[0].p2 = -1e308, "loads[0].p2");
        bad(|s| s.loads[0].p2 = -1e-60, "loads[0].p2");
        bad(|s| s.loads[0].p1 = 1e51, "loads[0].p1");
        bad(|s| s.material.young = 1e60, "material.young");
        bad(|s| s.material.young = 1e-51, "material.young");
        let mut s = Scene::paper_problem(1).unwrap();
        s.loads[0].p2 = -1e50;
        s.material.young = 1e-50;
        s.validate().unwrap();
    }

    #[test]
    fn invalid_fields_are_named() {
        let bad = |f: fn(&mut Scene), field: &str| {
            let mut s = Scene::paper_problem(1).unwrap();
            f(&mut s);
            let msg = s.validate().unwrap_err().to_string();
            assert!(msg.contains(field), "{msg}");
        };
        bad(|s| s.material.young = 0.0, "material.young");
        bad(|s| s.material.poisson = 0.5, "material.poisson");
        bad(|s| s.material.poisson = f64::NAN, "material.poisson");
        bad(|s| s.friction = -0.1, "friction");
        bad(|s| s.loads[0].to = 1.5, "loads[0].to");
        bad(|s| s.loads[0].from = 0.5, "loads[0].to");
        bad(|s| s.levels.reverse(), "levels");
        bad(|s| s.side_shift = f64::NAN, "side_shift");
        bad(|s| s.side_shift = -0.5, "side_shift");
        // A body free to slide has no sides held in place to shift.
        bad(
            |s| {
                s.hold = crate::mechanics::dofs::Hold::Sliding;
                s.side_shift = 1e-4;
            },
            "side_shift",
        );
        bad(|s| s.name = "a\u{0}b".into(), "name");
        bad(|s| s.name = "two\nlines".into(), "name");
        bad(|s| s.name = "abc\u{202E}fed".into(), "name");
        bad(|s| s.name = "\u{1b}[31mred".into(), "name");
        bad(|s| s.name = String::new(), "name");
        bad(|s| s.name = "x".repeat(201), "name");
        let mut s = Scene::paper_problem(1).unwrap();
        s.name = "задача 1 (𝓕 = 0.5)".into();
        s.validate().unwrap();
    }
}
