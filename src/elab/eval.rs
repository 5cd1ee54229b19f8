//! Evaluation of declarations and expressions.

use std::sync::Arc;

use super::elaborator::{internal, Elaborator, Global, OwnJoin};
use super::instances::{InstanceId, ROOT};
use super::mechanism::*;
use super::operations::{
    as_displacement, as_frame, as_join, as_scalar, as_vector, binary, builtin_call, check_axis,
    check_finite, finite_literal, is_zero, vector_or_matrix,
};
use super::value::*;

/// The name of a contact (`join plane and ball with rolling(r) as c`) stands for a join whose
/// number has this bit set, and the contact's index below it: it has no coordinates to read.
const CONTACT_JOIN: u32 = 1 << 31;
use crate::check::scope::{ScopeId, Target};
use crate::check::types::Ty;
use crate::diag::Diagnostic;
use crate::load::ModuleId;
use crate::source::Span;
use crate::syntax::ast::{
    ApplyDecl, Arg, BinaryExpr, BinaryOp, Binding, Callee, ConstructKind, Decl, DeclKind,
    DefineDecl, Expr, ExprKind, FieldInit, Ident, JoinDecl, LocalExpr, Name,
};

type Result<T> = std::result::Result<T, Diagnostic>;

/// Local bindings while evaluating an expression: parameters, coordinates, `local` names.
pub(super) type Locals = Vec<(Name, Value)>;

const MAX_DEPTH: usize = 64;

impl<'c, 'w> Elaborator<'c, 'w> {
    pub(super) fn module(&mut self, id: ModuleId) -> Result<()> {
        if self.elaborated_modules.contains(&id) {
            return Ok(());
        }
        self.elaborated_modules.push(id);
        let scope = *self
            .checked
            .module_scopes
            .get(&id)
            .ok_or_else(|| internal("module was not checked"))?;
        for index in 0..self.decl_count(scope)? {
            self.with_decl(scope, index, |elaborator, decl| {
                elaborator.decl(decl, scope)
            })?;
        }
        Ok(())
    }

    /// Records the frames a main module names at its top level (`let tip = … @ arm;`) in the
    /// mechanism's table of frames. Only bindings the checker typed as frames are evaluated, so
    /// no other unused definition is. The names are read in the checker's scope, in declaration
    /// order: the declarations of a root file may have been freed by now.
    pub(super) fn name_frames(&mut self, id: ModuleId) -> Result<()> {
        let Some(&scope) = self.checked.module_scopes.get(&id) else {
            return Ok(());
        };
        let checked = self.checked;
        let names = &checked.scope(scope).names;
        for name in &checked.scope(scope).order {
            // Only a `let` binding has the type of a frame.
            let Some(entry) = names.get(name).filter(|e| e.ty == Ty::Frame) else {
                continue;
            };
            if let Value::Frame(frame) = self.global(scope, name)? {
                self.mechanism.frames.push(NamedFrame {
                    name: *name,
                    frame,
                    span: entry.span,
                });
            }
        }
        Ok(())
    }

    /// The declarations of a package, in order.
    pub(super) fn decls(&mut self, decls: &[Decl], scope: ScopeId) -> Result<()> {
        decls.iter().try_for_each(|decl| self.decl(decl, scope))
    }

