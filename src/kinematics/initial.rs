//! The starting configuration from the program's `initial` declarations: the coordinates it gives
//! (and which are held), and the assembled configuration that closes every loop from them.

use crate::diag::number::shortest;
use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::source::Span;

use super::assembly::{
    assemble_respecting, held, Assembled, AssemblyError, AssemblyOptions, Hold, Moved,
};
use super::branch::{self, Coincidence, FarGuess};
use super::eval;
use super::isolation::{self, Isolated};
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
#[cfg(lsdc_internals)]
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

/// An assembled starting configuration, with its warnings: the given values assembly had to
/// change (W0801), and the signs that it reached another branch than the one meant (W0803
/// singular, W0804 joins brought together, W0805 guesses moved far).
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
            let isolated = isolation::isolated(model, &assembled.q);
            if let Ok(Some(isolated)) = &isolated {
                return Err(vec![isolated_error(mechanism, model, isolated)]);
            }
            let names = model.coordinate_names();
            let mut warnings: Vec<Diagnostic> = moved_warning(&names, &assembled.moved, &starting)
                .into_iter()
                .collect();
            warnings.extend(branch_warnings(mechanism, model, &starting, &assembled.q));
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

/// E0830: a closed configuration the loops hold still, though they allow motions to first
/// order.
fn isolated_error(
    mechanism: &Mechanism,
    model: &KinematicModel,
    isolated: &Isolated,
) -> Diagnostic {
    let joint = &model.complementary()[isolated.stressed_loop()];
    let mut joins: Vec<String> = Vec::new();
    for &coordinate in &isolated.moving {
        let moving = (model.joints.iter())
            .find(|j| (j.offset..j.offset + j.coordinate_count()).contains(&coordinate));
        if let Some(name) = moving.map(|j| format!("`{}`", j.name)) {
            if !joins.contains(&name) {
                joins.push(name);
            }
        }
    }
    let joins = match joins.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
        None => "the joins".to_string(),
    };
    let ways = match isolated.first_order {
        1 => "1 way".to_string(),
        n => format!("{n} independent ways"),
    };
    Diagnostic::error(
        "E0830",
        "the mechanism cannot move: its loops close only at the assembled configuration",
    )
    .primary(
        mechanism.join(joint.join).span,
        "closes a loop that holds the mechanism still",
    )
    .note(format!(
        "to first order the loops let {joins} move in {ways}, but each of those motions opens a loop at second order: no other closed configuration is near this one"
    ))
    .note("a planar chain is held so when one of its bars, or its ground, is exactly as long as all the others together: it closes only stretched on one line")
    .help("a run from here cannot move and would shrink its steps to nothing; change a length so that the loop closes with room to move (each bar shorter than the others together), or join the bodies with `weld` if a rigid structure is meant")
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
    let changes: Vec<(usize, f64, String)> = (moved.iter())
        .map(|m| (m.coordinate, m.assembled, change(m)))
        .collect();
    let warning = labelled_at_each_value(Diagnostic::warning("W0801", message), &changes, starting);
    warning
        .note("no closed configuration holds every given value: this is the smallest change that closes the loops")
        .help("give the values of a closed configuration (the ones above), mark the values to hold `fixed` (the others then move), or mark starting guesses `guess`")
        .into()
}

/// The warnings on the branch a closed configuration lies on (`branch`): none for a tree, nor
/// when a configuration sampled to compare with cannot be evaluated (the assembled one was).
fn branch_warnings(
    mechanism: &Mechanism,
    model: &KinematicModel,
    starting: &Starting,
    q: &[f64],
) -> Vec<Diagnostic> {
    let Some(first_loop) = model.complementary().first() else {
        return Vec::new();
    };
    let mut warnings = Vec::new();
    let help = "give starting values near the configuration you mean with `initial` (from values all zero, a linkage often assembles folded), and check what `lsdc assemble` prints";
    if let Ok(found) = branch::examine(model, q) {
        if found.singular() {
            let more = found.generic_rank - found.rank;
            let ways = if more == 1 { "way" } else { "ways" };
            warnings.push(
                Diagnostic::warning(
                    "W0803",
                    format!("the assembled configuration is singular: it moves in {more} {ways} more than the mechanism"),
                )
                .primary(mechanism.join(first_loop.join).span, "closes a loop of this configuration")
                .note(format!(
                    "the loops' constraints have rank {} here and {} at other closed configurations of the mechanism (tree dof {})",
                    found.rank, found.generic_rank, found.tree_dof
                ))
                .help(help),
            );
        }
        if let Some(first) = found.coinciding.first() {
            warnings.push(coinciding_warning(
                mechanism,
                model,
                &found.coinciding,
                first,
                help,
            ));
        }
    }
    let guessed: Vec<bool> = (0..q.len())
        .map(|i| starting.holds[i] == Hold::Free && starting.spans[i].is_some())
        .collect();
    let far = branch::far_guesses(model, &starting.q, q, &guessed);
    if let Some(first) = far.first() {
        warnings.push(far_guesses_warning(model, starting, &far, first));
    }
    warnings
}

