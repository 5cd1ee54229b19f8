//! Arrays of packages: `package P[i in a .. b] = decls end` evaluates its declarations once per
//! index, each instance with its own values for the package's names (`instances.rs`); the
//! instance of a scope is the one being evaluated (or one of its enclosing instances), and
//! `P[k]:x` evaluates `x` in instance `k`.

use super::elaborator::{internal, Elaborator, Global};
use super::instances::{Instance, InstanceId, ROOT};
use super::value::{constant, Value};
use crate::check::scope::ScopeId;
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::{Decl, Expr, Ident, Name, PackageIndex};

type Result<T> = std::result::Result<T, Diagnostic>;

/// The most instances one array may have: a bound beyond it is a typing slip, not a mechanism.
const MAX_INSTANCES: i64 = 1_000_000;

impl<'w> Elaborator<'_, 'w> {
    /// The instance that `scope`'s names take their values in, from the one being evaluated:
    /// an array on the way out from it, or for a plain package the instance of its file or
    /// package.
    pub(super) fn instance_of(&self, scope: ScopeId) -> Result<InstanceId> {
        let mut at = self.instances.current;
        while at != ROOT {
            let instance = &self.instances.table[at as usize];
            if instance.scope == scope {
                return Ok(at);
            }
            at = instance.parent;
        }
        let declared = self.checked.scope(scope);
        match declared.parent {
            Some(_) if declared.index.is_some() => Err(internal(
                "a name of an array of packages outside its instances",
            )),
            Some((enclosing, _)) => self.instance_of(enclosing),
            None => Ok(ROOT),
        }
    }

    /// Runs `f` as if evaluating inside `instance`.
    pub(super) fn within<T>(
        &mut self,
        instance: InstanceId,
        f: impl FnOnce(&mut Self) -> Result<T>,
    ) -> Result<T> {
        let outer = std::mem::replace(&mut self.instances.current, instance);
        let result = f(self);
        self.instances.current = outer;
        result
    }

    /// `package P[i in a .. b] = decls end`: the declarations once per index, in order.
    pub(super) fn package_array(
        &mut self,
        name: &Ident,
        index: &PackageIndex,
        decls: &[Decl],
        scope: ScopeId,
    ) -> Result<()> {
        let first = self.bound(&index.first)?;
        let last = self.bound(&index.last)?;
        if last - first + 1 > MAX_INSTANCES {
            return Err(Diagnostic::error(
                "E0630",
                format!("`{}` would have {} instances", name.name, last - first + 1),
            )
            .primary(index.first.span.to(index.last.span), "this range")
            .note(format!(
                "an array of packages has at most {MAX_INSTANCES} instances"
            )));
        }
        let enclosing = self.instance_of(self.enclosing(scope)?)?;
        self.instances
            .ranges
            .insert((scope, enclosing), (first, last));
        for k in first..=last {
            let instance = self.instance(scope, k, name.span)?;
            (self.enclosing_groups).push(format!("{}[{k}]", name.name));
            let elaborated = self.within(instance, |elaborator| elaborator.decls(decls, scope));
            self.enclosing_groups.pop();
            elaborated.map_err(|error| {
                error.secondary(
                    name.span,
                    format!(
                        "in the instance `{}[{k}]` ({} = {k})",
                        name.name, index.variable.name
                    ),
                )
            })?;
        }
        Ok(())
    }

    /// The instance of the array `scope` that `P[index]` names.
    pub(super) fn instance_at(
        &mut self,
        scope: ScopeId,
        index: &Expr,
        locals: &mut super::eval::Locals,
    ) -> Result<InstanceId> {
        let value = self.expr(index, locals)?;
        let k = integer(&value).ok_or_else(|| {
            Diagnostic::error("E0630", "the index of an instance is not a whole number")
                .primary(index.span, format!("this is {}", describe(&value)))
                .help("an index is a whole number known when the program is read: `P[3]:x`, `P[i - 1]:x`")
        })?;
        self.instance(scope, k, index.span)
    }

    /// The instance `k` of the array `scope`, within the current instance of its enclosing
    /// scope; its index variable is bound when it is first made.
    fn instance(&mut self, scope: ScopeId, k: i64, span: Span) -> Result<InstanceId> {
        let parent = self.instance_of(self.enclosing(scope)?)?;
        let (first, last) = *self
            .instances
            .ranges
            .get(&(scope, parent))
            .ok_or_else(|| internal("an instance named before its array is evaluated"))?;
        // An instance made before was in range: only a new one needs the array's name.
        if let Some(&id) = self.instances.ids.get(&(parent, scope, k)) {
            return Ok(id);
        }
        let package = self.package_name(scope)?;
        if !(first..=last).contains(&k) {
            let range = if first > last {
                "it has no instances".to_string()
            } else {
                format!("its instances are `{package}[{first}]` to `{package}[{last}]`")
            };
            return Err(Diagnostic::error(
                "E0630",
                format!("`{package}[{k}]` is not an instance of `{package}`"),
            )
            .primary(span, format!("index {k}"))
            .note(range));
        }
        let variable = self
            .checked
            .scope(scope)
            .index
            .ok_or_else(|| internal("an index of a plain package"))?;
        let id = self.instances.table.len() as InstanceId;
        self.instances.table.push(Instance {
            package,
            scope,
            parent,
            index: k,
        });
        self.instances.ids.insert((parent, scope, k), id);
        let value = Value::Scalar(self.literal(k as f64));
        self.globals
            .insert((scope, id, variable), Global::Ready(value));
        Ok(id)
    }

    fn enclosing(&self, scope: ScopeId) -> Result<ScopeId> {
        self.checked
            .scope(scope)
            .parent
            .map(|(parent, _)| parent)
            .ok_or_else(|| internal("an array of packages outside a file"))
    }

    /// The name an array is declared with, from its enclosing scope's names.
    fn package_name(&self, scope: ScopeId) -> Result<Name> {
        let enclosing = self.checked.scope(self.enclosing(scope)?);
        enclosing
            .order
            .iter()
            .find(|name| {
                matches!(enclosing.names[*name].ty, crate::check::types::Ty::Package(s) if s == scope)
            })
            .cloned()
            .ok_or_else(|| internal("an array of packages without a name"))
    }

    /// A bound of an array's range: a whole number.
    fn bound(&mut self, expr: &Expr) -> Result<i64> {
        let value = self.expr(expr, &mut Vec::new())?;
        integer(&value).ok_or_else(|| {
            Diagnostic::error(
                "E0630",
                "the bounds of an array of packages are whole numbers",
            )
            .primary(expr.span, format!("this is {}", describe(&value)))
            .help("write numbers, or names and arithmetic of numbers: `[i in 1 .. N]`")
        })
    }
}

/// The whole number a value is, if it is one (exactly, and not too large to count).
fn integer(value: &Value) -> Option<i64> {
    let x = match value {
        Value::Zero => 0.0,
        Value::One => 1.0,
        Value::Scalar(s) => constant(s)?,
        _ => return None,
    };
    (x.fract() == 0.0 && x.abs() < 1e15).then_some(x as i64)
}

/// What a value that should have been a whole number is, for messages.
fn describe(value: &Value) -> String {
    let Value::Scalar(s) = value else {
        return "not a number".to_string();
    };
    match (constant(s), &**s) {
        (Some(x), _) => format!("{x}"),
        (None, super::value::SExpr::Unknown(_)) => {
            "an unknown, without a value when the program is read".to_string()
        }
        (None, _) => "a scalar that depends on the motion or on unknowns".to_string(),
    }
}