    fn decl(&mut self, decl: &Decl, scope: ScopeId) -> Result<()> {
        let mut locals = Locals::new();
        match &decl.kind {
            // Definitions are evaluated when first used (see `global`).
            DeclKind::Let(_) | DeclKind::Define(_) => Ok(()),
            DeclKind::Join(join) => {
                let JoinDecl {
                    first,
                    second,
                    link,
                    name,
                } = &**join;
                let first = self
                    .expr(first, &mut locals)
                    .and_then(|v| as_frame(v, first.span))?;
                let second = self
                    .expr(second, &mut locals)
                    .and_then(|v| as_frame(v, second.span))?;
                // The join's own name is visible in its link, for reading its coordinates.
                let id = JoinId(self.mechanism.joins.len() as u32);
                if let Some(name) = name {
                    locals.push((name.name, Value::Join(id)));
                    self.own_join = Some(OwnJoin {
                        id,
                        name: name.name,
                        read: Vec::new(),
                    });
                }
                let link_value = self.expr(link, &mut locals);
                let own = self.own_join.take();
                let Value::Link(link) = link_value? else {
                    return Err(internal("join without a link"));
                };
                if let Some(own) = own {
                    self.resolve_own_coordinates(own, link, decl.span)?;
                }
                let instance = self.instances.current;
                let join_name = name
                    .as_ref()
                    .map(|n| self.qualified_name(&n.name, instance));
                // A contact is a constraint, not a joint: its name stands for no coordinates.
                let id = if self.mechanism.link(link).contact().is_some() {
                    let id = JoinId(CONTACT_JOIN | self.mechanism.contacts.len() as u32);
                    let contact = Contact {
                        name: join_name,
                        first,
                        second,
                        link,
                        span: decl.span,
                    };
                    self.mechanism.contacts.push(contact);
                    id
                } else {
                    let join = Join {
                        name: join_name,
                        first,
                        second,
                        link,
                        span: decl.span,
                    };
                    self.mechanism.joins.push(join);
                    id
                };
                if let Some(name) = name {
                    let key = (scope, self.instance_of(scope)?, name.name);
                    self.globals.insert(key, Global::Ready(Value::Join(id)));
                }
                Ok(())
            }
            DeclKind::Given(values) => {
                for given in values {
                    let target = self.expr(&given.target, &mut locals)?;
                    let value = self.expr(&given.value, &mut locals)?;
                    let pairs: Vec<(Scalar, Scalar)> = match (target, value) {
                        (Value::Vector(t), v) => {
                            t.into_iter().zip(as_vector(v, given.value.span)?).collect()
                        }
                        (t, v) => vec![(
                            as_scalar(t, given.target.span)?,
                            as_scalar(v, given.value.span)?,
                        )],
                    };
                    for (target, value) in pairs {
                        let SExpr::Unknown(id) = *target else {
                            return Err(Diagnostic::error(
                                "E0604",
                                "`given` gives values to unknowns and generic quantities only",
                            )
                            .primary(given.target.span, "this already has a value")
                            .help("values written in the program need no `given`"));
                        };
                        self.mechanism.given.push((id, value, given.target.span));
                    }
                }
                Ok(())
            }
            DeclKind::Output(output) => self.output(output),
            DeclKind::Simulate(fields) => {
                let mut scenario = crate::elab::mechanism::Scenario {
                    span: Some(decl.span),
                    ..Default::default()
                };
                for field in fields {
                    if &*field.name.name == "integrator" {
                        if let ExprKind::Name(name) = &field.value.kind {
                            scenario.integrator = Some((name.to_string(), field.value.span));
                        }
                        continue;
                    }
                    let value = self
                        .expr(&field.value, &mut locals)
                        .and_then(|v| as_scalar(v, field.value.span))?;
                    scenario
                        .settings
                        .push((field.name.name.to_string(), value, field.value.span));
                }
                self.mechanism.scenario = Some(scenario);
                Ok(())
            }
            DeclKind::Initial(values) => {
                for initial in values {
                    let Value::Scalar(target) = self.expr(&initial.target, &mut locals)? else {
                        return Err(internal("initial value of a non-coordinate"));
                    };
                    let SExpr::JoinCoordinate { join, index, order } = *target else {
                        return Err(internal("initial value of a non-coordinate"));
                    };
                    let value = self
                        .expr(&initial.value, &mut locals)
                        .and_then(|v| as_scalar(v, initial.value.span))?;
                    self.mechanism.initial.push(InitialValue {
                        join,
                        coordinate: index as usize,
                        order,
                        value,
                        fixed: initial.fixed,
                        guess: initial.guess,
                        span: initial.target.span,
                    });
                }
                Ok(())
            }
            DeclKind::Drive(input) if input.word.name.as_str() == "input" => {
                self.input_decl(input, scope, &mut locals)
            }
            DeclKind::Drive(rate) if matches!(rate.word.name.as_str(), "rate" | "update") => {
                self.rate_decl(rate, &mut locals)
            }
            DeclKind::Drive(drive) if drive.position_target().is_some() => {
                self.position_drive(drive, &mut locals)
            }
            DeclKind::Drive(drive) => {
                let Value::Scalar(target) = self.expr(&drive.target, &mut locals)? else {
                    return Err(internal("drive of a non-coordinate"));
                };
                let SExpr::JoinCoordinate { join, index, .. } = *target else {
                    return Err(internal("drive of a non-coordinate"));
                };
                let law = self
                    .expr(&drive.value, &mut locals)
                    .and_then(|v| as_scalar(v, drive.value.span))?;
                if drive.word.name.as_str() == "actuate" {
                    self.mechanism.actuators.push(Actuator {
                        join,
                        coordinate: index as usize,
                        law,
                        span: drive.target.span,
                        law_span: drive.value.span,
                    });
                    return Ok(());
                }
                let locked = drive.word.name.as_str() == "lock";
                if locked && law.varies_with_motion() {
                    return Err(Diagnostic::error(
                        "E0711",
                        "a lock holds a coordinate at one value: its value cannot vary",
                    )
                    .primary(drive.value.span, "this varies with the time or the motion")
                    .help("lock at a number (`lock elbow.q = 0.4;`), or impose a motion with `drive elbow.q = law;`"));
                }
                self.mechanism.drives.push(Drive {
                    join,
                    coordinate: index as usize,
                    law,
                    span: drive.target.span,
                    law_span: drive.value.span,
                    locked,
                });
                Ok(())
            }
            DeclKind::Apply(apply) => {
                let ApplyDecl {
                    effort,
                    target,
                    reaction,
                } = &**apply;
                let written = effort;
                let effort = match self.expr(effort, &mut locals)? {
                    Value::Force(id) | Value::Torque(id) => id,
                    _ => return Err(internal("apply without an effort")),
                };
                if let Some(filter) = &mut self.effort_filter {
                    let name = self.mechanism.efforts[effort.0 as usize].name;
                    let names = super::effort_choice::application_names(
                        name.map(|n| n.to_string()),
                        written,
                        &self.enclosing_groups,
                    );
                    if !filter.keeps(names) {
                        return Ok(());
                    }
                }
                let Some(target) = target else {
                    self.fields.push((effort, decl.span));
                    return Ok(());
                };
                let target = self
                    .expr(target, &mut locals)
                    .and_then(|v| as_frame(v, target.span))?;
                self.mechanism.applications.push(Application {
                    effort,
                    target,
                    span: decl.span,
                });
                if let Some(reaction) = reaction {
                    let on = self
                        .expr(reaction, &mut locals)
                        .and_then(|v| as_frame(v, reaction.span))?;
                    let opposite = self.opposite(effort);
                    self.mechanism.applications.push(Application {
                        effort: opposite,
                        target: on,
                        span: decl.span,
                    });
                }
                Ok(())
            }
            DeclKind::Package(package_decl) => {
                let package = *self
                    .checked
                    .package_scopes
                    .get(&decl.span)
                    .ok_or_else(|| internal("package not checked"))?;
                match &package_decl.index {
                    None => {
                        (self.enclosing_groups).push(package_decl.name.name.to_string());
                        let elaborated = self.decls(&package_decl.decls, package);
                        self.enclosing_groups.pop();
                        elaborated
                    }
                    Some(index) => {
                        self.package_array(&package_decl.name, index, &package_decl.decls, package)
                    }
                }
            }
            DeclKind::Import { .. } => match self.workspace.imports.get(&decl.span) {
                Some(&module) => self.module(module),
                None => Err(internal("unresolved import")),
            },
            DeclKind::Error => Err(internal("declaration with a syntax error")),
            DeclKind::Scene(_) | DeclKind::SelectEfforts(_) => Err(internal(
                "a scene's declaration left after loading (`load::scene`)",
            )),
        }
    }

