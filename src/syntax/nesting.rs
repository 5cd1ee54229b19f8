//! The nesting limit of programs. The parser keeps its own stack and reads any depth, but the
//! passes after it (checker, elaborator, symbolic algebra, printing) walk the tree recursively:
//! a declaration nested deeper than [`MAX_NESTING`] levels (`1+1+…+1`, `[[[…]]]`, `---…1`,
//! `sin(sin(…))`, `x'''…`, `local … in` in `local … in`, packages in packages) is refused here
//! with a located error (E0203), measured and taken apart without recursion.

use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::{BinaryExpr, Decl, DeclKind, Expr, ExprKind, LocalExpr, Program};

/// The deepest nesting of expressions (and packages) a declaration may have, counting the
/// outermost expression as level 1: far beyond what a mechanism needs, far below what the
/// recursive passes can take on a thread's stack.
pub const MAX_NESTING: usize = 200;

/// Replaces every declaration nested deeper than [`MAX_NESTING`] by an error declaration, with
/// an E0203 at the first construct past the limit.
pub fn limit_nesting(program: &mut Program, diagnostics: &mut Vec<Diagnostic>) {
    for decl in &mut program.decls {
        if let Some(span) = too_deep(decl, &mut Vec::new()) {
            diagnostics.push(
                Diagnostic::error(
                    "E0203",
                    format!("this declaration is nested more than {MAX_NESTING} levels deep"),
                )
                .primary(
                    span.head(1),
                    format!("level {} starts here", MAX_NESTING + 1),
                )
                .help("name intermediate values with `let`, or write long sums as several terms bound to names"),
            );
            dismantle(std::mem::replace(&mut decl.kind, DeclKind::Error));
        }
    }
}

/// The span of the first construct of `decl` past the limit, or `None` if it is within it.
/// `children` is scratch room, kept by the caller so that a walk allocates nothing per node.
fn too_deep<'a>(decl: &'a Decl, children: &mut Vec<&'a Expr>) -> Option<Span> {
    let mut decls = vec![(decl, 0)];
    let mut exprs: Vec<(&Expr, usize)> = Vec::new();
    while let Some((decl, depth)) = decls.pop() {
        if depth > MAX_NESTING {
            return Some(decl.span);
        }
        match &decl.kind {
            DeclKind::Package(package) => {
                decls.extend(package.decls.iter().map(|d| (d, depth + 1)))
            }
            DeclKind::Scene(scene) => decls.extend(scene.decls.iter().map(|d| (d, depth + 1))),
            _ => {}
        }
        decl_exprs(&decl.kind, children);
        exprs.extend(children.drain(..).map(|e| (e, depth + 1)));
    }
    while let Some((expr, depth)) = exprs.pop() {
        if depth > MAX_NESTING {
            return Some(expr.span);
        }
        expr_children(expr, children);
        exprs.extend(children.drain(..).map(|e| (e, depth + 1)));
    }
    None
}

/// The expressions written directly in a declaration (not in its nested packages).
fn decl_exprs<'a>(kind: &'a DeclKind, out: &mut Vec<&'a Expr>) {
    match kind {
        DeclKind::Let(bindings) => out.extend(bindings.iter().map(|b| &b.value)),
        DeclKind::Define(define) => out.push(&define.body),
        DeclKind::Join(join) => out.extend([&join.first, &join.second, &join.link]),
        DeclKind::Initial(values) => {
            out.extend(values.iter().flat_map(|v| [&v.target, &v.value]));
        }
        DeclKind::Given(values) => out.extend(values.iter().flat_map(|v| [&v.target, &v.value])),
        DeclKind::Drive(drive) => out.extend([&drive.target, &drive.value]),
        DeclKind::Simulate(fields) => out.extend(fields.iter().map(|f| &f.value)),
        DeclKind::Output(output) => out.push(&output.value),
        DeclKind::Apply(apply) => {
            out.push(&apply.effort);
            out.extend(apply.target.iter().chain(&apply.reaction));
        }
        DeclKind::Package(_)
        | DeclKind::Scene(_)
        | DeclKind::SelectEfforts(_)
        | DeclKind::Import(_)
        | DeclKind::Error => {}
    }
}

