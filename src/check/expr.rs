//! Typing of expressions.

use std::collections::HashSet;

use super::checker::{Checker, Ctx, Local};
use super::scope::Target;
use super::types::{self, Ty};
use crate::diag::{suggest, Diagnostic};
use crate::source::Span;
use crate::syntax::ast::{
    BinaryExpr, BinaryOp, ConstructKind, DeclKind, Expr, ExprKind, FieldInit, Ident, LocalExpr,
    QualifiedName,
};

impl<'w> Checker<'w> {
    pub(super) fn expr(&mut self, expr: &'w Expr, ctx: &mut Ctx) -> Ty {
        match &expr.kind {
            ExprKind::Name(name) => self.name(
                &Ident {
                    name: *name,
                    span: expr.span,
                },
                ctx,
            ),
            ExprKind::Qualified(qualified) => self.qualified(qualified, expr.span, ctx),
            ExprKind::Field(access) => {
                let ty = self.expr(&access.target, ctx);
                self.field(ty, &access.field)
            }
            ExprKind::Unknown(name) => unknown_type(name),
            ExprKind::Int(0) => Ty::Zero,
            ExprKind::Int(1) => Ty::One,
            ExprKind::Int(_) | ExprKind::Float(_) => Ty::Scalar,
            ExprKind::Vector(items) => self.vector(items, expr.span, ctx),
            ExprKind::Call(call) => self.call(&call.callee, &call.args, expr.span, ctx),
            ExprKind::Binary(binary) => {
                let BinaryExpr { op, lhs, rhs } = &**binary;
                if let Some(ty) = self.precedence_trap(expr, *op, lhs, rhs, ctx) {
                    return ty;
                }
                let left = self.expr(lhs, ctx);
                let right = self.expr(rhs, ctx);
                self.binary(*op, lhs, left, rhs, right, expr.span)
            }
            ExprKind::Neg(inner) => match self.expr(inner, ctx).numeric() {
                ty @ (Ty::Scalar | Ty::Vector | Ty::Matrix | Ty::Error) => ty,
                other => {
                    self.report(
                        Diagnostic::error(
                            "E0402",
                            format!("cannot negate {}", other.with_article()),
                        )
                        .primary(inner.span, format!("this is {}", other.with_article())),
                    );
                    Ty::Error
                }
            },
            ExprKind::Prime(inner) => self.prime(inner, ctx),
            ExprKind::Construct(c) => self.construct(c.kind, &c.params, &c.fields, ctx),
            ExprKind::Local(local) => {
                let LocalExpr { bindings, body } = &**local;
                let types: Vec<Ty> = bindings.iter().map(|b| self.expr(&b.value, ctx)).collect();
                for (binding, ty) in bindings.iter().zip(&types) {
                    self.expect_first_class(&binding.value, *ty);
                }
                let depth = ctx.locals.len();
                for (binding, ty) in bindings.iter().zip(types) {
                    ctx.locals.push(Local {
                        name: binding.name.name,
                        ty,
                        coordinate: false,
                    });
                }
                let ty = self.expr(body, ctx);
                ctx.locals.truncate(depth);
                ty
            }
            ExprKind::Error => Ty::Error,
        }
    }

    pub(super) fn name(&mut self, ident: &Ident, ctx: &Ctx) -> Ty {
        if let Some(local) = ctx.locals.iter().rev().find(|l| l.name == ident.name) {
            self.out.resolutions.insert(ident.span, Target::Local);
            return local.ty;
        }
        if let Some((target, ty)) = self.lookup_global(&ident.name, ctx.scope, ctx.limit) {
            self.out.resolutions.insert(ident.span, target);
            if let Target::Global(found) = target {
                if super::shadowed::found_in_opened_module(self, found, ctx) {
                    self.warn_if_shadowed(ident, found, ctx);
                }
            }
            return ty;
        }
        if let Some(ty) = types::builtin_constant(&ident.name) {
            self.out.resolutions.insert(ident.span, Target::Builtin);
            return ty;
        }
        if types::is_builtin_function(&ident.name) {
            self.report(
                Diagnostic::error(
                    "E0417",
                    format!("`{}` is a built-in function, not a value", ident.name),
                )
                .primary(ident.span, "not called")
                .help(format!("call it: `{}(x)`", ident.name)),
            );
            return Ty::Error;
        }
        let diagnostic = self.unknown_name(ident, ctx);
        self.report(diagnostic);
        Ty::Error
    }

