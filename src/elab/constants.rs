//! The values of a program's numeric constants, for an editor's hover: `let L = 0.3 * 2;` is
//! `0.6`. Each binding the checker typed as a scalar, vector or matrix at the top level of a
//! module is evaluated by an elaborator of its own, so the mechanism is not changed and
//! bindings the mechanism never uses are evaluated too.

use rustc_hash::FxHashMap;

use super::elaborator::Elaborator;
use super::value::{constant, Scalar, Value};
use crate::check::types::Ty;
use crate::check::Checked;
use crate::load::Workspace;
use crate::source::Span;
use crate::syntax::ast::DeclKind;

/// The value of each numeric top-level binding, as text, by the span of its name. A binding
/// whose evaluation fails (it reads a joint coordinate, say) has none.
pub fn constant_values(workspace: &Workspace, checked: &Checked) -> FxHashMap<Span, String> {
    let mut elaborator = Elaborator::new(workspace, checked);
    let mut values = FxHashMap::default();
    for (id, module) in workspace.modules.iter().enumerate() {
        let Some(&scope) = checked.module_scopes.get(&crate::load::ModuleId(id as u32)) else {
            continue;
        };
        for decl in &module.program.decls {
            let DeclKind::Let(bindings) = &decl.kind else {
                continue;
            };
            for binding in bindings {
                let name = &binding.name.name;
                let Some(entry) = checked.scope(scope).names.get(name) else {
                    continue;
                };
                if !matches!(entry.ty, Ty::Scalar | Ty::Vector | Ty::Matrix) {
                    continue;
                }
                if let Some(text) = elaborator.global(scope, name).ok().and_then(|v| render(&v)) {
                    values.insert(entry.span, text);
                }
            }
        }
    }
    values
}

/// A number as written for a reader: its shortest exact form, or the expression (`?0` for an
/// unknown) when it is not a number.
fn scalar(s: &Scalar) -> String {
    constant(s).map_or_else(|| s.to_string(), |x| x.to_string())
}

fn render(value: &Value) -> Option<String> {
    let vector =
        |v: &[Scalar; 3]| format!("[{}, {}, {}]", scalar(&v[0]), scalar(&v[1]), scalar(&v[2]));
    Some(match value {
        Value::Scalar(s) => scalar(s),
        Value::Vector(v) => vector(v),
        Value::Matrix(m) => format!("[{}, {}, {}]", vector(&m[0]), vector(&m[1]), vector(&m[2])),
        Value::Zero => "0".to_string(),
        Value::One => "1".to_string(),
        _ => return None,
    })
}