/// W0804: joins brought to one point that stand apart elsewhere.
fn coinciding_warning(
    mechanism: &Mechanism,
    model: &KinematicModel,
    coinciding: &[Coincidence],
    first: &Coincidence,
    help: &str,
) -> Diagnostic {
    let name = |joint: usize| &model.joints[joint].name;
    let span = |joint: usize| mechanism.join(model.joints[joint].join).span;
    let point = |p: &nalgebra::Vector3<f64>| {
        format!("[{}, {}, {}]", rounded(p.x), rounded(p.y), rounded(p.z))
    };
    let mut warning = Diagnostic::warning(
        "W0804",
        format!(
            "the joins `{}` and `{}` stand at one point, {}",
            name(first.first),
            name(first.second),
            point(&first.point)
        ),
    )
    .primary(span(first.first), "here")
    .secondary(span(first.second), "at the same point");
    for other in &coinciding[1..] {
        warning = warning.note(format!(
            "so do `{}` and `{}`, at {}",
            name(other.first),
            name(other.second),
            point(&other.point)
        ));
    }
    warning
        .note(format!(
            "at other closed configurations of the mechanism they stand {} apart: this one is folded",
            rounded(first.apart)
        ))
        .help(help)
}

/// W0805: guesses that assembly moved by more than a quarter turn.
fn far_guesses_warning(
    model: &KinematicModel,
    starting: &Starting,
    far: &[FarGuess],
    first: &FarGuess,
) -> Diagnostic {
    let names = model.coordinate_names();
    let change = |f: &FarGuess| {
        format!(
            "`{}` from {} to {} (a change of {} rad, whole turns aside)",
            names[f.coordinate],
            shortest(f.guess),
            shortest(f.assembled),
            rounded(f.change)
        )
    };
    let message = match far.len() {
        1 => format!("assembly moved the guess {}", change(first)),
        n => format!("assembly moved {n} guesses by more than a quarter turn"),
    };
    let changes: Vec<(usize, f64, String)> = (far.iter())
        .map(|f| (f.coordinate, f.assembled, change(f)))
        .collect();
    let warning = labelled_at_each_value(Diagnostic::warning("W0805", message), &changes, starting);
    warning
        .note("the configuration reached may lie on another assembly branch than the one the guesses describe")
        .help("give guesses near the configuration you mean (mark them `fixed` to hold them), and check what `lsdc assemble` prints")
}

/// `warning` labelled at the `initial` of each starting value assembly moved (coordinate, value
/// reached, its change in words), the first label primary, with a note per value when there
/// are several.
fn labelled_at_each_value(
    mut warning: Diagnostic,
    changes: &[(usize, f64, String)],
    starting: &Starting,
) -> Diagnostic {
    for (k, (coordinate, assembled, change)) in changes.iter().enumerate() {
        if let Some(span) = starting.spans[*coordinate] {
            let label = format!("moved to {}", shortest(*assembled));
            warning = match k {
                0 => warning.primary(span, label),
                _ => warning.secondary(span, label),
            };
        }
        if changes.len() > 1 {
            warning = warning.note(change.clone());
        }
    }
    warning
}

/// Four significant digits, for positions and changes read by people.
fn rounded(value: f64) -> String {
    shortest(format!("{value:.3e}").parse().unwrap_or(value))
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