    /// The value of a declared name. A `let` is evaluated on first use: unused definitions of a
    /// library cost nothing here.
    pub(super) fn global(&mut self, scope: ScopeId, name: &Name) -> Result<Value> {
        let instance = self.instance_of(scope)?;
        let key = (scope, instance, *name);
        match self.globals.get(&key) {
            Some(Global::Ready(value)) => return Ok(value.clone()),
            Some(Global::InProgress) => {
                let shown = self.qualified_name(name, instance);
                return Err(Diagnostic::error(
                    "E0631",
                    format!("`{shown}` depends on itself through instances of an array"),
                )
                .primary(self.checked.scope(scope).names[name].span, "defined here")
                .help("an instance may use the names of other instances, but not in a cycle"));
            }
            None => {}
        }
        let entry = self
            .checked
            .scope(scope)
            .names
            .get(name)
            .ok_or_else(|| internal(format!("`{name}` not declared")))?;
        let value = match entry.ty {
            Ty::Definition(def) => Value::Definition(def),
            Ty::Package(_) => Value::Package,
            Ty::Join => {
                let shown = self.qualified_name(name, instance);
                return Err(Diagnostic::error(
                    "E0631",
                    format!("the join `{shown}` is used before its instance declares it"),
                )
                .primary(entry.span, "declared here, in a later instance")
                .help("an instance may name the joins of the instances before it, not after"));
            }
            _ => {
                let at = *self
                    .checked
                    .bindings
                    .get(&entry.span)
                    .ok_or_else(|| internal(format!("`{name}` has no value")))?;
                self.globals.insert(key, Global::InProgress);
                return self.with_decl(scope, at.decl, |elaborator, decl| {
                    let DeclKind::Let(bindings) = &decl.kind else {
                        return Err(internal(format!("`{name}` is not bound by a `let`")));
                    };
                    let binding = (bindings.get(at.binding as usize))
                        .ok_or_else(|| internal(format!("`{name}` has no binding")))?;
                    elaborator.binding(binding, key, instance)
                });
            }
        };
        self.globals.insert(key, Global::Ready(value.clone()));
        Ok(value)
    }

    /// Evaluates a `let` binding of the name `key` in `instance`, and records its value (before
    /// its declaration is given back: see `decls.rs`).
    fn binding(
        &mut self,
        binding: &Binding,
        key: (ScopeId, InstanceId, Name),
        instance: InstanceId,
    ) -> Result<Value> {
        let value = self.within(instance, |elaborator| {
            elaborator.expr(&binding.value, &mut Locals::new())
        })?;
        if matches!(binding.value.kind, ExprKind::Name(_)) {
            self.point_out_alias(&value, binding, instance);
        }
        self.name_object(&value, &binding.name.name, instance);
        self.globals.insert(key, Global::Ready(value.clone()));
        Ok(value)
    }

    /// `let v1 = proto;` where `proto` is a body: `v1` is that same body, not a copy. Legal,
    /// and harmless once; a second such name (`let v0 = proto; let v1 = proto;`, or one per
    /// instance of an array) is the usual slip of someone who wanted several bodies, and is
    /// pointed out.
    fn point_out_alias(&mut self, value: &Value, binding: &Binding, instance: InstanceId) {
        let Value::Body(BodyRef::Body(id)) = value else {
            return;
        };
        let alias = self.qualified_name(&binding.name.name, instance);
        let Some((earlier, earlier_span)) = self.aliases.get(id).cloned() else {
            self.aliases.insert(*id, (alias, binding.value.span));
            return;
        };
        let body = self.mechanism.body_name(BodyRef::Body(*id));
        self.warnings.push(
            Diagnostic::warning(
                "W0610",
                format!("`{alias}` and `{earlier}` are one body, `{body}`"),
            )
            .primary(binding.value.span, format!("the body `{body}` itself"))
            .secondary(earlier_span, format!("`{earlier}` is this body too"))
            .help(format!(
                "a `let` gives a value another name, it does not copy it; for a new body at each use, \
                 make a definition `let {body}() = body ... end;` and write `{body}()`"
            )),
        );
    }

    /// A name declared in `instance`, as messages and outputs show it:
    /// `P[3]:crank` in an array of packages, `crank` elsewhere.
    pub(super) fn qualified_name(&self, name: &Name, instance: InstanceId) -> Name {
        match instance {
            ROOT => *name,
            _ => Name::from(format!("{}{name}", self.instances.prefix(instance))),
        }
    }

