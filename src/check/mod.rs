//! Name resolution and type checking. Walks every module once, in import order, and records for
//! each name use where it resolves (for the elaborator). Parameterised definitions may have
//! untyped parameters: their bodies are checked at each instantiation with the arguments' types,
//! and an error inside one shows both the definition and the use.

mod calls;
mod checker;
mod expr;
mod inputs;
mod laws;
mod model_laws;
mod output;
pub mod resolutions;
pub mod scope;
mod shadowed;
mod stdlib_hint;
pub mod types;

use std::collections::HashMap;

use rustc_hash::FxHashMap;

use crate::diag::{Diagnostic, Diagnostics};
use crate::load::{ModuleId, Workspace};
use crate::source::Span;
use crate::syntax::ast::{
    ApplyDecl, Binding, Decl, DeclKind, Expr, Ident, JoinDecl, Name, PackageDecl, Param,
};
pub use checker::{BindingAt, Checked, Definition};
use checker::{Checker, Ctx, Local};
pub use expr::dof_mentions;
use scope::{DeclsAt, Scope};
use types::{DefId, ScopeId, Ty};

/// Checks every module of the workspace.
pub fn check(workspace: &Workspace) -> (Checked, Diagnostics) {
    let mut checker = Checker {
        workspace,
        out: Checked {
            scopes: Vec::new(),
            definitions: Vec::new(),
            resolutions: Default::default(),
            module_scopes: FxHashMap::default(),
            package_scopes: FxHashMap::default(),
            bindings: FxHashMap::default(),
        },
        definition_trees: Vec::new(),
        diagnostics: Diagnostics::default(),
        instantiations: Vec::new(),
        memo: FxHashMap::default(),
        modules_in_progress: Vec::new(),
        simulate_seen: None,
        outputs: HashMap::new(),
        suggestions_left: std::cell::Cell::new(checker::MAX_SUGGESTIONS),
        shadow_warned: Default::default(),
        value_inputs: Default::default(),
    };
    for &root in &workspace.roots {
        checker.module(root);
    }
    checker.out.resolutions.finish();
    (checker.out, checker.diagnostics)
}

impl<'w> Checker<'w> {
    fn new_scope(&mut self, parent: Option<(ScopeId, u32)>, decls: DeclsAt) -> ScopeId {
        self.out.scopes.push(Scope::new(parent, decls));
        ScopeId(self.out.scopes.len() as u32 - 1)
    }

    fn scope_mut(&mut self, id: ScopeId) -> &mut Scope {
        &mut self.out.scopes[id.0 as usize]
    }

    /// Reports an error, adding the use sites of the definitions being instantiated.
    fn report(&mut self, mut diagnostic: Diagnostic) {
        for (site, name) in self.instantiations.iter().rev() {
            diagnostic = diagnostic.secondary(*site, format!("in this use of `{name}`"));
        }
        self.diagnostics.push(diagnostic);
    }

    fn module(&mut self, id: ModuleId) -> ScopeId {
        if let Some(&scope) = self.out.module_scopes.get(&id) {
            return scope;
        }
        let scope = self.new_scope(None, DeclsAt::Module(id));
        self.out.module_scopes.insert(id, scope);
        if self.modules_in_progress.contains(&id) {
            return scope;
        }
        self.modules_in_progress.push(id);
        let decls = &self.workspace.module(id).program.decls;
        self.decls(decls, scope);
        self.modules_in_progress.pop();
        scope
    }

    fn decls(&mut self, decls: &'w [Decl], scope: ScopeId) {
        for (index, decl) in (0..).zip(decls) {
            self.decl(decl, index, scope);
        }
    }

