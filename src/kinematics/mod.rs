//! Kinematics of the numbered mechanism: the numeric model, forward kinematics with analytic
//! Jacobians, closure of the complementary links, assembly, joint analysis and mobility.

pub mod assembly;
pub mod closure;
pub mod eval;
pub mod forward;
pub mod joint;
pub mod mobility;
pub mod model;
pub mod spatial;

use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use model::KinematicModel;

/// Starting coordinates and which of them are held, from the program's `initial` declarations
/// (coordinates without one start at 0).
pub fn initial_coordinates(
    mechanism: &Mechanism,
    model: &KinematicModel,
) -> Result<(Vec<f64>, Vec<bool>), Diagnostic> {
    let mut q = vec![0.0; model.coordinate_count];
    let mut fixed = vec![false; model.coordinate_count];
    for initial in mechanism.initial.iter().filter(|i| i.order == 0) {
        let Some(joint) = model.joint_of_join(initial.join) else {
            continue;
        };
        let value = eval::eval(&initial.value, &model.unknowns, &[]).map_err(|_| {
            Diagnostic::error("E0803", "an initial value must be a number").primary(
                initial.span,
                "its value depends on something without a value",
            )
        })?;
        q[joint.offset + initial.coordinate] = value;
        fixed[joint.offset + initial.coordinate] |= initial.fixed;
    }
    Ok((q, fixed))
}

/// A deterministic pseudo-random number in [-1, 1] for sample `sample`, coordinate `i`
/// (SplitMix64 of the pair).
pub(crate) fn jitter(sample: usize, i: usize) -> f64 {
    let mut z = (sample as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (i as u64).wrapping_add(0x632B_E59B_D9B4_E019);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}
