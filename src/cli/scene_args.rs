//! Which scene a command works on: a built-in problem of the paper or a
//! scene file, with the material and mesh overridden from the command line.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::{Overrides, Scene};
use crate::settings::Settings;

/// Which scene, on which mesh, with which material: a built-in problem of the
/// paper or a scene file, with optional overrides.
#[derive(Debug, Clone, Args)]
pub struct SceneArgs {
    /// The paper's problem: 1 (P''_2 = -60 on the left third of the top side),
    /// 2 (-120 on the left third) or 3 (-60 on the whole top side).
    #[arg(
        long,
        value_name = "N",
        conflicts_with = "scene",
        allow_hyphen_values = true
    )]
    pub problem: Option<u32>,
    /// A scene file (TOML) instead of a built-in problem.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Finest mesh size h = 1/2^k in the paper's notation (e.g. 1/64); the
    /// continuation levels run 1/8, 1/16, ..., h. Default: the scene's levels
    /// (the paper's 1/8 to 1/64).
    #[arg(long, value_name = "1/2^k")]
    pub h: Option<MeshSize>,
    #[command(flatten)]
    pub material: MaterialArgs,
}

impl SceneArgs {
    /// The scene with the overrides applied, validated (condition (13) included).
    pub fn resolve(&self) -> Result<Scene> {
        Ok(self.load()?.0)
    }

    /// The scene and the settings it brings (a scene file's sections, else
    /// the defaults), with the scene overrides applied and validated.
    pub fn load(&self) -> Result<(Scene, Settings)> {
        let (scene, settings) = match (&self.scene, self.problem) {
            (Some(path), _) => crate::formats::scene_file::load(path)?,
            (None, Some(n)) => (Scene::paper_problem(n)?, Settings::default()),
            (None, None) => anyhow::bail!(
                "no scene given: add --problem N (the paper's problem 1, 2 or 3) or --scene FILE (a scene file)"
            ),
        };
        Ok((self.material.apply(scene, self.h)?, settings))
    }
}

/// The material and friction overrides: a single scene's (with its --h,
/// [`SceneArgs`]), and those of a command that takes several scenes
/// (`sweep`), applied to each.
#[derive(Debug, Clone, Default, Args)]
pub struct MaterialArgs {
    /// Young's modulus E (default 73e3).
    #[arg(long, value_name = "E", allow_hyphen_values = true)]
    pub young: Option<f64>,
    /// Poisson's ratio ν, in (-1, 0.5) (default 0.34).
    #[arg(long, value_name = "NU", allow_hyphen_values = true)]
    pub poisson: Option<f64>,
    /// Plane strain or plane stress (default strain; the paper does not say).
    #[arg(long, value_parser = crate::study::catalog::plane_choice())]
    pub plane: Option<PlaneModel>,
    /// Coulomb friction coefficient 𝓕 ≥ 0 (default 0.5; 0 is frictionless).
    #[arg(long, value_name = "F", allow_hyphen_values = true)]
    pub friction: Option<f64>,
}

impl MaterialArgs {
    /// `scene` with these overrides and the finest mesh `h` (None: its
    /// own), validated (condition (13) included).
    pub fn apply(&self, scene: Scene, h: Option<MeshSize>) -> Result<Scene> {
        Ok(Overrides {
            h,
            young: self.young,
            poisson: self.poisson,
            plane: self.plane,
            friction: self.friction,
        }
        .apply(scene)?)
    }
}