    /// The declarations of a scope, in the syntax tree.
    fn scope_decls(&self, scope: ScopeId) -> &'w [Decl] {
        match self.out.scope(scope).decls {
            DeclsAt::Module(module) => &self.workspace.module(module).program.decls,
            DeclsAt::Package { parent, decl } => {
                match self.scope_decls(parent).get(decl as usize).map(|d| &d.kind) {
                    Some(DeclKind::Package(package)) => &package.decls,
                    _ => &[],
                }
            }
        }
    }

    /// Makes the table of the names a scope declares that are not declared yet, with the spans
    /// of their first declaration, when a name is first found missing in it (see
    /// [`Scope::declared_later`]): a program without such errors never makes one.
    fn note_declared_later(&mut self, scope: ScopeId) {
        if self.out.scope(scope).declared_later.is_some() {
            return;
        }
        let mut later = FxHashMap::default();
        for decl in self.scope_decls(scope) {
            for (name, span, extent) in declared_names(decl) {
                if !self.out.scope(scope).names.contains_key(&name) {
                    later.entry(name).or_insert((span, extent));
                }
            }
        }
        self.scope_mut(scope).declared_later = Some(later);
    }

    fn ctx(&self, scope: ScopeId) -> Ctx {
        Ctx {
            scope,
            limit: self.out.scope(scope).len(),
            locals: Vec::new(),
        }
    }

    /// Checks the `index`-th declaration of `scope`.
    fn decl(&mut self, decl: &'w Decl, index: u32, scope: ScopeId) {
        match &decl.kind {
            DeclKind::Let(bindings) => self.let_decl(bindings, index, scope),
            DeclKind::Define(define) => {
                self.define(&define.name, &define.params, &define.body, index, scope)
            }
            DeclKind::Join(join) => {
                let JoinDecl {
                    first,
                    second,
                    link,
                    name,
                } = &**join;
                let mut ctx = self.ctx(scope);
                for (member, position) in [(first, "first"), (second, "second")] {
                    let ty = self.expr(member, &mut ctx);
                    if !ty.fits(Ty::Frame) {
                        self.report(join_member_error(member.span, position, ty));
                    }
                }
                // The link may read the join's own coordinates (`crank.q'`); its frames may not.
                if let Some(name) = name {
                    ctx.locals.push(Local {
                        name: name.name,
                        ty: Ty::Join,
                        coordinate: false,
                    });
                }
                let ty = self.expr(link, &mut ctx);
                self.expect_value(link, ty, Ty::Link, "the link of `join ... with <link>`");
                if let Some(name) = name {
                    self.declare(scope, name, Ty::Join);
                }
            }
            DeclKind::Initial(values) => {
                let mut ctx = self.ctx(scope);
                for initial in values {
                    self.initial_value(initial, &mut ctx);
                }
            }
            DeclKind::Given(values) => {
                let mut ctx = self.ctx(scope);
                for given in values {
                    let target = self.expr(&given.target, &mut ctx);
                    let value = self.expr(&given.value, &mut ctx);
                    let expected = if target.numeric() == Ty::Vector {
                        Ty::Vector
                    } else {
                        Ty::Scalar
                    };
                    if !matches!(target.numeric(), Ty::Scalar | Ty::Vector | Ty::Error) {
                        self.report(
                            Diagnostic::error("E0419", format!("`given` gives values to unknowns, not to {}", target.with_article()))
                                .primary(given.target.span, format!("this is {}", target.with_article()))
                                .help("name an unknown (`let L = ?s;` then `given L = 0.5`) or a generic quantity (`given arm.mass = 2`)"),
                        );
                    }
                    self.expect_value(&given.value, value, expected, "a given value");
                }
            }
            DeclKind::Drive(drive) => {
                let mut ctx = self.ctx(scope);
                self.drive(drive, &mut ctx);
            }
            DeclKind::Simulate(fields) => self.simulate(fields, decl.span, scope),
            DeclKind::Output(output) => self.output(output, scope),
            DeclKind::Apply(apply) => {
                let ApplyDecl {
                    effort,
                    target,
                    reaction,
                } = &**apply;
                let mut ctx = self.ctx(scope);
                let effort_ty = self.expr(effort, &mut ctx);
                for target in target.iter().chain(reaction) {
                    let target_ty = self.expr(target, &mut ctx);
                    self.apply(effort, effort_ty, target, target_ty);
                }
            }
            DeclKind::Package(package_decl) => self.package(package_decl, decl.span, index, scope),
            DeclKind::Import(import) => {
                let alias = &import.alias;
                let Some(&module) = self.workspace.imports.get(&decl.span) else {
                    return;
                };
                let imported = self.module(module);
                match alias {
                    Some(alias) => self.declare(scope, alias, Ty::Package(imported)),
                    None => {
                        let limit = self.out.scope(scope).len();
                        self.scope_mut(scope).opened.push((imported, limit));
                        let name: Name = self.workspace.module(module).name.as_str().into();
                        if !self.out.scope(scope).names.contains_key(&name) {
                            self.scope_mut(scope)
                                .insert(name, Ty::Package(imported), decl.span);
                        }
                    }
                }
            }
            // Scenes are selected by the loader (`load::scene`) and never reach the checker,
            // nor the effort selections of the selected scene: any other is out of place.
            DeclKind::SelectEfforts(selection) => self.report(
                Diagnostic::error("E0717", format!("`apply {}` chooses the efforts of a scene, and is written in one", selection.word.name))
                    .primary(decl.span, "outside a scene")
                    .help("move it into a scene (`scene light = apply without weight ; end ;`): the program itself applies what it declares"),
            ),
            DeclKind::Scene(_) | DeclKind::Error => {}
        }
    }

    /// `package P = decls end`: its declarations see the file's names declared before it.
    /// An array `package P[i in a .. b]` is declared before its declarations, which may name
    /// other instances (`P[i - 1]:x`), and its index is a scalar name of the package.
    fn package(&mut self, package_decl: &'w PackageDecl, span: Span, at: u32, scope: ScopeId) {
        let PackageDecl { name, index, decls } = package_decl;
        let decls_at = DeclsAt::Package {
            parent: scope,
            decl: at,
        };
        let package = self.new_scope(None, decls_at);
        self.out.package_scopes.insert(span, package);
        if let Some(index) = index {
            let mut ctx = self.ctx(scope);
            for bound in [&index.first, &index.last] {
                let ty = self.expr(bound, &mut ctx);
                self.expect_value(bound, ty, Ty::Scalar, "a bound of an array of packages");
            }
            self.declare(scope, name, Ty::Package(package));
            self.scope_mut(package).index = Some(index.variable.name);
            self.declare(package, &index.variable, Ty::Scalar);
        }
        let limit = self.out.scope(scope).len();
        self.scope_mut(package).parent = Some((scope, limit));
        self.decls(decls, package);
        if index.is_none() {
            self.declare(scope, name, Ty::Package(package));
        }
    }

    /// `let a = e and b = e`: the bindings are simultaneous, as in the thesis's grammar: none of
    /// them sees the others.
    fn let_decl(&mut self, bindings: &'w [Binding], decl: u32, scope: ScopeId) {
        let mut ctx = self.ctx(scope);
        let types: Vec<Ty> = bindings
            .iter()
            .map(|b| self.expr(&b.value, &mut ctx))
            .collect();
        for ((binding, ty), at) in bindings.iter().zip(types).zip(0..) {
            self.expect_first_class(&binding.value, ty);
            self.declare(scope, &binding.name, ty);
            let at = BindingAt { decl, binding: at };
            self.out.bindings.insert(binding.name.span, at);
        }
    }

    fn define(
        &mut self,
        name: &'w Ident,
        params: &'w [Param],
        body: &'w Expr,
        decl: u32,
        scope: ScopeId,
    ) {
        let limit = self.out.scope(scope).len();
        let mut seen: HashMap<&str, Span> = HashMap::new();
        let mut declared = Vec::with_capacity(params.len());
        for param in params {
            if let Some(first) = seen.insert(&param.name.name, param.name.span) {
                self.report(
                    Diagnostic::error(
                        "E0303",
                        format!("parameter `{}` is declared twice", param.name.name),
                    )
                    .primary(param.name.span, "second declaration")
                    .secondary(first, "first declaration"),
                );
            }
            declared.push(self.annotation(param));
        }
        let id = DefId(self.out.definitions.len() as u32);
        self.out.definitions.push(Definition {
            name: name.name,
            span: name.span,
            scope,
            limit,
            decl,
        });
        self.definition_trees.push((params, body));
        self.declare(scope, name, Ty::Definition(id));
        // Check the body once now: names are resolved and typed parameters checked even if the
        // definition is never used. Untyped parameters are `Error` here (they fit anywhere);
        // their real types are checked at each use.
        let locals = params
            .iter()
            .zip(declared)
            .map(|(p, ty)| Local {
                name: p.name.name,
                ty: ty.unwrap_or(Ty::Error),
                coordinate: false,
            })
            .collect();
        let mut ctx = Ctx {
            scope,
            limit,
            locals,
        };
        self.expr(body, &mut ctx);
    }

    fn annotation(&mut self, param: &Param) -> Option<Ty> {
        let annotation = param.ty.as_ref()?;
        let ty = Ty::from_annotation(&annotation.name);
        if ty.is_none() {
            let candidate = crate::diag::suggest::did_you_mean(&annotation.name, Ty::ANNOTATIONS);
            let diagnostic =
                Diagnostic::error("E0409", format!("unknown type `{}`", annotation.name))
                    .primary(annotation.span, "not a type");
            self.report(match candidate {
                Some(_) => diagnostic.did_you_mean(annotation.span, candidate),
                None => diagnostic.help(format!("the types are: {}", Ty::ANNOTATIONS.join(", "))),
            });
        }
        ty
    }

    /// Binds a name in a scope, refusing a second declaration of the same name.
    fn declare(&mut self, scope: ScopeId, name: &Ident, ty: Ty) {
        if let Some(previous) = self.out.scope(scope).names.get(&name.name) {
            let previous = previous.span;
            self.report(
                Diagnostic::error("E0302", format!("`{}` is already defined", name.name))
                    .primary(name.span, "defined again here")
                    .secondary(previous, "first defined here")
                    .help("give the second definition another name"),
            );
            return;
        }
        self.scope_mut(scope).insert(name.name, ty, name.span);
    }

    /// `simulate duration = 10, integrator = dopri5, ... end`.
    fn simulate(
        &mut self,
        fields: &'w [crate::syntax::ast::FieldInit],
        span: Span,
        scope: ScopeId,
    ) {
        if let Some(previous) = self.simulate_seen.replace(span) {
            self.report(
                Diagnostic::error("E0418", "a program has one `simulate` declaration")
                    .primary(span, "a second one")
                    .secondary(previous, "the first one")
                    .help("keep one; for several studies of the program, give each its own in a scene (`scene fast = simulate duration = 1 end; end;`)"),
            );
        }
        let mut ctx = self.ctx(scope);
        for (i, field) in fields.iter().enumerate() {
            let name = &*field.name.name;
            if let Some(first) = fields[..i].iter().find(|f| f.name.name == field.name.name) {
                self.report(
                    Diagnostic::error("E0303", format!("field `{name}` is given twice"))
                        .primary(field.name.span, "second value")
                        .secondary(first.name.span, "first value"),
                );
                continue;
            }
            if name == "integrator" {
                let known: Vec<&str> = crate::integrators::names().collect();
                let given = match &field.value.kind {
                    crate::syntax::ast::ExprKind::Name(name) => Some(name),
                    _ => None,
                };
                if given.is_none_or(|g| !known.contains(&&**g)) {
                    let candidate = given
                        .and_then(|g| crate::diag::suggest::did_you_mean(g, known.iter().copied()));
                    let diagnostic = Diagnostic::error("E0420", "unknown integrator")
                        .primary(field.value.span, "not an integrator");
                    self.report(match candidate {
                        Some(_) => diagnostic.did_you_mean(field.value.span, candidate),
                        None => {
                            diagnostic.help(format!("the integrators are: {}", known.join(", ")))
                        }
                    });
                }
                continue;
            }
            if !crate::check::types::SIMULATE_FIELDS.contains(&name) {
                let candidate = crate::diag::suggest::did_you_mean(
                    name,
                    crate::check::types::SIMULATE_FIELDS.iter().copied(),
                );
                let diagnostic =
                    Diagnostic::error("E0405", format!("`simulate` has no field `{name}`"))
                        .primary(field.name.span, "unknown field");
                self.report(match candidate {
                    Some(_) => diagnostic.did_you_mean(field.name.span, candidate),
                    None => diagnostic.help(format!(
                        "the fields of `simulate` are: integrator, {}",
                        crate::check::types::SIMULATE_FIELDS.join(", ")
                    )),
                });
                continue;
            }
            let ty = self.expr(&field.value, &mut ctx);
            self.expect_value(&field.value, ty, Ty::Scalar, &format!("field `{name}`"));
        }
    }

    /// `initial crank.q = e [fixed]`: the target is a coordinate of a named join, or its
    /// derivative (a starting velocity, which cannot be `fixed`).
    fn initial_value(&mut self, initial: &'w crate::syntax::ast::InitialValue, ctx: &mut Ctx) {
        let (coordinate, primes) = strip_primes(&initial.target);
        let is_coordinate = matches!(&coordinate.kind, crate::syntax::ast::ExprKind::Field(_));
        let ty = self.expr(&initial.target, ctx);
        let target_ty = match &coordinate.kind {
            crate::syntax::ast::ExprKind::Field(access) => {
                self.expr_type_silently(&access.target, ctx)
            }
            _ => ty,
        };
        if !is_coordinate || target_ty != Ty::Join {
            if ty != Ty::Error && target_ty != Ty::Error {
                self.report(
                    Diagnostic::error("E0416", "`initial` gives values to joint coordinates: `<join>.<coordinate>`")
                        .primary(initial.target.span, "not a coordinate of a named join")
                        .help("name the join with `join ... with <link> as crank;`, then write `initial crank.q = ...`"),
                );
            }
        } else if primes > 1 {
            self.report(
                Diagnostic::error(
                    "E0416",
                    "`initial` gives positions (`crank.q`) or velocities (`crank.q'`) only",
                )
                .primary(initial.target.span, "a second derivative"),
            );
        } else if primes == 1 && (initial.fixed || initial.guess) {
            let mark = if initial.fixed { "fixed" } else { "guess" };
            self.report(
                Diagnostic::error("E0416", format!("a starting velocity cannot be `{mark}`"))
                    .primary(initial.target.span, "a velocity")
                    .help("`fixed` and `guess` tell assembly how to treat a position; a velocity is a simulation's starting rate"),
            );
        }
        let value_ty = self.expr(&initial.value, ctx);
        self.expect_value(&initial.value, value_ty, Ty::Scalar, "an initial value");
    }

    /// `drive crank.q = law`: the word is `drive` (E0480), the target a coordinate of a named
    /// join (E0481), the law a scalar. What the law may depend on (the time and numbers) and
    /// which coordinates may be driven are decided with the mechanism (`kinematics::drives`).
    fn drive(&mut self, drive: &'w crate::syntax::ast::DriveDecl, ctx: &mut Ctx) {
        match drive.word.name.as_str() {
            // `lock crank.q = 0.3`: a drive at one value (`elab` refuses a value that varies).
            "drive" | "lock" => {}
            "rate" | "update" => return self.rate(drive, ctx),
            "actuate" => return self.actuate(drive, ctx),
            "input" => return self.input(drive, ctx.scope, ctx),
            word => {
                let help = match crate::diag::suggest::did_you_mean(word, ["drive", "rate", "update", "actuate", "lock", "input"]) {
                    Some("input") => "did you mean `input`? `input swing.q = 0;` declares the effort along a coordinate as an input",
                    Some("rate") => "did you mean `rate`? `rate integral = error;` gives the derivative of a state",
                    Some("update") => "did you mean `update`? `update u = -k * arm.q;` gives the next value of a sampled state",
                    Some("actuate") => "did you mean `actuate`? `actuate arm.q = law;` applies an effort along a coordinate",
                    Some("lock") => "did you mean `lock`? `lock elbow.q = 0.4;` holds a coordinate at one value",
                    _ => "did you mean `drive`? `drive crank.q = 2 * pi * time;` imposes a coordinate as a law of time",
                };
                self.report(
                    Diagnostic::error("E0480", format!("unknown declaration `{word}`"))
                        .primary(drive.word.span, "a declaration starts with a keyword")
                        .help(help),
                );
                return;
            }
        }
        if let Some(frame) = drive.position_target() {
            return self.position_drive(drive, frame, ctx);
        }
        let ty = self.expr(&drive.target, ctx);
        let target_ty = match &drive.target.kind {
            crate::syntax::ast::ExprKind::Field(access) => {
                self.expr_type_silently(&access.target, ctx)
            }
            _ => Ty::Error,
        };
        if target_ty != Ty::Join && ty != Ty::Error {
            let found = match &drive.target.kind {
                crate::syntax::ast::ExprKind::Prime(_) => {
                    "a rate: the law gives the position, its rates follow"
                }
                _ => "not a coordinate of a named join",
            };
            self.report(
                Diagnostic::error("E0481", "`drive` imposes a joint coordinate: `drive <join>.<coordinate> = <law of time>`")
                    .primary(drive.target.span, found)
                    .help("name the join with `join ... with <link> as crank;`, then write `drive crank.q = 2 * pi * time`"),
            );
        }
        let value_ty = self.expr(&drive.value, ctx);
        self.expect_value(&drive.value, value_ty, Ty::Scalar, "the law of a drive");
    }

    /// `drive position(F) = law`: F a frame (E0492), the law a vector (E0493). Whether the
    /// path over-constrains the mechanism is decided with it (`kinematics::position_drives`).
    fn position_drive(
        &mut self,
        drive: &'w crate::syntax::ast::DriveDecl,
        frame: &'w Expr,
        ctx: &mut Ctx,
    ) {
        let frame_ty = self.expr(frame, ctx);
        if !frame_ty.fits(Ty::Frame) {
            self.report(
                Diagnostic::error("E0492", format!("`drive position(...)` imposes the position of a frame, not of {}", frame_ty.with_article()))
                    .primary(frame.span, format!("this is {}, not a frame", frame_ty.with_article()))
                    .help("name a body or a frame (`drive position(nacelle) = [x, y, z]`, `drive position(arm.tip) = ...`); to impose a join's coordinate, `drive crank.q = law`"),
            );
        }
        let law_ty = self.expr(&drive.value, ctx);
        if !law_ty.fits(Ty::Vector) {
            self.report(
                Diagnostic::error("E0493", format!("the law of a position drive is a vector of three laws of time (x, y, z in the fixed axes), not {}", law_ty.with_article()))
                    .primary(drive.value.span, format!("this is {}", law_ty.with_article()))
                    .help("write the three coordinates of the path: `drive position(nacelle) = [0.05 * cos(time), 0.05 * sin(time), -0.3];`"),
            );
        }
    }

    /// `rate s = f` and `update s = f`: the target and the law are scalars (that the target is
    /// a state made by `state(x0)`, or by `sample(period, x0)` for `update`, is known once
    /// evaluated: E0486, E0495, E0496).
    fn rate(&mut self, rate: &'w crate::syntax::ast::DriveDecl, ctx: &mut Ctx) {
        let (target, law) = match rate.word.name.as_str() {
            "update" => ("the state of `update`", "the update of a sampled state"),
            _ => ("the state of `rate`", "the rate of a state"),
        };
        let target_ty = self.expr(&rate.target, ctx);
        self.expect_value(&rate.target, target_ty, Ty::Scalar, target);
        let value_ty = self.expr(&rate.value, ctx);
        self.expect_value(&rate.value, value_ty, Ty::Scalar, law);
    }

    /// The type of an expression already checked (its diagnostics were reported then).
    pub(super) fn expr_type_silently(&mut self, expr: &'w Expr, ctx: &mut Ctx) -> Ty {
        let reported = self.diagnostics.list.len();
        let ty = self.expr(expr, ctx);
        self.diagnostics.truncate(reported);
        ty
    }

    fn apply(&mut self, effort: &Expr, effort_ty: Ty, target: &Expr, target_ty: Ty) {
        match effort_ty {
            Ty::Force => {
                if !target_ty.fits(Ty::Frame) {
                    self.report(
                        Diagnostic::error("E0411", format!("a force is applied on a frame, not on {}", target_ty.with_article()))
                            .primary(target.span, format!("this is {}", target_ty.with_article()))
                            .help("the frame's origin is the point of application, as in `apply f on b.iframe`"),
                    );
                }
            }
            Ty::Torque => {
                if !target_ty.fits(Ty::Body) {
                    let help = if target_ty == Ty::Frame {
                        "a torque acts on a whole body: write `<frame>.body`"
                    } else {
                        "write `apply <torque> on <body>`"
                    };
                    self.report(
                        Diagnostic::error(
                            "E0411",
                            format!(
                                "a torque is applied on a body, not on {}",
                                target_ty.with_article()
                            ),
                        )
                        .primary(target.span, format!("this is {}", target_ty.with_article()))
                        .help(help),
                    );
                }
            }
            Ty::Error => {}
            other => self.report(
                Diagnostic::error(
                    "E0411",
                    format!(
                        "`apply` needs a force or a torque, found {}",
                        other.with_article()
                    ),
                )
                .primary(effort.span, format!("this is {}", other.with_article()))
                .help("write `apply force value = ..., body = ... end on <frame>`"),
            ),
        }
    }

    /// Packages and parameterised definitions are not values: they cannot be bound or passed.
    fn expect_first_class(&mut self, expr: &Expr, ty: Ty) -> bool {
        let what = match ty {
            Ty::Package(_) => "a package",
            Ty::Definition(_) => "a parameterised definition",
            _ => return true,
        };
        let help = if matches!(ty, Ty::Package(_)) {
            "take a name from it: `P:name`"
        } else {
            "call it: `f(...)`"
        };
        self.report(
            Diagnostic::error("E0417", format!("{what} is not a value"))
                .primary(expr.span, format!("this is {what}"))
                .help(help),
        );
        false
    }

    /// Checks that an expression's type fits the expected one.
    pub(super) fn expect_value(&mut self, expr: &Expr, ty: Ty, expected: Ty, role: &str) -> bool {
        if ty.fits(expected) {
            return true;
        }
        let mut diagnostic = Diagnostic::error(
            "E0401",
            format!(
                "{role} must be {}, found {}",
                expected.with_article(),
                ty.with_article()
            ),
        )
        .primary(expr.span, format!("this is {}", ty.with_article()));
        if let Some(help) = conversion_help(ty, expected) {
            diagnostic = diagnostic.help(help);
        }
        self.report(diagnostic);
        false
    }
}

