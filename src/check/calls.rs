//! Typing of calls: built-in functions, unknown functions `?f(x, x')`, and parameterised
//! definitions, whose bodies are checked at each use with the arguments' types (memoised), with
//! positional and named arguments.

use super::checker::{Checker, Ctx, Local, MAX_INSTANTIATION_DEPTH};
use super::scope::Target;
use super::types::{self, DefId, Ty};
use crate::diag::{suggest, Diagnostic};
use crate::source::Span;
use crate::syntax::ast::{Arg, Callee, Ident};

impl<'w> Checker<'w> {
    pub(super) fn call(
        &mut self,
        callee: &'w Callee,
        args: &'w [Arg],
        span: Span,
        ctx: &mut Ctx,
    ) -> Ty {
        let arg_types: Vec<Ty> = args.iter().map(|a| self.expr(&a.value, ctx)).collect();
        match callee {
            Callee::Unknown(ident) => {
                self.positional_only(args);
                for (arg, ty) in args.iter().zip(&arg_types) {
                    if !ty.fits(Ty::Scalar) {
                        self.expect_value(
                            &arg.value,
                            *ty,
                            Ty::Scalar,
                            "an argument of an unknown function",
                        );
                    }
                }
                let _ = ident;
                Ty::Scalar
            }
            Callee::Name(ident) => {
                let is_local = ctx.locals.iter().any(|l| l.name == ident.name);
                if !is_local
                    && self
                        .lookup_global(&ident.name, ctx.scope, ctx.limit)
                        .is_none()
                {
                    if let Some(arguments) = types::reference_law(&ident.name) {
                        self.out.resolutions.insert(ident.span, Target::Builtin);
                        self.positional_only(args);
                        return self.law_call(ident, arguments, args, &arg_types, span);
                    }
                    if ident.name == "inverse_dynamics" {
                        self.out.resolutions.insert(ident.span, Target::Builtin);
                        self.positional_only(args);
                        return self.inverse_dynamics_call(ident, args, &arg_types, span);
                    }
                    if ident.name == "derivative" {
                        self.out.resolutions.insert(ident.span, Target::Builtin);
                        self.positional_only(args);
                        return self.derivative_call(ident, args, &arg_types, span);
                    }
                    if let Some((params, result)) = types::builtin_function(&ident.name) {
                        self.out.resolutions.insert(ident.span, Target::Builtin);
                        return self.builtin_call(ident, params, result, args, &arg_types, span);
                    }
                }
                let ty = self.name(ident, ctx);
                self.call_value(ident, ty, args, arg_types, span)
            }
            Callee::Qualified(qualified) => match self.package_member(qualified, ctx) {
                Some((scope, ty)) => {
                    let name = &qualified.name;
                    self.out
                        .resolutions
                        .insert(name.span, Target::Global(scope));
                    self.call_value(name, ty, args, arg_types, span)
                }
                None => Ty::Error,
            },
        }
    }

    fn positional_only(&mut self, args: &[Arg]) {
        if let Some(named) = args.iter().find_map(|a| a.name.as_ref()) {
            self.report(
                Diagnostic::error("E0413", "this function takes positional arguments only")
                    .primary(named.span, "named argument"),
            );
        }
    }

    fn builtin_call(
        &mut self,
        ident: &Ident,
        params: &[Ty],
        result: Ty,
        args: &'w [Arg],
        arg_types: &[Ty],
        span: Span,
    ) -> Ty {
        self.positional_only(args);
        let required = params.len() - types::builtin_optional_parameters(&ident.name);
        if !(required..=params.len()).contains(&args.len()) {
            let expected = args.len().clamp(required, params.len());
            self.report(arity_error(&ident.name, expected, args.len(), span, None));
            return Ty::Error;
        }
        for ((arg, ty), param) in args.iter().zip(arg_types).zip(params) {
            self.expect_value(
                &arg.value,
                *ty,
                *param,
                &format!("an argument of `{}`", ident.name),
            );
        }
        result
    }

    fn call_value(
        &mut self,
        ident: &Ident,
        ty: Ty,
        args: &'w [Arg],
        arg_types: Vec<Ty>,
        span: Span,
    ) -> Ty {
        let def = match ty {
            Ty::Definition(def) => def,
            Ty::Error => return Ty::Error,
            other => {
                self.report(
                    Diagnostic::error(
                        "E0412",
                        format!(
                            "`{}` is {}, not a parameterised definition",
                            ident.name,
                            other.with_article()
                        ),
                    )
                    .primary(ident.span, "cannot be called"),
                );
                return Ty::Error;
            }
        };
        match self.bind_arguments(def, args, arg_types, span) {
            Some(types) => self.instantiate(def, types, span),
            None => Ty::Error,
        }
    }