    /// Gives an unnamed body, link, effort or unknown the name it is first bound to (in
    /// `instance`, which qualifies it).
    fn name_object(&mut self, value: &Value, name: &Name, instance: InstanceId) {
        let qualified = self.qualified_name(name, instance);
        let slot = match value {
            Value::Body(BodyRef::Body(id)) => &mut self.mechanism.bodies[id.0 as usize].name,
            Value::Link(id) => &mut self.mechanism.links[id.0 as usize].name,
            Value::Force(id) | Value::Torque(id) => &mut self.mechanism.efforts[id.0 as usize].name,
            Value::Scalar(s) => match **s {
                SExpr::Unknown(id) => &mut self.mechanism.unknowns[id.0 as usize].name,
                SExpr::State(id) => &mut self.mechanism.states[id.0 as usize].name,
                _ => return,
            },
            _ => return,
        };
        if slot.is_none() {
            *slot = Some(qualified);
        }
    }

    fn resolution(&mut self, span: Span) -> Result<Target> {
        let checked = self.checked;
        (checked.resolutions)
            .get_near(span, &mut self.resolved)
            .ok_or_else(|| internal("unresolved name"))
    }

    fn lookup(&mut self, name: &Name, target: Target, locals: &Locals) -> Result<Value> {
        match target {
            Target::Local => locals
                .iter()
                .rev()
                .find(|(n, _)| n == name)
                .map(|(_, v)| v.clone())
                .ok_or_else(|| internal(format!("local `{name}` missing"))),
            Target::Global(scope) => self.global(scope, name),
            Target::Builtin => match &**name {
                "pi" => Ok(Value::Scalar(num(std::f64::consts::PI))),
                "time" => Ok(Value::Scalar(Arc::new(SExpr::Time))),
                "earth" => Ok(Value::Body(BodyRef::Earth)),
                other => Err(internal(format!("`{other}` is not a constant"))),
            },
        }
    }

    pub(super) fn expr(&mut self, expr: &Expr, locals: &mut Locals) -> Result<Value> {
        Ok(match &expr.kind {
            ExprKind::Name(name) => {
                let target = self.resolution(expr.span)?;
                self.lookup(name, target, locals)?
            }
            ExprKind::Qualified(qualified) => {
                let target = self.resolution(expr.span)?;
                match (&qualified.index, target) {
                    (Some(index), Target::Global(scope)) => {
                        let instance = self.instance_at(scope, index, locals)?;
                        self.within(instance, |e| e.global(scope, &qualified.name.name))
                            .map_err(|error| error.secondary(expr.span, "named here"))?
                    }
                    _ => self.lookup(&qualified.name.name, target, locals)?,
                }
            }
            ExprKind::Field(access) => {
                let value = self.expr(&access.target, locals)?;
                self.field(value, &access.field)?
            }
            ExprKind::Unknown(name) => {
                if matches!(&**name, "v" | "vector") {
                    Value::Vector(
                        [0, 1, 2].map(|c| {
                            self.unknown(UnknownKind::Vector, Origin::Written, c, expr.span)
                        }),
                    )
                } else {
                    Value::Scalar(self.unknown(UnknownKind::Scalar, Origin::Written, 0, expr.span))
                }
            }
            ExprKind::Int(0) => Value::Zero,
            ExprKind::Int(1) => Value::One,
            ExprKind::Int(n) => Value::Scalar(self.literal(*n as f64)),
            ExprKind::Float(x) => {
                let x = finite_literal(*x, expr.span)?;
                let x = self.perturbation.map_or(x, |p| p.apply(x));
                Value::Scalar(self.literal(x))
            }
            ExprKind::Vector(items) => {
                let values = items
                    .iter()
                    .map(|e| self.expr(e, locals))
                    .collect::<Result<Vec<_>>>()?;
                vector_or_matrix(values, expr.span)?
            }
            ExprKind::Call(call) => {
                let value = self.call(&call.callee, &call.args, locals, expr.span)?;
                check_finite(&value, None, expr.span)?;
                value
            }
            ExprKind::Binary(operation) => {
                let BinaryExpr { op, lhs, rhs } = &**operation;
                let left = self.expr(lhs, locals)?;
                let right = self.expr(rhs, locals)?;
                if *op == BinaryOp::Rotation {
                    check_axis(&right, rhs.span)?;
                }
                let divisor_is_zero = matches!(op, BinaryOp::Div) && is_zero(&right);
                let value = binary(*op, left, right, expr.span)?;
                check_finite(&value, Some((*op, divisor_is_zero)), expr.span)?;
                value
            }
            ExprKind::Neg(inner) => match self.expr(inner, locals)? {
                Value::Zero => Value::Zero,
                Value::One => Value::Scalar(num(-1.0)),
                Value::Scalar(s) => Value::Scalar(negate(&s)),
                Value::Vector(v) => Value::Vector(v.map(|s| negate(&s))),
                Value::Matrix(m) => {
                    Value::Matrix(Box::new((*m).map(|row| row.map(|s| negate(&s)))))
                }
                _ => return Err(internal("negation of a non-number")),
            },
            ExprKind::Prime(inner) => match self.expr(inner, locals)? {
                Value::Scalar(s) => match *s {
                    SExpr::Coordinate { index, order } => {
                        Value::Scalar(Arc::new(SExpr::Coordinate {
                            index,
                            order: order + 1,
                        }))
                    }
                    SExpr::JoinCoordinate { join, index, order } => {
                        Value::Scalar(Arc::new(SExpr::JoinCoordinate {
                            join,
                            index,
                            order: order + 1,
                        }))
                    }
                    _ => return Err(internal("prime of a non-coordinate")),
                },
                _ => return Err(internal("prime of a non-scalar")),
            },
            ExprKind::Construct(c) => {
                self.construct(c.kind, &c.params, &c.fields, locals, expr.span)?
            }
            ExprKind::Local(local) => {
                let LocalExpr { bindings, body } = &**local;
                let depth = locals.len();
                let mut values = Vec::with_capacity(bindings.len());
                for binding in bindings {
                    values.push((binding.name.name, self.expr(&binding.value, locals)?));
                }
                locals.extend(values);
                let value = self.expr(body, locals);
                locals.truncate(depth);
                value?
            }
            ExprKind::Error => return Err(internal("expression with a syntax error")),
        })
    }

