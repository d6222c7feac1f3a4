//! Scene files (TOML). Unknown keys are errors; every error is one line that
//! names the file, the place and what is wrong.

use std::collections::BTreeMap;
use std::path::Path;

use contactlab_solvers::Stopping;
use serde::Deserialize;
use thiserror::Error;

use crate::coulomb::continuation::Schedule;
use crate::mechanics::material::Material;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::{Scene, SceneError, Traction, default_friction, default_levels};
use crate::settings::{CertificateSettings, Settings};

/// Scene files larger than this are refused (a scene is a few hundred bytes).
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// The scene file format: a scene and, optionally, the settings of a run.
///
/// ```toml
/// name = "problem 1"
/// friction = 0.5                  # Coulomb coefficient
/// levels = ["1/8", "1/16", "1/32", "1/64"]
/// schedule = "revisit"            # optional (unset: each solver's own)
/// stopping = "relative"           # optional: relative (default) or paper
///
/// [material]                      # optional, the paper's values by default
/// young = 73e3
/// poisson = 0.34
/// plane = "strain"
///
/// [lower_material]                # optional: the lower body's own (default: [material])
/// young = 200e3
/// poisson = 0.3
///
/// hold = "roller"                 # optional: "roller" (x = 1, the paper's), "rollers" (on x = 0 and x = 1) or "sliding" (rollers on both sides that move together: a second rigid mode, held by friction)
/// side_shift = 0.0                # optional: u''_1 prescribed on the held sides (shears the upper body)
///
/// [gap]                           # optional: the initial gap along Γ_K
/// shape = "parabola"              # (x − center)²/(2 radius), or "table" with x, d
/// center = 0.5
/// radius = 8.0
///
/// [[loads]]                       # vertical tractions on the top side y = 1
/// from = 0.0
/// to = "1/3"
/// p2 = -60.0
///
/// [coulomb]                       # optional: the fixed point's settings
/// epsilon = 1e-8
///
/// [certificate]                   # optional
/// tolerance = 1e-6
///
/// [solver.relaxation]             # optional, one section per registered solver
/// r = 1e7
/// ```
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: String,
    #[serde(default)]
    pub material: Material,
    /// The lower body's material, when it differs (`[lower_material]`).
    pub lower_material: Option<Material>,
    #[serde(default = "default_friction")]
    pub friction: f64,
    pub loads: Vec<Traction>,
    #[serde(default = "default_levels")]
    pub levels: Vec<MeshSize>,
    /// The initial gap along Γ_K (`[gap]` with `shape = "parabola"`,
    /// `center`, `radius`, or `shape = "table"`, `x`, `d`).
    pub gap: Option<crate::mechanics::gap::Gap>,
    /// How the upper body is held sideways: "roller" (the paper's, on
    /// x = 1) or "rollers" (u''_1 = 0 on both sides, symmetric).
    #[serde(default)]
    pub hold: crate::mechanics::dofs::Hold,
    /// The horizontal displacement u''_1 prescribed on the held sides
    /// (default 0: the paper's roller in place).
    #[serde(default)]
    pub side_shift: f64,
    pub schedule: Option<Schedule>,
    pub stopping: Option<Stopping>,
    pub certificate: Option<CertificateSettings>,
    /// The fixed point's settings, by name.
    #[serde(default)]
    pub coulomb: BTreeMap<String, toml::Value>,
    /// Each registered solver's settings, by solver and name.
    #[serde(default)]
    pub solver: BTreeMap<String, BTreeMap<String, toml::Value>>,
}

impl SceneFile {
    /// The scene and the settings the file gives (defaults where it is
    /// silent); an unknown setting is an error that names it.
    pub fn split(self) -> Result<(Scene, Settings), String> {
        let mut settings = Settings::default();
        settings.stopping = self.stopping.unwrap_or_default();
        settings.schedule = self.schedule;
        settings.certificate = self.certificate.unwrap_or_default();
        let tree = |v: &toml::Value| serde_json::to_value(v).map_err(|e| e.to_string());
        for (name, value) in &self.coulomb {
            settings.set(&format!("coulomb.{name}"), tree(value)?)?;
        }
        for (solver, section) in &self.solver {
            for (name, value) in section {
                settings.set(&format!("{solver}.{name}"), tree(value)?)?;
            }
        }
        let scene = Scene {
            name: self.name,
            material: self.material,
            lower_material: self.lower_material,
            friction: self.friction,
            loads: self.loads,
            levels: self.levels,
            gap: self.gap,
            hold: self.hold,
            side_shift: self.side_shift,
        };
        Ok((scene, settings))
    }
}

/// A scene file that cannot be used.
#[derive(Debug, Error)]
pub enum SceneFileError {
    #[error("cannot read scene file {path}: {reason}")]
    Read { path: String, reason: String },
    #[error("scene file {path}, line {line}, column {column}: {message}")]
    Parse {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("scene file {path}: {error}")]
    Invalid { path: String, error: SceneError },
    #[error("scene file {path}: {message}")]
    Settings { path: String, message: String },
}

/// Reads, parses and validates a scene file.
pub fn load(path: &Path) -> Result<(Scene, Settings), SceneFileError> {
    let shown = path.display().to_string();
    let text = crate::io::guarded::read_small_text(path, MAX_SCENE_BYTES).map_err(|reason| {
        SceneFileError::Read {
            path: shown.clone(),
            reason,
        }
    })?;
    let (scene, settings) = parse(&text)
        .map_err(|(line, column, message)| SceneFileError::Parse {
            path: shown.clone(),
            line,
            column,
            message,
        })?
        .split()
        .map_err(|message| SceneFileError::Settings {
            path: shown.clone(),
            message,
        })?;
    scene.validate().map_err(|error| SceneFileError::Invalid {
        path: shown.clone(),
        error,
    })?;
    settings
        .validate()
        .map_err(|message| SceneFileError::Settings {
            path: shown,
            message,
        })?;
    Ok((scene, settings))
}

/// Parses scene text; on error gives (line, column, one-line message).
pub fn parse(text: &str) -> Result<SceneFile, (usize, usize, String)> {
    toml::from_str::<SceneFile>(text).map_err(|e| {
        let offset = e.span().map(|s| s.start).unwrap_or(0).min(text.len());
        let before = &text[..floor_char_boundary(text, offset)];
        let line = before.matches('\n').count() + 1;
        let column = before
            .rsplit('\n')
            .next()
            .map(|l| l.chars().count())
            .unwrap_or(0)
            + 1;
        let message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
        (line, column, message)
    })
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}