    /// Looks a name up in a scope (its first `limit` names), its opened modules, then its parents.
    pub(super) fn lookup_global(
        &self,
        name: &str,
        scope: types::ScopeId,
        limit: u32,
    ) -> Option<(Target, Ty)> {
        let mut current = Some((scope, limit));
        while let Some((id, limit)) = current {
            let s = self.out.scope(id);
            if let Some(entry) = s.get(name, limit) {
                return Some((Target::Global(id), entry.ty));
            }
            for &(opened, opened_at) in s.opened.iter().rev() {
                if opened_at <= limit {
                    if let Some(entry) = self.out.scope(opened).names.get(name) {
                        return Some((Target::Global(opened), entry.ty));
                    }
                }
            }
            current = s.parent;
        }
        None
    }

    fn unknown_name(&mut self, ident: &Ident, ctx: &Ctx) -> Diagnostic {
        let name = &ident.name;
        let diagnostic = Diagnostic::error("E0301", format!("unknown name `{name}`"))
            .primary(ident.span, "not defined here");
        // Declared later in the same scope?
        let mut current = Some(ctx.scope);
        while let Some(id) = current {
            self.note_declared_later(id);
            let scope = self.out.scope(id);
            let later = scope.declared_later.as_ref();
            if let Some(&(later, extent)) = later.and_then(|later| later.get(name.as_ref())) {
                let inside = extent.file() == ident.span.file()
                    && extent.start() <= ident.span.start()
                    && ident.span.end() <= extent.end();
                if inside && self.declares_join(extent) {
                    return diagnostic
                        .secondary(later, "the join being declared")
                        .help(format!("a join's frames cannot depend on the join; only its link (after `with`) may read its coordinates, as in `{name}.q'`"));
                }
                if inside {
                    return diagnostic
                        .secondary(later, "the name being defined")
                        .help("a definition cannot refer to itself; LSD has no recursion");
                }
                if later.file() == ident.span.file() && later.start() < ident.span.start() {
                    return diagnostic
                        .secondary(later, "defined in the same `let ... and ...`")
                        .help("bindings joined by `and` are simultaneous and do not see each other: use two `let` declarations");
                }
                let help = if self.declares_join(extent) && self.in_join(id, ident.span) {
                    // Written in `name`'s own link, the effort would act on `name`, not on the
                    // join that reads it.
                    format!("a link reads only the coordinates of joins declared before it: declare the join `{name}` first (swap the two joins), or apply the effort after both joins, on the two bodies this join connects, as in `apply force value = [2 - 0.1 * {name}.q', 0, 0], body = earth end between base and moved;` (on `moved`, its opposite on `base`)")
                } else if self.declares_join(extent) {
                    format!("a join's coordinates are read after the join, or inside its own link: write the expression in the link, as in `with motor(axis, 2 - 0.1 * {name}.q') as {name}`")
                } else {
                    "a name is visible only after its declaration: move the declaration up"
                        .to_string()
                };
                return diagnostic
                    .secondary(later, "defined here, after its use")
                    .help(help);
            }
            if let Some(entry) = scope.names.get(name.as_ref()) {
                return diagnostic
                    .secondary(entry.span, "defined here, after this definition")
                    .help("a definition sees only the names declared before it");
            }
            current = scope.parent.map(|(p, _)| p);
        }
        let left = self.suggestions_left.get();
        if left == 0 {
            return diagnostic;
        }
        self.suggestions_left.set(left - 1);
        let visible = self.visible_names(ctx);
        if let Some(number) = suggest::thesis_body_number(name) {
            let bodies: Vec<&(String, Ty)> =
                visible.iter().filter(|(_, ty)| *ty == Ty::Body).collect();
            if let Some((body, _)) = bodies.iter().filter(|(n, _)| n != "earth").nth(number - 1) {
                return diagnostic.help(format!(
                    "did you mean `{body}`? bodies are referred to by the names they are declared with (`S{number}` is the thesis's notation for body {number})"
                )).fix(ident.span, body.as_str());
            }
        }
        if let Some(hinted) =
            super::stdlib_hint::import_hint(&diagnostic, name, ident.span, self.workspace)
        {
            return hinted;
        }
        let candidate = suggest::did_you_mean(name, visible.iter().map(|(n, _)| n.as_str()));
        diagnostic.did_you_mean(ident.span, candidate)
    }

