//! The problem's own scales, from its data alone (see [`Scales`]).

use serde::{Deserialize, Serialize};

use super::{ContactNode, ProblemError};
use crate::numerics::linalg::{Csr, max_abs};

/// The smallest net load, relative to the gross load F = Σ|f_i|, that a
/// problem with rigid modes may carry along each of them. The contact
/// forces must balance the load along a rigid mode (paper condition (13));
/// below this fraction the net load cannot be told from the rounding of the
/// gross one at fine meshes, and contact pressures, which are of the size
/// of the net load, cannot be certified in double precision (a relative
/// error ε of the answer in the gross load's scale is ε·F/N in theirs).
pub const MIN_NET_LOAD_FRACTION: f64 = 1e-8;

/// The problem's own scales, from its data alone. Every stopping test of a
/// solver in relative mode and every measure of the certificate is stated
/// in them, so that multiplying the loads by a factor, or the stiffness and
/// the loads together, changes no iteration count and no verdict.
///
/// - force F = Σ_i |f_i|, the gross load (for a traction load: ∫|P| ds,
///   whatever the mesh);
/// - contact load N, the load the contact pressures must carry: for each
///   rigid mode z that moves a jump (z_t ≠ 0 at some contact node),
///   |zᵀf| / ‖z‖∞ (the smallest), since the contact forces balance the load
///   along z; F when the problem has no such mode. A mode that moves only
///   slips (a body free sideways) is held by friction alone, and its load
///   may be zero: it sets no scale;
/// - length L = Σ_i w_i (the length of Γ_K);
/// - stiffness K = max_i A_ii;
/// - pressure P = N/L (the mean contact pressure): measured in the net load
///   and not the gross one, so that an answer cannot hide a wrong contact
///   force in the scale of a load that the contact does not carry (a load
///   nearly balanced by an upward one has contact forces of the size of the
///   net load, not of the gross);
/// - displacement U = F/K (displacements and gaps follow the whole load).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scales {
    pub force: f64,
    pub contact_load: f64,
    pub length: f64,
    pub stiffness: f64,
    pub pressure: f64,
    pub displacement: f64,
}

impl Scales {
    pub(super) fn of(
        a: &Csr,
        f: &[f64],
        contacts: &[ContactNode],
        rigid_modes: &[Vec<f64>],
    ) -> Result<Self, ProblemError> {
        let or_one = |x: f64| if x > 0.0 { x } else { 1.0 };
        let force = or_one(f.iter().map(|x| x.abs()).sum());
        let mut contact_load = f64::INFINITY;
        for (index, z) in rigid_modes.iter().enumerate() {
            if !moves_a_jump(z, contacts) {
                continue;
            }
            let size = max_abs(z);
            let along: f64 = z.iter().zip(f).map(|(zk, fk)| (zk / size) * fk).sum();
            let load = along.abs();
            // NaN (an overflow) fails too.
            if load.is_nan() || load < MIN_NET_LOAD_FRACTION * force {
                return Err(ProblemError::NetLoad {
                    index,
                    fraction: load / force,
                });
            }
            contact_load = contact_load.min(load);
        }
        if contact_load == f64::INFINITY {
            contact_load = force;
        }
        let length = or_one(contacts.iter().map(|c| c.weight).sum());
        let stiffness = or_one(
            (0..a.nrows())
                .filter_map(|i| {
                    let (cols, vals) = a.row(i);
                    let k = cols.find(i)?;
                    Some(vals[k].abs())
                })
                .fold(0.0, f64::max),
        );
        let scales = Self {
            force,
            contact_load,
            length,
            stiffness,
            pressure: contact_load / length,
            displacement: force / stiffness,
        };
        for (what, value) in [
            ("force", scales.force),
            ("contact load", scales.contact_load),
            ("stiffness", scales.stiffness),
            ("pressure", scales.pressure),
            ("displacement", scales.displacement),
        ] {
            if !(value.is_finite() && value.is_normal()) {
                return Err(ProblemError::Scale {
                    what,
                    value,
                    why: "it over- or underflows in double precision; \
                          the loads and the stiffness are too far apart in magnitude",
                });
            }
        }
        Ok(scales)
    }
}

/// Whether the rigid mode z moves a jump t_i (the contact pressures carry
/// its load), rather than slips alone (friction carries it).
pub fn moves_a_jump(z: &[f64], contacts: &[ContactNode]) -> bool {
    contacts.iter().any(|c| z[c.t] != 0.0)
}
