//! `output name = value;`: the value must be something a run can write at each output (a scalar,
//! a vector, a matrix, or a frame whose state is written), and each name one column group.

use crate::diag::Diagnostic;
use crate::syntax::ast::{Name, OutputDecl};

use super::checker::Checker;
use super::types::{ScopeId, Ty};

/// The columns every run writes besides the coordinates: an output cannot take their names.
pub const RUN_COLUMNS: [&str; 3] = ["time", "kinetic_energy", "potential_energy"];

impl<'w> Checker<'w> {
    pub(super) fn output(&mut self, output: &'w OutputDecl, scope: ScopeId) {
        let mut ctx = self.ctx(scope);
        let ty = self.expr(&output.value, &mut ctx);
        if let Some(diagnostic) = type_error(output, ty) {
            self.report(diagnostic);
        }
        let name = &output.name;
        if RUN_COLUMNS.contains(&&*name.name) {
            self.report(
                Diagnostic::error(
                    "E0462",
                    format!(
                        "`{}` is a column of every run, not a name for an output",
                        name.name
                    ),
                )
                .primary(name.span, "this name is taken by the run's own column")
                .help(format!(
                    "give the output another name, such as `{}_out`",
                    name.name
                )),
            );
        }
        let key: (ScopeId, Name) = (scope, name.name);
        if let Some(&first) = self.outputs.get(&key) {
            self.report(
                Diagnostic::error("E0461", format!("output `{}` is declared twice", name.name))
                    .primary(name.span, "second declaration")
                    .secondary(first, "first declaration")
                    .help("each output names its own columns: rename one of them"),
            );
        } else {
            self.outputs.insert(key, name.span);
        }
    }
}

/// Why a value of type `ty` cannot be an output, with the fix.
fn type_error(output: &OutputDecl, ty: Ty) -> Option<Diagnostic> {
    let help = match ty.numeric() {
        Ty::Scalar | Ty::Vector | Ty::Matrix | Ty::Frame | Ty::Body | Ty::Error => return None,
        Ty::Rotation => "a rotation is not written as numbers: output the orientation of a frame, `orientation(F)`, a matrix (nine columns)".to_string(),
        Ty::Displacement => format!(
            "place it on a body to make a frame: `output {} = <displacement> @ <body>;`",
            output.name.name
        ),
        Ty::Force | Ty::Torque => "write its vector: `output f = <effort>.value;`".to_string(),
        Ty::Join => "write one of its coordinates or rates: `output a = crank.q;` or `crank.q'`".to_string(),
        _ => "an output is a scalar, a vector, a matrix or a frame, e.g. `output tip = position(arm.tip);`".to_string(),
    };
    Some(
        Diagnostic::error(
            "E0460",
            format!(
                "an output must be a scalar, a vector, a matrix or a frame, found {}",
                ty.with_article()
            ),
        )
        .primary(output.value.span, format!("this is {}", ty.with_article()))
        .help(help),
    )
}