    /// Whether a declaration's extent is a `join` (whose name comes last: `join ... as crank`).
    /// Whether `span` lies inside a `join` declaration of `scope`.
    fn in_join(&self, scope: types::ScopeId, span: Span) -> bool {
        self.scope_decls(scope).iter().any(|decl| {
            matches!(decl.kind, DeclKind::Join(_))
                && decl.span.file() == span.file()
                && decl.span.start() <= span.start()
                && span.end() <= decl.span.end()
        })
    }

    fn declares_join(&self, extent: Span) -> bool {
        self.source(extent).starts_with("join")
    }

    /// The source text of a span.
    pub(super) fn source(&self, span: Span) -> &str {
        let text = &self.workspace.sources.file(span.file()).text;
        text.get(span.range()).unwrap_or_default()
    }

    /// `t ++ q || axis`, which reads `(t ++ q) || axis` since `||` binds most loosely: one error
    /// (E0421) that suggests `t ++ (q || axis)`, and the type the suggestion has, so that the
    /// declaration raises no other error. `None` when the expression is not this trap.
    fn precedence_trap(
        &mut self,
        expr: &'w Expr,
        op: BinaryOp,
        lhs: &'w Expr,
        rhs: &'w Expr,
        ctx: &mut Ctx,
    ) -> Option<Ty> {
        let ExprKind::Binary(inner) = &lhs.kind else {
            return None;
        };
        let BinaryExpr {
            op: BinaryOp::Displacement,
            lhs: translation,
            rhs: angle,
        } = &**inner
        else {
            return None;
        };
        // A parenthesised `(t ++ q)` starts after the parenthesis: written on purpose.
        if op != BinaryOp::Rotation || lhs.span.start() != expr.span.start() {
            return None;
        }
        for part in [translation, angle, rhs] {
            self.expr(part, ctx);
        }
        // `axis @ b` on the right, unparenthesised: the frame applies to the whole displacement.
        let (axis, body, ty) = match &rhs.kind {
            ExprKind::Binary(frame)
                if frame.op == BinaryOp::Frame && rhs.span.end() == expr.span.end() =>
            {
                (frame.lhs.span, Some(frame.rhs.span), Ty::Frame)
            }
            _ => (rhs.span, None, Ty::Displacement),
        };
        let mut intended = format!(
            "{} ++ ({} || {})",
            self.source(translation.span),
            self.source(angle.span),
            self.source(axis)
        );
        if let Some(body) = body {
            intended = format!("{intended} @ {}", self.source(body));
        }
        self.report(
            Diagnostic::error("E0421", "`||` binds more loosely than `++`")
                .primary(
                    expr.span,
                    format!("this reads `({}) || ...`", self.source(lhs.span)),
                )
                .help(format!(
                    "a displacement with a rotation is `t ++ (q || axis)`: write `{intended}`"
                ))
                .fix(expr.span, intended),
        );
        Some(ty)
    }

    /// Every name visible from a context, in declaration order (for suggestions).
    fn visible_names(&self, ctx: &Ctx) -> Vec<(String, Ty)> {
        let mut names: Vec<(String, Ty)> = Vec::new();
        let mut seen = HashSet::new();
        let mut push = |name: &str, ty: Ty, names: &mut Vec<(String, Ty)>| {
            if seen.insert(name.to_string()) {
                names.push((name.to_string(), ty));
            }
        };
        for local in ctx.locals.iter().rev() {
            push(&local.name, local.ty, &mut names);
        }
        let mut current = Some((ctx.scope, ctx.limit));
        while let Some((id, limit)) = current {
            let scope = self.out.scope(id);
            for name in scope.order.iter().take(limit as usize) {
                if let Some(entry) = scope.names.get(name) {
                    push(name, entry.ty, &mut names);
                }
            }
            for &(opened, _) in &scope.opened {
                let module = self.out.scope(opened);
                for name in &module.order {
                    push(name, module.names[name].ty, &mut names);
                }
            }
            current = scope.parent;
        }
        for name in crate::syntax::names::BUILTIN_NAMES {
            let ty = types::builtin_constant(name).unwrap_or(Ty::Scalar);
            push(name, ty, &mut names);
        }
        names
    }

    fn qualified(&mut self, qualified: &'w QualifiedName, span: Span, ctx: &mut Ctx) -> Ty {
        match self.package_member(qualified, ctx) {
            Some((scope, ty)) => {
                self.out.resolutions.insert(span, Target::Global(scope));
                ty
            }
            None => Ty::Error,
        }
    }