    /// Matches positional and named arguments to the definition's parameters.
    fn bind_arguments(
        &mut self,
        def: DefId,
        args: &'w [Arg],
        arg_types: Vec<Ty>,
        span: Span,
    ) -> Option<Vec<Ty>> {
        let definition = &self.out.definitions[def.0 as usize];
        let params = self.definition_trees[def.0 as usize].0;
        let (name, def_span) = (definition.name, definition.span);
        let mut bound: Vec<Option<Ty>> = vec![None; params.len()];
        let mut ok = true;
        for (position, (arg, ty)) in args.iter().zip(arg_types).enumerate() {
            ok &= self.expect_first_class(&arg.value, ty);
            let index = match &arg.name {
                None if position < params.len() => position,
                None => {
                    self.report(arity_error(
                        &name,
                        params.len(),
                        args.len(),
                        span,
                        Some(def_span),
                    ));
                    return None;
                }
                Some(arg_name) => match params.iter().position(|p| p.name.name == arg_name.name) {
                    Some(index) => index,
                    None => {
                        let candidate = suggest::did_you_mean(
                            &arg_name.name,
                            params.iter().map(|p| p.name.name.as_ref()),
                        );
                        self.report(
                            Diagnostic::error(
                                "E0413",
                                format!("`{name}` has no parameter `{}`", arg_name.name),
                            )
                            .primary(arg_name.span, "unknown parameter")
                            .secondary(def_span, "defined here")
                            .did_you_mean(arg_name.span, candidate),
                        );
                        ok = false;
                        continue;
                    }
                },
            };
            if bound[index].is_some() {
                self.report(
                    Diagnostic::error(
                        "E0413",
                        format!("parameter `{}` is given twice", params[index].name.name),
                    )
                    .primary(arg.value.span, "second value"),
                );
                ok = false;
            }
            if let Some(expected) = params[index]
                .ty
                .as_ref()
                .and_then(|a| Ty::from_annotation(&a.name))
            {
                ok &= self.expect_value(
                    &arg.value,
                    ty,
                    expected,
                    &format!("parameter `{}`", params[index].name.name),
                );
            }
            bound[index] = Some(ty);
        }
        let missing: Vec<String> = params
            .iter()
            .zip(&bound)
            .filter(|(_, b)| b.is_none())
            .map(|(p, _)| format!("`{}`", p.name.name))
            .collect();
        if !missing.is_empty() {
            self.report(
                Diagnostic::error(
                    "E0413",
                    format!("missing argument {} for `{name}`", missing.join(", ")),
                )
                .primary(span, "in this call")
                .secondary(def_span, "defined here"),
            );
            return None;
        }
        ok.then(|| bound.into_iter().map(|b| b.unwrap_or(Ty::Error)).collect())
    }

    /// Checks a definition's body with the arguments' types (memoised per list of types).
    fn instantiate(&mut self, def: DefId, arg_types: Vec<Ty>, use_site: Span) -> Ty {
        if let Some(&ty) = self.memo.get(&(def, arg_types.clone())) {
            return ty;
        }
        let definition = &self.out.definitions[def.0 as usize];
        let (params, body) = self.definition_trees[def.0 as usize];
        let (name, scope, limit) = (definition.name, definition.scope, definition.limit);
        if self.instantiations.len() >= MAX_INSTANTIATION_DEPTH {
            self.report(
                Diagnostic::error(
                    "E0414",
                    format!("definitions nest more than {MAX_INSTANTIATION_DEPTH} deep"),
                )
                .primary(use_site, format!("instantiating `{name}` here")),
            );
            return Ty::Error;
        }
        let locals = params
            .iter()
            .zip(&arg_types)
            .map(|(p, &ty)| Local {
                name: p.name.name,
                ty,
                coordinate: false,
            })
            .collect();
        let mut ctx = Ctx {
            scope,
            limit,
            locals,
        };
        self.instantiations.push((use_site, name));
        let ty = self.expr(body, &mut ctx);
        self.instantiations.pop();
        self.memo.insert((def, arg_types), ty);
        ty
    }
}

pub(super) fn arity_error(
    name: &str,
    expected: usize,
    found: usize,
    span: Span,
    def_span: Option<Span>,
) -> Diagnostic {
    let plural = if expected == 1 { "" } else { "s" };
    let mut diagnostic = Diagnostic::error(
        "E0413",
        format!("`{name}` takes {expected} argument{plural}, {found} given"),
    )
    .primary(span, "in this call");
    if let Some(def_span) = def_span {
        diagnostic = diagnostic.secondary(def_span, "defined here");
    }
    diagnostic
}
