//! The starting configuration from the program's `initial` declarations: the coordinates it gives
//! (and which are held), and the assembled configuration that closes every loop from them.

use crate::diag::number::shortest;
use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::source::Span;

use super::assembly::{
    assemble_respecting, held, Assembled, AssemblyError, AssemblyOptions, Hold, Moved,
};
use super::eval;
use super::model::KinematicModel;

/// The program's starting configuration: a value per coordinate (0 where none is given), how
/// assembly treats it, and where it was given.
pub struct Starting {
    pub q: Vec<f64>,
    pub holds: Vec<Hold>,
    /// The `initial` declaration that gave each coordinate its value (the last one counts).
    pub spans: Vec<Option<Span>>,
}

impl Starting {
    /// Which coordinates are held (`fixed`).
    pub fn fixed(&self) -> Vec<bool> {
        held(&self.holds)
    }
}

/// Starting coordinates and which of them are held, from the program's `initial` declarations
/// (coordinates without one start at 0).
pub fn initial_coordinates(
    mechanism: &Mechanism,
    model: &KinematicModel,
) -> Result<(Vec<f64>, Vec<bool>), Diagnostic> {
    let starting = starting(mechanism, model)?;
    let fixed = starting.fixed();
    Ok((starting.q, fixed))
}

/// The starting configuration the program's `initial` declarations give, each driven
/// coordinate at its law's value at time 0 and held there (a drive overrides `initial`).
pub fn starting(mechanism: &Mechanism, model: &KinematicModel) -> Result<Starting, Diagnostic> {
    let count = model.coordinate_count;
    let mut starting = Starting {
        q: vec![0.0; count],
        holds: vec![Hold::Free; count],
        spans: vec![None; count],
    };
    for initial in mechanism.initial.iter().filter(|i| i.order == 0) {
        let Some(joint) = model.joint_of_join(initial.join) else {
            continue;
        };
        let value = eval::eval(&initial.value, &model.unknowns).map_err(|_| {
            Diagnostic::error("E0803", "an initial value must be a number").primary(
                initial.span,
                "its value depends on something without a value",
            )
        })?;
        let index = joint.offset + initial.coordinate;
        starting.q[index] = value;
        starting.spans[index] = Some(initial.span);
        // The last value counts, and a coordinate any of them marks `fixed` is held.
        starting.holds[index] = match (initial.fixed, starting.holds[index]) {
            (true, _) | (_, Hold::Fixed) => Hold::Fixed,
            _ if initial.guess => Hold::Free,
            _ => Hold::Given,
        };
    }
    let drives = super::drives::resolve(mechanism, model).map_err(first_error)?;
    for drive in &drives {
        starting.q[drive.coordinate] = drive.law.at(0.0).position;
        starting.holds[drive.coordinate] = Hold::Fixed;
        starting.spans[drive.coordinate] = Some(drive.span);
    }
    Ok(starting)
}

/// The first of several diagnostics (the rest are reported when the model is built).
fn first_error(mut errors: Vec<Diagnostic>) -> Diagnostic {
    errors.swap_remove(0)
}

/// An assembled starting configuration, with a warning (W0801) for each given value assembly
/// had to change.
pub struct InitialAssembly {
    pub assembled: Assembled,
    pub fixed: Vec<bool>,
    pub warnings: Vec<Diagnostic>,
}

/// Assembles the mechanism from its `initial` values, holding the `fixed` ones and keeping the
/// given ones where the loops allow; a failure is reported as a diagnostic on the loop that
/// stays open.
pub fn assemble_initial(
    mechanism: &Mechanism,
    model: &KinematicModel,
    options: &AssemblyOptions,
) -> Result<InitialAssembly, Vec<Diagnostic>> {
    let starting = starting(mechanism, model).map_err(|d| vec![d])?;
    match assemble_respecting(model, &starting.q, &starting.holds, options) {
        Ok(assembled) => {
            let names = model.coordinate_names();
            let warnings = moved_warning(&names, &assembled.moved, &starting)
                .into_iter()
                .collect();
            Ok(InitialAssembly {
                assembled,
                fixed: starting.fixed(),
                warnings,
            })
        }
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

/// One warning for the given values assembly changed, each labelled where it was given.
fn moved_warning(names: &[String], moved: &[Moved], starting: &Starting) -> Option<Diagnostic> {
    let first = moved.first()?;
    let change = |m: &Moved| {
        format!(
            "`{}` from {} to {}",
            names[m.coordinate],
            shortest(m.given),
            shortest(m.assembled)
        )
    };
    let message = match moved.len() {
        1 => format!("assembly moved {}", change(first)),
        n => format!("assembly moved {n} given values"),
    };
    let mut warning = Diagnostic::warning("W0801", message);
    for (k, m) in moved.iter().enumerate() {
        if let Some(span) = starting.spans[m.coordinate] {
            let label = format!("moved to {}", shortest(m.assembled));
            warning = if k == 0 {
                warning.primary(span, label)
            } else {
                warning.secondary(span, label)
            };
        }
        if moved.len() > 1 {
            warning = warning.note(change(m));
        }
    }
    warning
        .note("no closed configuration holds every given value: this is the smallest change that closes the loops")
        .help("give the values of a closed configuration (the ones above), mark the values to hold `fixed` (the others then move), or mark starting guesses `guess`")
        .into()
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