    /// Resolves `P:X` (or `P[k]:X`) to the package's scope and X's type, reporting what is
    /// wrong.
    pub(super) fn package_member(
        &mut self,
        qualified: &'w QualifiedName,
        ctx: &mut Ctx,
    ) -> Option<(types::ScopeId, Ty)> {
        let QualifiedName {
            package,
            index,
            name,
        } = qualified;
        let scope = match self.name(package, ctx) {
            Ty::Package(scope) => scope,
            Ty::Error => return None,
            other => {
                self.report(
                    Diagnostic::error(
                        "E0404",
                        format!(
                            "`{}` is {}, not a package",
                            package.name,
                            other.with_article()
                        ),
                    )
                    .primary(package.span, "`:` selects a name in a package"),
                );
                return None;
            }
        };
        if !self.instance_index(package, scope, index.as_ref(), ctx) {
            return None;
        }
        let members = self.out.scope(scope);
        if let Some(entry) = members.names.get(&name.name) {
            return Some((scope, entry.ty));
        }
        let candidate = suggest::did_you_mean(&name.name, members.order.iter().map(|n| n.as_ref()));
        let help = candidate.as_ref().map(|s| match index {
            Some(_) => format!("did you mean `{}[…]:{s}`?", package.name),
            None => format!("did you mean `{}:{s}`?", package.name),
        });
        let mut diagnostic = Diagnostic::error(
            "E0301",
            format!("package `{}` has no `{}`", package.name, name.name),
        )
        .primary(name.span, "not defined in the package")
        .with_help(help);
        if let Some(candidate) = candidate {
            diagnostic = diagnostic.fix(name.span, candidate);
        }
        self.report(diagnostic);
        None
    }

    /// Checks that an array of packages is named with an index (a scalar) and a plain package
    /// without one.
    fn instance_index(
        &mut self,
        package: &Ident,
        scope: types::ScopeId,
        index: Option<&'w Expr>,
        ctx: &mut Ctx,
    ) -> bool {
        let array = self.out.scope(scope).index.is_some();
        match (array, index) {
            (true, Some(index)) => {
                let ty = self.expr(index, ctx);
                self.expect_value(index, ty, Ty::Scalar, "the index of an instance");
                true
            }
            (false, None) => true,
            (true, None) => {
                self.report(
                    Diagnostic::error(
                        "E0430",
                        format!("`{}` is an array of packages", package.name),
                    )
                    .primary(package.span, "which instance?")
                    .help(format!(
                        "name one instance by its index: `{}[k]:name`",
                        package.name
                    )),
                );
                false
            }
            (false, Some(index)) => {
                self.report(
                    Diagnostic::error(
                        "E0430",
                        format!("`{}` is a package, not an array of packages", package.name),
                    )
                    .primary(index.span, "an index of a package that has one instance")
                    .help(format!("write `{}:name`", package.name)),
                );
                false
            }
        }
    }

    fn field(&mut self, target: Ty, field: &Ident) -> Ty {
        if target == Ty::Error {
            return Ty::Error;
        }
        if let Some(ty) = types::field_type(target, &field.name) {
            return ty;
        }
        let names = types::field_names(target);
        let mut diagnostic = Diagnostic::error(
            "E0405",
            format!("{} has no field `{}`", target.with_article(), field.name),
        )
        .primary(field.span, "unknown field");
        let candidate = suggest::did_you_mean(&field.name, names.iter().map(String::as_str));
        diagnostic = match candidate {
            Some(_) => diagnostic.did_you_mean(field.span, candidate),
            None if names.is_empty() => {
                diagnostic.note(format!("{} has no fields", target.with_article()))
            }
            None => diagnostic.help(format!(
                "the fields of {} are: {}",
                target.with_article(),
                names.join(", ")
            )),
        };
        self.report(diagnostic);
        Ty::Error
    }