    fn new_unknown(
        &mut self,
        kind: UnknownKind,
        origin: Origin,
        component: u8,
        span: Span,
    ) -> UnknownId {
        self.mechanism.unknowns.push(Unknown {
            kind,
            origin,
            component,
            span,
            name: None,
        });
        UnknownId(self.mechanism.unknowns.len() as u32 - 1)
    }

    fn unknown(&mut self, kind: UnknownKind, origin: Origin, component: u8, span: Span) -> Scalar {
        Arc::new(SExpr::Unknown(
            self.new_unknown(kind, origin, component, span),
        ))
    }

    fn generic(&mut self, origin: impl Fn(u8) -> Origin, i: u8, span: Span) -> Scalar {
        self.unknown(UnknownKind::Generic, origin(i), 0, span)
    }

    fn generic_vector(&mut self, origin: impl Fn(u8) -> Origin + Copy, span: Span) -> Vector {
        [0, 1, 2].map(|i| self.generic(origin, i, span))
    }

    fn field(&mut self, value: Value, field: &Ident) -> Result<Value> {
        let name = &*field.name;
        Ok(match (value, name) {
            (Value::Body(body), "frame") => Value::Frame(Frame {
                body,
                displacement: Displacement::default(),
            }),
            (Value::Body(BodyRef::Earth), "iframe") => Value::Frame(Frame {
                body: BodyRef::Earth,
                displacement: Displacement::default(),
            }),
            (Value::Body(BodyRef::Earth), _) => {
                return Err(Diagnostic::error("E0601", format!("`earth` has no {name}"))
                    .primary(field.span, "earth is the fixed frame, not a body with mass")
                    .help("masses and inertias belong to the bodies you declare"))
            }
            (Value::Body(BodyRef::Body(id)), f) => {
                let body = self.mechanism.body(id);
                match f {
                    "iframe" => Value::Frame(Frame {
                        body: BodyRef::Body(id),
                        displacement: body.iframe.value().clone(),
                    }),
                    "mass" => Value::Scalar(body.mass.value().clone()),
                    _ => Value::Vector(body.inertia.value().clone()),
                }
            }
            (Value::Frame(frame), "body") => Value::Body(frame.body),
            (Value::Frame(frame), _) => Value::Displacement(frame.displacement),
            (Value::Force(id) | Value::Torque(id), "value") => {
                Value::Vector(self.mechanism.effort(id).value.value().clone())
            }
            (Value::Force(id) | Value::Torque(id), _) => {
                Value::Body(self.mechanism.effort(id).basis)
            }
            (Value::Link(id), f) => self.link_field(id, f, field.span)?,
            (Value::Join(id), _) => self.join_coordinate(id, &field.name, field.span)?,
            _ => {
                return Err(internal(format!(
                    "field `{name}` of a value without fields"
                )))
            }
        })
    }

    fn join_coordinate(&mut self, id: JoinId, coordinate: &Name, span: Span) -> Result<Value> {
        if id.0 & CONTACT_JOIN != 0 {
            let name = self.mechanism.contact_name((id.0 & !CONTACT_JOIN) as usize);
            return Err(Diagnostic::error(
                "E0440",
                format!("`{name}` is a contact: it has no coordinate `{coordinate}`"),
            )
            .primary(span, "a contact has no coordinates")
            .help("a contact constrains the coordinates of the joints that place its bodies: read those (`motion.x`); its force is in the reactions (`lsdc simulate --reactions`)"));
        }
        if let Some(value) = self.own_coordinate(id, coordinate, span) {
            return Ok(value);
        }
        let join = self.mechanism.join(id);
        let coordinates = &self.mechanism.link(join.link).coordinates;
        match coordinates.iter().position(|c| c == coordinate) {
            Some(index) => Ok(Value::Scalar(Arc::new(SExpr::JoinCoordinate {
                join: id,
                index: index as u32,
                order: 0,
            }))),
            None => {
                let name = self.mechanism.join_name(id);
                Err(no_such_coordinate(
                    &name,
                    coordinates,
                    coordinate,
                    span,
                    join.span,
                ))
            }
        }
    }

    fn link_field(&self, id: LinkId, field: &str, span: Span) -> Result<Value> {
        let link = self.mechanism.link(id);
        let base = field.trim_end_matches(|c: char| c.is_ascii_digit());
        let index = field[base.len()..].parse::<usize>().unwrap_or(0);
        let missing = |what: String| {
            Diagnostic::error("E0602", format!("this link has no `{field}`"))
                .primary(span, what)
                .secondary(link.span, "the link is declared here")
        };
        if base == "dof" {
            if index == 0 {
                return Ok(Value::Displacement(
                    link.dofs
                        .iter()
                        .fold(Displacement::default(), |a, d| a.then(d)),
                ));
            }
            let count = link.dofs.len();
            return link
                .dofs
                .get(index - 1)
                .map(|d| Value::Displacement(d.clone()))
                .ok_or_else(|| {
                    missing(format!(
                        "its dof chain has {count} step{}",
                        if count == 1 { "" } else { "s" }
                    ))
                });
        }
        let list = if base == "force" {
            &link.forces
        } else {
            &link.torques
        };
        list.iter()
            .find(|(i, _)| *i as usize == index)
            .map(|(_, v)| Value::Vector(v.clone()))
            .ok_or_else(|| {
                missing(format!(
                    "the link declares no `{field}`; unknown link efforts are not values"
                ))
            })
    }

