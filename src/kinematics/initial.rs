//! The starting configuration from the program's `initial` declarations: the coordinates it gives
//! (and which are held), and the assembled configuration that closes every loop from them.

use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;

use super::assembly::{assemble, Assembled, AssemblyError, AssemblyOptions};
use super::eval;
use super::model::KinematicModel;

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

/// Assembles the mechanism from its `initial` values, holding the `fixed` ones; a failure is
/// reported as a diagnostic on the loop that stays open.
pub fn assemble_initial(
    mechanism: &Mechanism,
    model: &KinematicModel,
    options: &AssemblyOptions,
) -> Result<(Assembled, Vec<bool>), Vec<Diagnostic>> {
    let (start, fixed) = initial_coordinates(mechanism, model).map_err(|d| vec![d])?;
    match assemble(model, &start, &fixed, options) {
        Ok(assembled) => Ok((assembled, fixed)),
        Err(AssemblyError::Evaluation(e)) => Err(vec![Diagnostic::error(
            "E0804",
            format!(
                "cannot evaluate the geometry: {}",
                eval::describe(&e, mechanism)
            ),
        )]),
        Err(AssemblyError::NoAssembly { loop_errors, .. }) => {
            Err(vec![no_assembly(mechanism, model, &loop_errors)])
        }
    }
}

/// A residual for people: three significant digits, and "< 1e-6" for what is only round-off.
fn gap(value: f64) -> String {
    if value < 1e-6 {
        "< 1e-6".to_string()
    } else {
        format!("{value:.3}")
    }
}

fn no_assembly(
    mechanism: &Mechanism,
    model: &KinematicModel,
    loop_errors: &[(f64, f64)],
) -> Diagnostic {
    let worst = loop_errors
        .iter()
        .enumerate()
        .max_by(|a, b| (a.1 .0 + a.1 .1).total_cmp(&(b.1 .0 + b.1 .1)))
        .map(|(k, _)| k)
        .unwrap_or(0);
    let joint = &model.complementary()[worst];
    let (position, rotation) = loop_errors[worst];
    let join = mechanism.join(joint.join);
    let mut diagnostic = Diagnostic::error("E0805", format!("the loop closed by join `{}` cannot be assembled", joint.name))
        .primary(join.span, format!("still {} m and {} rad apart", gap(position), gap(rotation)))
        .help("check the geometry, or give starting values closer to an assembled configuration with `initial`");
    for (k, (p, r)) in loop_errors.iter().enumerate() {
        if k != worst && (p + r) > 1e-9 {
            let other = &model.complementary()[k];
            diagnostic = diagnostic.note(format!(
                "the loop closed by `{}` is also open ({} m, {} rad)",
                other.name,
                gap(*p),
                gap(*r)
            ));
        }
    }
    diagnostic
}