fn join_member_error(span: Span, position: &str, ty: Ty) -> Diagnostic {
    Diagnostic::error("E0410", format!("`join` connects two frames, but its {position} member is {}", ty.with_article()))
        .primary(span, format!("this is {}, not a frame", ty.with_article()))
        .help("write `join <frame> and <frame> with <link>`; a frame is `<displacement> @ <body>`, `b.frame` or `b.iframe`")
}

fn conversion_help(found: Ty, expected: Ty) -> Option<String> {
    Some(match (found, expected) {
        (Ty::Scalar, Ty::Vector) => "a vector is written `[x, y, z]`".to_string(),
        (Ty::Vector, Ty::Rotation) => "a rotation is written `angle || axis`".to_string(),
        (Ty::Displacement, Ty::Frame) => "a frame is `<displacement> @ <body>`".to_string(),
        (Ty::Body, Ty::Scalar | Ty::Vector) => "read a field: `b.mass`, `b.inertia`".to_string(),
        (Ty::Definition(_), _) => "a parameterised definition must be called: `f(...)`".to_string(),
        (Ty::Package(_), _) => "take a name from the package: `P:name`".to_string(),
        _ => return None,
    })
}

/// `crank.q''` → (`crank.q`, 2).
fn strip_primes(expr: &Expr) -> (&Expr, usize) {
    match &expr.kind {
        crate::syntax::ast::ExprKind::Prime(inner) => {
            let (base, n) = strip_primes(inner);
            (base, n + 1)
        }
        _ => (expr, 0),
    }
}

/// An optional name a declaration introduces, with the declaration's span.
fn named(name: &Option<Ident>, decl: Span) -> Vec<(Name, Span, Span)> {
    name.iter()
        .map(|name| (name.name, name.span, decl))
        .collect()
}

/// Names a declaration introduces in its scope, with the span of the name and of its whole
/// definition.
fn declared_names(decl: &Decl) -> Vec<(Name, Span, Span)> {
    match &decl.kind {
        DeclKind::Let(bindings) => bindings
            .iter()
            .map(|b| (b.name.name, b.name.span, b.name.span.to(b.value.span)))
            .collect(),
        DeclKind::Define(define) => vec![(define.name.name, define.name.span, decl.span)],
        DeclKind::Package(package) => {
            vec![(package.name.name, package.name.span, decl.span)]
        }
        DeclKind::Import(import) => named(&import.alias, decl.span),
        DeclKind::Join(join) => named(&join.name, decl.span),
        DeclKind::Drive(drive) => match drive.value_input_name() {
            Some(name) => vec![(name.name, name.span, decl.span)],
            None => Vec::new(),
        },
        _ => Vec::new(),
    }
}