    fn call(
        &mut self,
        callee: &Callee,
        args: &[Arg],
        locals: &mut Locals,
        span: Span,
    ) -> Result<Value> {
        let values = args
            .iter()
            .map(|a| self.expr(&a.value, locals))
            .collect::<Result<Vec<_>>>()?;
        let (ident, target, index) = match callee {
            Callee::Unknown(ident) => {
                let id = self.new_unknown(UnknownKind::Function, Origin::Written, 0, ident.span);
                let scalars = values
                    .into_iter()
                    .map(|v| as_scalar(v, span))
                    .collect::<Result<Vec<_>>>()?;
                return Ok(Value::Scalar(Arc::new(SExpr::unknown_function(
                    id, scalars,
                ))));
            }
            Callee::Name(ident) => (ident, self.resolution(ident.span)?, None),
            Callee::Qualified(qualified) => (
                &qualified.name,
                self.resolution(qualified.name.span)?,
                qualified.index.as_ref(),
            ),
        };
        if target == Target::Builtin {
            let shape = match &*ident.name {
                "rolling" | "sliding" => Some(RoundShape::Sphere),
                "rolling_disc" | "sliding_disc" => Some(RoundShape::Disc),
                _ => None,
            };
            if let Some(shape) = shape {
                return self.contact_link(shape, values, span);
            }
            if ident.name == "state" {
                return self.new_state(values, span);
            }
            if ident.name == "sample" {
                return self.new_sampled_state(values, span);
            }
            let spans: Vec<Span> = args.iter().map(|a| a.value.span).collect();
            if ident.name == "aim" {
                return super::aim::aim(values, &spans, span);
            }
            if crate::check::types::reference_law(&ident.name).is_some() {
                return super::laws::law(&ident.name, values, &spans, span);
            }
            if super::model_laws::is_model_function(&ident.name) {
                return super::model_laws::model_call(&ident.name, values, &spans, span);
            }
            match &*ident.name {
                "derivative" => {
                    let value = values.into_iter().next();
                    let value = value.ok_or_else(|| internal("`derivative` without argument"))?;
                    return super::laws::derivative(value, spans[0], span);
                }
                "saturate" | "dead_zone" => {
                    let scalars = values
                        .into_iter()
                        .map(|v| as_scalar(v, span))
                        .collect::<Result<Vec<_>>>()?;
                    return Ok(Value::Scalar(match &*ident.name {
                        "saturate" => super::piecewise::saturate(&scalars, &spans)?,
                        _ => super::piecewise::dead_zone(&scalars, &spans)?,
                    }));
                }
                _ => {}
            }
            return builtin_call(&ident.name, values, span);
        }
        // The instance the definition was declared in: its body's names take their values there.
        let home = match (index, target) {
            (Some(index), Target::Global(scope)) => self.instance_at(scope, index, locals)?,
            _ => self.instances.current,
        };
        let Value::Definition(def) =
            self.within(home, |e| e.lookup(&ident.name, target, locals))?
        else {
            return Err(internal("call of a non-definition"));
        };
        let definition = &self.checked.definitions[def.0 as usize];
        self.with_decl(definition.scope, definition.decl, |elaborator, decl| {
            let DeclKind::Define(define) = &decl.kind else {
                return Err(internal("a definition without its declaration"));
            };
            elaborator.instantiate(define, args, values, home, span)
        })
    }

    /// The value of a definition's body with the arguments `values` (written as `args`), its
    /// names taking their values in the instance `home`.
    fn instantiate(
        &mut self,
        define: &DefineDecl,
        args: &[Arg],
        values: Vec<Value>,
        home: InstanceId,
        span: Span,
    ) -> Result<Value> {
        let (params, body, name) = (&define.params, &define.body, &define.name.name);
        let mut bound: Vec<Option<Value>> = vec![None; params.len()];
        for (position, (arg, value)) in args.iter().zip(values).enumerate() {
            let index = match &arg.name {
                None => position,
                Some(n) => params
                    .iter()
                    .position(|p| p.name.name == n.name)
                    .ok_or_else(|| internal("unknown parameter"))?,
            };
            *bound
                .get_mut(index)
                .ok_or_else(|| internal("too many arguments"))? = Some(value);
        }
        let mut frame: Locals = Vec::with_capacity(params.len());
        for (param, value) in params.iter().zip(bound) {
            frame.push((
                param.name.name,
                value.ok_or_else(|| internal(format!("missing argument for `{name}`")))?,
            ));
        }
        if self.depth >= MAX_DEPTH {
            return Err(Diagnostic::error(
                "E0414",
                format!("definitions nest more than {MAX_DEPTH} deep"),
            )
            .primary(span, format!("instantiating `{name}` here")));
        }
        self.depth += 1;
        let result = self.within(home, |e| e.expr(body, &mut frame));
        self.depth -= 1;
        result.map_err(|error| at_use(error, span, name))
    }