    fn vector(&mut self, items: &'w [Expr], span: Span, ctx: &mut Ctx) -> Ty {
        let types: Vec<Ty> = items.iter().map(|e| self.expr(e, ctx)).collect();
        if items.len() != 3 {
            self.report(
                Diagnostic::error(
                    "E0406",
                    format!("a vector has 3 components, this one has {}", items.len()),
                )
                .primary(span, "expected `[x, y, z]`"),
            );
            return Ty::Error;
        }
        if types.iter().all(|t| t.fits(Ty::Scalar)) {
            return Ty::Vector;
        }
        if types.iter().all(|t| t.fits(Ty::Vector)) {
            return Ty::Matrix;
        }
        for (item, ty) in items.iter().zip(types) {
            if !ty.fits(Ty::Scalar) {
                self.report(
                    Diagnostic::error(
                        "E0401",
                        format!(
                            "a vector's components must be scalars, found {}",
                            ty.with_article()
                        ),
                    )
                    .primary(item.span, format!("this is {}", ty.with_article())),
                );
                break;
            }
        }
        Ty::Error
    }

    fn prime(&mut self, inner: &'w Expr, ctx: &mut Ctx) -> Ty {
        let is_coordinate = match &inner.kind {
            ExprKind::Name(name) => ctx
                .locals
                .iter()
                .rev()
                .find(|l| l.name == *name)
                .is_some_and(|l| l.coordinate),
            ExprKind::Prime(_) => true,
            ExprKind::Field(access) => self.expr_type_silently(&access.target, ctx) == Ty::Join,
            _ => false,
        };
        let ty = self.expr(inner, ctx);
        if !is_coordinate && ty != Ty::Error {
            self.report(
                Diagnostic::error("E0408", "`'` (time derivative) applies only to joint coordinates")
                    .primary(inner.span, "not a coordinate of the enclosing `link(...)`")
                    .help("prime a coordinate of the enclosing `link(x) ... end`, or of a named join: `crank.q'`"),
            );
            return Ty::Error;
        }
        Ty::Scalar
    }

    fn construct(
        &mut self,
        kind: ConstructKind,
        params: &'w [Ident],
        fields: &'w [FieldInit],
        ctx: &mut Ctx,
    ) -> Ty {
        let depth = ctx.locals.len();
        for (i, param) in params.iter().enumerate() {
            if let Some(first) = params[..i].iter().find(|p| p.name == param.name) {
                self.report(
                    Diagnostic::error(
                        "E0303",
                        format!("coordinate `{}` is declared twice", param.name),
                    )
                    .primary(param.span, "second declaration")
                    .secondary(first.span, "first declaration"),
                );
            }
            ctx.locals.push(Local {
                name: param.name,
                ty: Ty::Scalar,
                coordinate: true,
            });
        }
        for (i, field) in fields.iter().enumerate() {
            let ty = self.expr(&field.value, ctx);
            if let Some(first) = fields[..i].iter().find(|f| f.name.name == field.name.name) {
                self.report(
                    Diagnostic::error(
                        "E0303",
                        format!("field `{}` is given twice", field.name.name),
                    )
                    .primary(field.name.span, "second value")
                    .secondary(first.name.span, "first value"),
                );
                continue;
            }
            match types::constructor_field_type(kind, &field.name.name) {
                // The field's role is spelled out only for a message (a body has a few fields).
                Some(expected) if !ty.fits(expected) => {
                    self.expect_value(
                        &field.value,
                        ty,
                        expected,
                        &format!("field `{}`", field.name.name),
                    );
                }
                Some(_) => {}
                None => self.report(unknown_constructor_field(kind, &field.name)),
            }
        }
        ctx.locals.truncate(depth);
        if kind == ConstructKind::Link {
            self.check_dof_fields(fields);
            self.check_coordinates_used(params, fields);
        }
        match kind {
            ConstructKind::Body => Ty::Body,
            ConstructKind::Link => Ty::Link,
            ConstructKind::Force => Ty::Force,
            ConstructKind::Torque => Ty::Torque,
        }
    }

    /// A coordinate that no dof mentions is a mistake: the link would have a useless parameter.
    fn check_coordinates_used(&mut self, params: &[Ident], fields: &[FieldInit]) {
        for param in params {
            if !dof_mentions(fields, &param.name) {
                self.report(
                    Diagnostic::warning(
                        "W0401",
                        format!(
                            "coordinate `{}` does not appear in the link's dof",
                            param.name
                        ),
                    )
                    .primary(param.span, "unused coordinate")
                    .help("use it in `dof = ...`, or remove it from the parameter list"),
                );
            }
        }
    }

