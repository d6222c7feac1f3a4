//! The classical scenes of `scenes/` (Hertz's line contact, a flat punch,
//! Cattaneo–Mindlin sheared and free to slide), compiled in from their
//! committed files: what `verify`, the benchmark collection and the
//! stability map run is what a user reads there.

use anyhow::{Context, Result};

use crate::formats::scene_file;
use crate::mechanics::scene::Scene;

/// The classical scenes, as committed in `scenes/`: what `verify` runs is
/// what a user reads there.
pub const SCENES: [(&str, &str); 4] = [
    ("hertz", include_str!("../../scenes/hertz.toml")),
    ("flat_punch", include_str!("../../scenes/flat_punch.toml")),
    (
        "cattaneo_mindlin",
        include_str!("../../scenes/cattaneo_mindlin.toml"),
    ),
    (
        "cattaneo_mindlin_sliding",
        include_str!("../../scenes/cattaneo_mindlin_sliding.toml"),
    ),
];

/// A classical scene, read from its committed file.
pub fn scene(name: &str) -> Result<Scene> {
    let (_, text) = SCENES
        .iter()
        .find(|(n, _)| *n == name)
        .with_context(|| format!("no classical scene named {name}"))?;
    let (scene, _) = scene_file::parse(text)
        .map_err(|(l, c, m)| anyhow::anyhow!("scenes/{name}.toml, line {l}, column {c}: {m}"))?
        .split()
        .map_err(anyhow::Error::msg)?;
    scene.validate()?;
    Ok(scene)
}