    fn construct(
        &mut self,
        kind: ConstructKind,
        params: &[Ident],
        fields: &[FieldInit],
        locals: &mut Locals,
        span: Span,
    ) -> Result<Value> {
        let depth = locals.len();
        for (index, param) in params.iter().enumerate() {
            locals.push((
                param.name,
                Value::Scalar(Arc::new(SExpr::Coordinate {
                    index: index as u32,
                    order: 0,
                })),
            ));
        }
        let mut values = Vec::with_capacity(fields.len());
        for field in fields {
            match self.expr(&field.value, locals) {
                Ok(v) => values.push((&*field.name.name, v, field.value.span)),
                Err(e) => {
                    locals.truncate(depth);
                    return Err(e);
                }
            }
        }
        locals.truncate(depth);
        match kind {
            ConstructKind::Body => self.body(values, span),
            ConstructKind::Link => self.link(params, fields, values, span),
            ConstructKind::Force | ConstructKind::Torque => self.effort(kind, values, span),
        }
    }

    fn body(&mut self, fields: Vec<(&str, Value, Span)>, span: Span) -> Result<Value> {
        let id = BodyId(self.mechanism.bodies.len() as u32);
        let (mut mass, mut iframe, mut inertia) = (None, None, None);
        let (mut mass_at, mut inertia_at) = (span, span);
        for (name, value, at) in fields {
            match name {
                "mass" => (mass, mass_at) = (Some(as_scalar(value, at)?), at),
                "iframe" => iframe = Some(as_displacement(value, at)?),
                "inertia" => (inertia, inertia_at) = (Some(as_vector(value, at)?), at),
                _ => return Err(internal(format!("body field `{name}`"))),
            }
        }
        let mass_value = mass.as_ref().and_then(constant);
        let moments = inertia
            .as_ref()
            .and_then(|v| Some([constant(&v[0])?, constant(&v[1])?, constant(&v[2])?]));
        if let Some(problem) = inertia_problem(mass_value, moments) {
            let at = if problem.about_mass {
                mass_at
            } else {
                inertia_at
            };
            return Err(Diagnostic::error("E0608", problem.message)
                .primary(at, "written here")
                .help(problem.help));
        }
        let mass = match mass {
            Some(m) => Quantity::Declared(m),
            None => Quantity::Generic(self.generic(|_| Origin::Mass(id), 0, span)),
        };
        let inertia = match inertia {
            Some(i) => Quantity::Declared(i),
            None => Quantity::Generic(self.generic_vector(|i| Origin::Inertia(id, i), span)),
        };
        let iframe = match iframe {
            Some(d) => Quantity::Declared(d),
            None => Quantity::Generic(self.generic_displacement(id, span)),
        };
        self.mechanism.bodies.push(Body {
            name: None,
            span,
            mass,
            iframe,
            inertia,
        });
        Ok(Value::Body(BodyRef::Body(id)))
    }

    /// An unspecified inertia frame: a translation, then rotations about x, y and z.
    fn generic_displacement(&mut self, body: BodyId, span: Span) -> Displacement {
        let origin = move |i| Origin::InertiaFrame(body, i);
        let translation = self.generic_vector(origin, span);
        let mut steps = vec![Elementary::Translation(translation)];
        for (i, axis) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .into_iter()
            .enumerate()
        {
            let angle = self.generic(origin, 3 + i as u8, span);
            steps.push(Elementary::Rotation {
                angle,
                axis: axis.map(num),
            });
        }
        Displacement(steps)
    }

    fn link(
        &mut self,
        params: &[Ident],
        written: &[FieldInit],
        fields: Vec<(&str, Value, Span)>,
        span: Span,
    ) -> Result<Value> {
        let coordinates = params.iter().map(|p| p.name).collect();
        let mut link = Link::new(span, coordinates);
        let mut dofs: Vec<(u8, Displacement)> = Vec::new();
        for (name, value, at) in fields {
            let base = name.trim_end_matches(|c: char| c.is_ascii_digit());
            let index = name[base.len()..].parse::<u8>().unwrap_or(0);
            match base {
                "dof" => dofs.push((index, as_displacement(value, at)?)),
                "force" => link.forces.push((index, as_vector(value, at)?)),
                "torque" => link.torques.push((index, as_vector(value, at)?)),
                "potential" => link.potential = Some(as_scalar(value, at)?),
                _ => extra_field(link.extras_mut(), name, value, at)?,
            }
        }
        dofs.sort_by_key(|(i, _)| *i);
        // Exact lengths: a chain has one link per body, and a list grown by pushing keeps
        // room for four.
        link.dofs = Vec::with_capacity(dofs.len());
        link.dofs.extend(dofs.into_iter().map(|(_, d)| d));
        link.forces.shrink_to_fit();
        link.torques.shrink_to_fit();
        coordinates_move(&link, params, written)?;
        self.mechanism.links.push(link);
        Ok(Value::Link(LinkId(self.mechanism.links.len() as u32 - 1)))
    }

    /// `rolling(radius)` or `sliding(radius, friction)`, or their disc's forms
    /// (`rolling_disc`, `sliding_disc`): a link without coordinates that makes its join a
    /// contact (see `mechanism::Contact`).
    fn contact_link(&mut self, shape: RoundShape, values: Vec<Value>, span: Span) -> Result<Value> {
        let mut scalars = values.into_iter().map(|v| as_scalar(v, span));
        let radius = scalars
            .next()
            .ok_or_else(|| internal("contact without a radius"))??;
        let friction = scalars.next().transpose()?;
        let mut link = Link::new(span, Vec::new());
        link.extras_mut().contact = Some(ContactLaw {
            radius,
            shape,
            friction,
            span,
        });
        self.mechanism.links.push(link);
        Ok(Value::Link(LinkId(self.mechanism.links.len() as u32 - 1)))
    }