    /// The plain form (`dof`, `force`, `torque`) or the numbered one (`dof1`, `force1`, …), not
    /// both; `dof1`, `dof2`, … numbered from 1 without gaps; `forceN`/`torqueN` only with `dofN`.
    fn check_dof_fields(&mut self, fields: &[FieldInit]) {
        let number = |f: &FieldInit| -> Option<u32> {
            let digits = f.name.name.trim_start_matches(|c: char| c.is_alphabetic());
            digits.parse().ok()
        };
        // Fields that are not link fields were reported already.
        let fields: Vec<&FieldInit> = fields
            .iter()
            .filter(|f| {
                ["dof", "force", "torque"]
                    .iter()
                    .any(|base| types::is_numbered(&f.name.name, base))
            })
            .collect();
        let fields = fields.as_slice();
        let plain = fields.iter().find(|f| number(f).is_none());
        let numbered = fields.iter().find(|f| number(f).is_some());
        if let (Some(plain), Some(numbered)) = (plain, numbered) {
            self.report(
                Diagnostic::error("E0415", "a link uses either `dof`, `force`, `torque` or `dof1`, `force1`, `torque1`, …, not both")
                    .primary(numbered.name.span, "numbered field here")
                    .secondary(plain.name.span, "plain field here"),
            );
            return;
        }
        let mut dofs: Vec<(u32, &FieldInit)> = fields
            .iter()
            .filter(|f| f.name.name.starts_with("dof"))
            .filter_map(|f| number(f).map(|n| (n, *f)))
            .collect();
        dofs.sort_by_key(|(n, _)| *n);
        for (expected, (n, field)) in (1..).zip(&dofs) {
            if *n != expected {
                self.report(
                    Diagnostic::error("E0415", format!("`dof{n}` without `dof{expected}`"))
                        .primary(
                            field.name.span,
                            format!("expected `dof{expected}` before this"),
                        )
                        .help("number the displacements of a link's dof chain from 1, in order"),
                );
                return;
            }
        }
        for field in fields.iter().filter(|f| !f.name.name.starts_with("dof")) {
            if let Some(n) = number(field).filter(|&n| n as usize > dofs.len()) {
                self.report(
                    Diagnostic::error("E0415", format!("`{}` goes with `dof{n}`, which this link does not have", field.name.name))
                        .primary(field.name.span, "no matching dof")
                        .help("`forceN` and `torqueN` are the known efforts along the N-th step of the dof chain"),
                );
            }
        }
    }

    fn binary(
        &mut self,
        op: BinaryOp,
        lhs: &Expr,
        left: Ty,
        rhs: &Expr,
        right: Ty,
        span: Span,
    ) -> Ty {
        use Ty::*;
        if left == Error || right == Error {
            return match op {
                BinaryOp::Rotation => Rotation,
                BinaryOp::Displacement => Displacement,
                BinaryOp::Frame => Frame,
                _ => Error,
            };
        }
        match op {
            BinaryOp::Rotation => {
                let angle_ok =
                    self.expect_value(lhs, left, Scalar, "the angle of a rotation `angle || axis`");
                let axis_ok =
                    self.expect_value(rhs, right, Vector, "the axis of a rotation `angle || axis`");
                if angle_ok && axis_ok {
                    Rotation
                } else {
                    Error
                }
            }
            BinaryOp::Displacement => {
                let t = self.expect_value(
                    lhs,
                    left,
                    Vector,
                    "the translation of `translation ++ rotation`",
                );
                let r = self.expect_value(
                    rhs,
                    right,
                    Rotation,
                    "the rotation of `translation ++ rotation`",
                );
                if t && r {
                    Displacement
                } else {
                    Error
                }
            }
            BinaryOp::Frame => {
                let d = self.expect_value(
                    lhs,
                    left,
                    Displacement,
                    "the displacement of `displacement @ body`",
                );
                let b = right.fits(Frame)
                    || self.expect_value(rhs, right, Body, "the body of `displacement @ body`");
                if d && b {
                    Frame
                } else {
                    Error
                }
            }
            _ => match arithmetic(op, left, right) {
                Some(ty) => ty,
                None => {
                    let mut diagnostic = Diagnostic::error(
                        "E0402",
                        format!(
                            "cannot apply `{}` to {} and {}",
                            op.symbol(),
                            left.with_article(),
                            right.with_article()
                        ),
                    )
                    .primary(span, "invalid operands")
                    .secondary(lhs.span, left.with_article().to_string())
                    .secondary(rhs.span, right.with_article().to_string());
                    if op == BinaryOp::Mul && left.numeric() == Vector && right.numeric() == Vector
                    {
                        diagnostic = diagnostic.help("use `dot(a, b)` or `cross(a, b)`");
                    }
                    self.report(diagnostic);
                    Error
                }
            },
        }
    }
}

