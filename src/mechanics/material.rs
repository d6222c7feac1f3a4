//! Isotropic linear elasticity in the plane: σ = D ε with engineering shear.

use serde::{Deserialize, Serialize};

/// Which plane reduction of 3-D elasticity. The paper does not say; plane
/// strain is the default (a thick body), plane stress is the thin-plate reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlaneModel {
    Strain,
    Stress,
}

impl PlaneModel {
    pub const ALL: [Self; 2] = [Self::Strain, Self::Stress];

    /// Its name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            PlaneModel::Strain => "strain",
            PlaneModel::Stress => "stress",
        }
    }
}

impl std::fmt::Display for PlaneModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Young's modulus E, Poisson's ratio ν and the plane model. Defaults are the
/// paper's: E = 73·10³, ν = 0.34, plane strain.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Material {
    pub young: f64,
    pub poisson: f64,
    pub plane: PlaneModel,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            young: 73e3,
            poisson: 0.34,
            plane: PlaneModel::Strain,
        }
    }
}

impl Material {
    /// The 3×3 matrix D of σ = D ε for ε = (ε11, ε22, 2ε12).
    pub fn elasticity_matrix(&self) -> [[f64; 3]; 3] {
        let (e, nu) = (self.young, self.poisson);
        let shear = e / (2.0 * (1.0 + nu));
        match self.plane {
            PlaneModel::Strain => {
                let c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
                [
                    [c * (1.0 - nu), c * nu, 0.0],
                    [c * nu, c * (1.0 - nu), 0.0],
                    [0.0, 0.0, shear],
                ]
            }
            PlaneModel::Stress => {
                let c = e / (1.0 - nu * nu);
                [[c, c * nu, 0.0], [c * nu, c, 0.0], [0.0, 0.0, shear]]
            }
        }
    }
}