    /// The reaction of an effort: its value negated, same basis. The element's potential is
    /// counted once, with the effort itself: the reaction's is 0 when the effort declares one.
    fn opposite(&mut self, id: EffortId) -> EffortId {
        let effort = self.mechanism.effort(id).clone();
        let value = effort.value.value().clone().map(|s| negate(&s));
        let potential = effort.potential.as_ref().map(|_| num(0.0));
        let opposite = Effort {
            value: Quantity::Declared(value),
            potential,
            ..effort
        };
        self.mechanism.efforts.push(opposite);
        EffortId(self.mechanism.efforts.len() as u32 - 1)
    }

    fn effort(
        &mut self,
        kind: ConstructKind,
        fields: Vec<(&str, Value, Span)>,
        span: Span,
    ) -> Result<Value> {
        let id = EffortId(self.mechanism.efforts.len() as u32);
        let effort_kind = if kind == ConstructKind::Force {
            EffortKind::Force
        } else {
            EffortKind::Torque
        };
        let (mut value, mut basis, mut potential, mut field) = (None, BodyRef::Earth, None, None);
        for (name, field_value, at) in fields {
            match (name, field_value) {
                ("value", v) => value = Some(as_vector(v, at)?),
                ("field", v) => field = Some(as_vector(v, at)?),
                ("potential", v) => potential = Some(as_scalar(v, at)?),
                ("body", Value::Body(b)) => basis = b,
                _ => return Err(internal(format!("effort field `{name}`"))),
            }
        }
        let value = match value {
            Some(v) => Quantity::Declared(v),
            None => Quantity::Generic(self.generic_vector(|i| Origin::EffortValue(id, i), span)),
        };
        // A field's own value is zero: `apply F` gives each body its weight instead.
        let value = if field.is_some() {
            Quantity::Declared(zero_vector())
        } else {
            value
        };
        self.mechanism.efforts.push(Effort {
            kind: effort_kind,
            name: None,
            span,
            value,
            basis,
            potential,
            field,
        });
        Ok(if effort_kind == EffortKind::Force {
            Value::Force(id)
        } else {
            Value::Torque(id)
        })
    }
}

/// E0610: a coordinate that the dof chain mentions as written but that its value does not
/// depend on (`q * [0, 0, 0]`, `0 * q || axis`): it would move nothing, and its mass matrix
/// would be singular. A coordinate the dof does not mention at all is the checker's W0401.
fn coordinates_move(link: &Link, params: &[Ident], written: &[FieldInit]) -> Result<()> {
    for (index, param) in params.iter().enumerate() {
        let moves = link.dofs.iter().any(|d| d.uses_coordinate(index as u32));
        if moves || !crate::check::dof_mentions(written, &param.name) {
            continue;
        }
        return Err(Diagnostic::error(
            "E0610",
            format!("coordinate `{}` moves nothing", param.name),
        )
        .primary(param.span, "the dof's value does not depend on it")
        .help(
            "a translation `q * axis` needs a non-zero axis, a rotation `k * q || axis` a non-zero \
             factor: check the values the dof is built from",
        ));
    }
    Ok(())
}

/// An error met inside a definition, with the place it was used (`revolute([0, 0, 0])` for a
/// zero axis inside `revolute`), as the checker shows them. The nesting limit E0414 already
/// points at the call that reached it, and would otherwise list all 64 of them.
fn at_use(error: Diagnostic, span: Span, name: &impl std::fmt::Display) -> Diagnostic {
    match error.code {
        "E0414" => error,
        _ => error.secondary(span, format!("in this use of `{name}`")),
    }
}

/// E0603: `crank.x` when the link of `crank` has no coordinate `x`.
pub(super) fn no_such_coordinate(
    join: &str,
    coordinates: &[Name],
    coordinate: &str,
    span: Span,
    join_span: Span,
) -> Diagnostic {
    let listed: Vec<String> = coordinates.iter().map(|c| format!("`{c}`")).collect();
    let help =
        match crate::diag::suggest::did_you_mean(coordinate, coordinates.iter().map(|c| &**c)) {
            Some(s) => format!("did you mean `{join}.{s}`?"),
            None if listed.is_empty() => format!("`{join}` is a weld: it has no coordinates"),
            None => format!("the coordinates of `{join}` are {}", listed.join(", ")),
        };
    Diagnostic::error(
        "E0603",
        format!("join `{join}` has no coordinate `{coordinate}`"),
    )
    .primary(span, "not a coordinate of this join's link")
    .secondary(join_span, "the join")
    .help(help)
}

/// A field of a link that few links write (see [`LinkExtras`]).
fn extra_field(extras: &mut LinkExtras, name: &str, value: Value, at: Span) -> Result<()> {
    match name {
        "lower" => extras.stops.lower = Some(as_scalar(value, at)?),
        "upper" => extras.stops.upper = Some(as_scalar(value, at)?),
        "restitution" => extras.stops.restitution = Some(as_scalar(value, at)?),
        "rotor_inertia" => extras.rotor.inertia = Some(as_scalar(value, at)?),
        "gear_ratio" => extras.rotor.ratio = Some(as_scalar(value, at)?),
        "rotor_axis" => extras.rotor.axis = Some(as_vector(value, at)?),
        "mimic" => extras.mimic.leader = Some((as_join(value, at)?, at)),
        "mimic_multiplier" => extras.mimic.multiplier = Some(as_scalar(value, at)?),
        "mimic_offset" => extras.mimic.offset = Some(as_scalar(value, at)?),
        "friction" => extras.friction.dry = Some(as_scalar(value, at)?),
        "damping" => extras.friction.viscous = Some(as_scalar(value, at)?),
        _ => return Err(internal(format!("link field `{name}`"))),
    }
    Ok(())
}