fn expr_children<'a>(expr: &'a Expr, out: &mut Vec<&'a Expr>) {
    match &expr.kind {
        ExprKind::Field(access) => out.push(&access.target),
        ExprKind::Vector(items) => out.extend(items.iter()),
        ExprKind::Call(call) => out.extend(call.args.iter().map(|a| &a.value)),
        ExprKind::Binary(binary) => out.extend([&binary.lhs, &binary.rhs]),
        ExprKind::Neg(inner) | ExprKind::Prime(inner) => out.push(inner),
        ExprKind::Construct(c) => out.extend(c.fields.iter().map(|f| &f.value)),
        ExprKind::Local(local) => {
            out.extend(local.bindings.iter().map(|b| &b.value));
            out.push(&local.body);
        }
        ExprKind::Name(_)
        | ExprKind::Qualified(_)
        | ExprKind::Unknown(_)
        | ExprKind::Int(_)
        | ExprKind::Float(_)
        | ExprKind::Error => {}
    }
}

/// Drops a declaration one node at a time: the recursive drop of a deep tree would overflow the
/// stack just as the passes would.
fn dismantle(kind: DeclKind) {
    let mut decls = vec![kind];
    let mut exprs: Vec<Expr> = Vec::new();
    while let Some(kind) = decls.pop() {
        match kind {
            DeclKind::Let(bindings) => {
                exprs.extend(bindings.into_vec().into_iter().map(|b| b.value))
            }
            DeclKind::Define(define) => exprs.push(define.into_inner().body),
            DeclKind::Join(join) => {
                let join = join.into_inner();
                exprs.extend([join.first, join.second, join.link]);
            }
            DeclKind::Initial(values) => {
                exprs.extend(
                    values
                        .into_vec()
                        .into_iter()
                        .flat_map(|v| [v.target, v.value]),
                );
            }
            DeclKind::Given(values) => {
                exprs.extend(
                    values
                        .into_vec()
                        .into_iter()
                        .flat_map(|v| [v.target, v.value]),
                );
            }
            DeclKind::Drive(drive) => {
                let drive = drive.into_inner();
                exprs.extend([drive.target, drive.value]);
            }
            DeclKind::Simulate(fields) => {
                exprs.extend(fields.into_vec().into_iter().map(|f| f.value))
            }
            DeclKind::Output(output) => exprs.push(output.into_inner().value),
            DeclKind::Apply(apply) => {
                let apply = apply.into_inner();
                exprs.push(apply.effort);
                exprs.extend(apply.target.into_iter().chain(apply.reaction));
            }
            DeclKind::Package(package) => {
                decls.extend(package.into_inner().decls.into_iter().map(|d| d.kind));
            }
            DeclKind::Scene(scene) => {
                decls.extend(scene.into_inner().decls.into_iter().map(|d| d.kind));
            }
            DeclKind::SelectEfforts(_) | DeclKind::Import(_) | DeclKind::Error => {}
        }
        while let Some(mut expr) = exprs.pop() {
            match std::mem::replace(&mut expr.kind, ExprKind::Error) {
                ExprKind::Field(access) => exprs.push(access.into_inner().target),
                ExprKind::Vector(items) => exprs.extend(items.into_vec()),
                ExprKind::Call(call) => exprs.extend(
                    call.into_inner()
                        .args
                        .into_vec()
                        .into_iter()
                        .map(|a| a.value),
                ),
                ExprKind::Binary(binary) => {
                    let BinaryExpr { lhs, rhs, .. } = binary.into_inner();
                    exprs.extend([lhs, rhs])
                }
                ExprKind::Neg(inner) | ExprKind::Prime(inner) => exprs.push(inner.into_inner()),
                ExprKind::Construct(c) => {
                    exprs.extend(
                        c.into_inner()
                            .fields
                            .into_vec()
                            .into_iter()
                            .map(|f| f.value),
                    );
                }
                ExprKind::Local(local) => {
                    let LocalExpr { bindings, body } = local.into_inner();
                    exprs.extend(bindings.into_vec().into_iter().map(|b| b.value));
                    exprs.push(body);
                }
                _ => {}
            }
        }
    }
}