/// Result type of `+ - * / ^` on numeric operands.
fn arithmetic(op: BinaryOp, left: Ty, right: Ty) -> Option<Ty> {
    use Ty::*;
    // `0 + v` is `v`: the literal zero takes the other operand's type.
    let (left, right) = match (left, right) {
        (Zero, other @ (Vector | Matrix)) | (other @ (Vector | Matrix), Zero)
            if matches!(op, BinaryOp::Add | BinaryOp::Sub) =>
        {
            (other, other)
        }
        (l, r) => (l.numeric(), r.numeric()),
    };
    Some(match (op, left, right) {
        (BinaryOp::Add | BinaryOp::Sub, a, b)
            if a == b && matches!(a, Scalar | Vector | Matrix) =>
        {
            a
        }
        (BinaryOp::Mul, Scalar, b @ (Scalar | Vector | Matrix)) => b,
        (BinaryOp::Mul, a @ (Vector | Matrix), Scalar) => a,
        (BinaryOp::Mul, Matrix, Vector) | (BinaryOp::Mul, Rotation, Vector) => Vector,
        (BinaryOp::Mul, Matrix, Matrix) => Matrix,
        (BinaryOp::Mul, Rotation, Rotation) => Rotation,
        (BinaryOp::Mul, Displacement | Vector | Rotation, Displacement)
        | (BinaryOp::Mul, Displacement, Vector | Rotation) => Displacement,
        (BinaryOp::Div, a @ (Scalar | Vector | Matrix), Scalar) => a,
        (BinaryOp::Pow, Scalar, Scalar) => Scalar,
        _ => return None,
    })
}

/// `?v` and `?vector` are unknown vectors; every other `?name` is an unknown scalar (the name is
/// a reminder for the reader, as `?s` is in the thesis).
fn unknown_type(name: &str) -> Ty {
    match name {
        "v" | "vector" => Ty::Vector,
        _ => Ty::Scalar,
    }
}

fn unknown_constructor_field(kind: ConstructKind, field: &Ident) -> Diagnostic {
    let names = types::constructor_field_names(kind);
    let keyword = kind.keyword();
    let mut diagnostic = Diagnostic::error(
        "E0405",
        format!("`{keyword}` has no field `{}`", field.name),
    )
    .primary(field.span, "unknown field");
    if kind == ConstructKind::Body && &*field.name == "frame" {
        return diagnostic.note("a body's reference frame is the body itself; other frames are `<displacement> @ <body>`");
    }
    let candidate = suggest::did_you_mean(&field.name, names.iter().map(String::as_str));
    diagnostic = match candidate {
        Some(_) => diagnostic.did_you_mean(field.span, candidate),
        None => diagnostic.help(format!(
            "the fields of `{keyword}` are: {}",
            names.join(", ")
        )),
    };
    diagnostic
}

/// Whether a link's `dof` fields (`dof`, `dof1`, …) mention a name, as written.
pub fn dof_mentions(fields: &[FieldInit], name: &str) -> bool {
    fields
        .iter()
        .filter(|f| types::is_numbered(&f.name.name, "dof"))
        .any(|f| mentions(&f.value, name))
}

/// Whether an expression mentions a name (a conservative syntactic test).
fn mentions(expr: &Expr, name: &str) -> bool {
    match &expr.kind {
        ExprKind::Name(written) => &**written == name,
        ExprKind::Field(access) => mentions(&access.target, name),
        ExprKind::Neg(target) | ExprKind::Prime(target) => mentions(target, name),
        ExprKind::Binary(binary) => mentions(&binary.lhs, name) || mentions(&binary.rhs, name),
        ExprKind::Vector(items) => items.iter().any(|e| mentions(e, name)),
        ExprKind::Call(call) => call.args.iter().any(|a| mentions(&a.value, name)),
        ExprKind::Local(local) => {
            local.bindings.iter().any(|b| mentions(&b.value, name)) || mentions(&local.body, name)
        }
        ExprKind::Construct(c) => c.fields.iter().any(|f| mentions(&f.value, name)),
        ExprKind::Qualified(qualified) => {
            qualified.index.as_ref().is_some_and(|e| mentions(e, name))
        }
        ExprKind::Unknown(_) | ExprKind::Int(_) | ExprKind::Float(_) | ExprKind::Error => false,
    }
}
