//! What the editor support knows about a file and the libraries it imports: every definition
//! (declarations, parameters, link coordinates, `local` bindings, modules) and every occurrence
//! of a name with what it refers to, built from the checker's name resolutions. Hover, go to
//! definition, references, rename, completion and semantic tokens all read this index.

use rustc_hash::FxHashMap;

use crate::check::scope::Target;
use crate::check::types::{ScopeId, Ty};
use crate::check::Checked;
use crate::driver::{self, Compilation};
use crate::elab::Mechanism;
use crate::load::{LoadOptions, Workspace};
use crate::source::{FileId, Span};
use crate::syntax::ast::{
    Arg, Callee, Decl, DeclKind, Expr, ExprKind, FieldInit, Ident, ImportTarget, LocalExpr, Name,
};
use crate::syntax::lexer::comments_in_gap;

/// A file compiled as the command line compiles it, with its index of names.
pub struct Analysis {
    pub compilation: Compilation,
    /// The file being edited (the compilation's root).
    pub root: FileId,
    pub index: Index,
}

impl Analysis {
    /// Compiles `text`, the contents of the file at `path` (its relative imports are looked up
    /// beside it), and indexes its names.
    pub fn new(path: &std::path::Path, text: &str, options: &LoadOptions) -> Analysis {
        let dir = path.parent();
        let name = path.display().to_string();
        let (compilation, index) =
            driver::compile_text_inspected(&name, text, dir, options, Index::build);
        let root = compilation
            .workspace
            .module(compilation.workspace.roots[0])
            .file;
        Analysis {
            compilation,
            root,
            index,
        }
    }

    pub fn text(&self, file: FileId) -> &str {
        &self.compilation.workspace.sources.file(file).text
    }

    pub fn mechanism(&self) -> Option<&Mechanism> {
        self.compilation.mechanism.as_ref()
    }
}

/// What a name is.
#[derive(Clone, Debug, PartialEq)]
pub enum DefinitionKind {
    /// `let x = e`
    Value,
    /// `let f(a, b) = e`, with its parameters (indices of their definitions).
    Function {
        parameters: Vec<usize>,
    },
    /// `package P = ... end`, with its scope.
    Package(Option<ScopeId>),
    /// A module (a library file), named by an import.
    Module(Option<ScopeId>),
    /// `join ... as crank`
    Join,
    Parameter,
    /// A link's joint coordinate: `link(x) ... end`.
    Coordinate,
    /// `local a = e in ... end`
    Local,
    /// `input voltage = 12`: a value set from outside the program (`--set`,
    /// `Simulator::set_input`, an FMI unit's input), holding its start value until set.
    Input,
}

#[derive(Clone, Debug)]
pub struct Definition {
    pub name: Name,
    /// The defining name (a module: the start of its file).
    pub span: Span,
    pub kind: DefinitionKind,
    pub ty: Option<Ty>,
    /// The whole declaration (a module: its first line).
    pub declaration: Span,
    /// The comment just before the declaration, without its `(*` and `*)`.
    pub doc: Option<String>,
}

impl Definition {
    /// Whether the name is only visible inside a definition, a link or a `local`.
    pub fn is_local(&self) -> bool {
        matches!(
            self.kind,
            DefinitionKind::Parameter | DefinitionKind::Coordinate | DefinitionKind::Local
        )
    }
}

/// What an occurrence of a name refers to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reference {
    Definition(usize),
    /// `pi`, `earth`, `sin`, …
    Builtin,
    /// A field: `b.mass`, `body mass = 1 end`.
    Field,
    /// A name the checker could not resolve (its error is reported).
    Unresolved,
}

#[derive(Clone, Copy, Debug)]
pub struct Occurrence {
    pub span: Span,
    pub reference: Reference,
}

#[derive(Default)]
pub struct Index {
    pub definitions: Vec<Definition>,
    /// In the order of the files, then of the text.
    pub occurrences: Vec<Occurrence>,
    /// The names the root file's top level sees: its own declarations, then those of the
    /// modules it imports (for completion).
    pub visible: Vec<usize>,
    /// The names of each package and module scope.
    pub scope_members: FxHashMap<ScopeId, Vec<usize>>,
    /// The values of the numeric constants, by the span of their name (when the program has
    /// no errors).
    pub values: FxHashMap<Span, String>,
}

impl Index {
    /// The occurrence of a name at a byte offset of a file.
    pub fn occurrence_at(&self, file: FileId, offset: usize) -> Option<&Occurrence> {
        self.occurrences.iter().find(|o| {
            o.span.file() == file
                && o.span.start() as usize <= offset
                && offset <= o.span.end() as usize
        })
    }

    /// Every occurrence referring to a definition, the defining name included.
    pub fn references(&self, definition: usize) -> impl Iterator<Item = &Occurrence> {
        self.occurrences
            .iter()
            .filter(move |o| o.reference == Reference::Definition(definition))
    }

    /// A visible definition of the root file by name.
    pub fn visible_named(&self, name: &str) -> Option<&Definition> {
        self.visible
            .iter()
            .map(|&d| &self.definitions[d])
            .find(|d| &*d.name == name)
    }

    fn build(workspace: &Workspace, checked: &Checked, mechanism: Option<&Mechanism>) -> Index {
        let values = match mechanism {
            Some(_) => crate::elab::constant_values(workspace, checked),
            None => FxHashMap::default(),
        };
        let mut builder = Builder {
            workspace,
            checked,
            index: Index {
                values,
                ..Index::default()
            },
            by_span: FxHashMap::default(),
        };
        builder.modules();
        for module in &workspace.modules {
            builder.scope_declarations(&module.program.decls, module.file, 0);
        }
        for module in &workspace.modules {
            builder.declarations(&module.program.decls);
        }
        builder.visible_names();
        builder
            .index
            .occurrences
            .sort_by_key(|o| (o.span.file(), o.span.start()));
        builder.index
    }
}

struct Builder<'a> {
    workspace: &'a Workspace,
    checked: &'a Checked,
    index: Index,
    /// Definitions by the span the checker's scopes record for them.
    by_span: FxHashMap<Span, usize>,
}

impl Builder<'_> {
    fn define(&mut self, definition: Definition) -> usize {
        let id = self.index.definitions.len();
        self.index.occurrences.push(Occurrence {
            span: definition.span,
            reference: Reference::Definition(id),
        });
        self.by_span.insert(definition.span, id);
        self.index.definitions.push(definition);
        id
    }

    /// One definition per module; each import names it.
    fn modules(&mut self) {
        for (id, module) in self.workspace.modules.iter().enumerate() {
            let text = &self.workspace.sources.file(module.file).text;
            let first_line = text.find('\n').unwrap_or(text.len());
            let scope = self
                .checked
                .module_scopes
                .get(&crate::load::ModuleId(id as u32))
                .copied();
            self.index.definitions.push(Definition {
                name: module.name.as_str().into(),
                span: Span::new(module.file, 0, 0),
                kind: DefinitionKind::Module(scope),
                ty: None,
                declaration: Span::new(module.file, 0, first_line),
                doc: leading_comment(text, first_comment_end(text)),
            });
        }
    }

    /// The declarations of a file or package: names, parameters' definitions (their bodies are
    /// walked later), packages' contents.
    fn scope_declarations(&mut self, decls: &[Decl], file: FileId, start: usize) {
        let text = &self.workspace.sources.file(file).text;
        let mut previous_end = start;
        for decl in decls {
            let doc = leading_comment(
                &text[previous_end..],
                decl.span.start() as usize - previous_end,
            );
            previous_end = decl.span.end() as usize;
            let declare = |builder: &mut Self, name: &Ident, kind: DefinitionKind| {
                let ty = builder.declared_type(name);
                builder.define(Definition {
                    name: name.name,
                    span: name.span,
                    kind,
                    ty,
                    declaration: decl.span,
                    doc: doc.clone(),
                })
            };
            match &decl.kind {
                DeclKind::Let(bindings) => {
                    for binding in bindings {
                        declare(self, &binding.name, DefinitionKind::Value);
                    }
                }
                DeclKind::Define(define) => {
                    let parameters = define
                        .params
                        .iter()
                        .map(|p| {
                            let ty = p.ty.as_ref().and_then(|t| Ty::from_annotation(&t.name));
                            self.local(&p.name, DefinitionKind::Parameter, ty, decl.span)
                        })
                        .collect();
                    declare(self, &define.name, DefinitionKind::Function { parameters });
                }
                DeclKind::Join(join) => {
                    if let Some(name) = &join.name {
                        declare(self, name, DefinitionKind::Join);
                    }
                }
                DeclKind::Package(package) => {
                    let scope = self.checked.package_scopes.get(&decl.span).copied();
                    declare(self, &package.name, DefinitionKind::Package(scope));
                    if let Some(index) = &package.index {
                        declare(self, &index.variable, DefinitionKind::Value);
                    }
                    let start = package.name.span.end() as usize;
                    self.scope_declarations(&package.decls, file, start);
                }
                DeclKind::Import(import) => self.import(decl.span, &import.target),
                DeclKind::Drive(drive) => {
                    if let Some(name) = drive.value_input_name() {
                        declare(self, &name, DefinitionKind::Input);
                    }
                }
                _ => {}
            }
        }
    }

    /// The type the checker gave a declared name, found in the scope that holds it.
    fn declared_type(&self, name: &Ident) -> Option<Ty> {
        self.checked
            .scopes
            .iter()
            .filter_map(|scope| scope.names.get(&name.name))
            .find(|entry| entry.span == name.span)
            .map(|entry| entry.ty)
    }

    /// `import joints`: the module's name refers to the module, and so do the names the
    /// checker declared for the import (the alias, or the import itself).
    fn import(&mut self, site: Span, target: &ImportTarget) {
        let Some(module) = self.workspace.imports.get(&site) else {
            return;
        };
        let definition = module.0 as usize;
        self.by_span.insert(site, definition);
        let span = match target {
            ImportTarget::Module(ident) => ident.span,
            ImportTarget::Path { span, .. } => *span,
        };
        self.index.occurrences.push(Occurrence {
            span,
            reference: Reference::Definition(definition),
        });
    }

    fn local(&mut self, name: &Ident, kind: DefinitionKind, ty: Option<Ty>, scope: Span) -> usize {
        self.define(Definition {
            name: name.name,
            span: name.span,
            kind,
            ty,
            declaration: scope,
            doc: None,
        })
    }

    /// The expressions of declarations: every name use.
    fn declarations(&mut self, decls: &[Decl]) {
        for decl in decls {
            let mut locals = Vec::new();
            match &decl.kind {
                DeclKind::Let(bindings) => {
                    for binding in bindings {
                        self.expr(&binding.value, &mut locals);
                    }
                }
                DeclKind::Define(define) => {
                    for param in &define.params {
                        if let Some(&id) = self.by_span.get(&param.name.span) {
                            locals.push((param.name.name, id));
                        }
                        if let Some(ty) = &param.ty {
                            self.occurrence(ty.span, Reference::Builtin);
                        }
                    }
                    self.expr(&define.body, &mut locals);
                }
                DeclKind::Join(join) => {
                    for expr in [&join.first, &join.second, &join.link] {
                        self.expr(expr, &mut locals);
                    }
                }
                DeclKind::Initial(values) => {
                    for value in values {
                        self.expr(&value.target, &mut locals);
                        self.expr(&value.value, &mut locals);
                    }
                }
                DeclKind::Given(values) => {
                    for value in values {
                        self.expr(&value.target, &mut locals);
                        self.expr(&value.value, &mut locals);
                    }
                }
                DeclKind::Drive(drive) => {
                    // A value input's target is the name it declares, not a use of one.
                    if drive.value_input_name().is_none() {
                        self.expr(&drive.target, &mut locals);
                    }
                    self.expr(&drive.value, &mut locals);
                }
                DeclKind::Simulate(fields) => self.fields(fields, &mut locals),
                DeclKind::Output(output) => self.expr(&output.value, &mut locals),
                DeclKind::Apply(apply) => {
                    self.expr(&apply.effort, &mut locals);
                    for target in apply.target.iter().chain(&apply.reaction) {
                        self.expr(target, &mut locals);
                    }
                }
                DeclKind::Package(package) => {
                    if let Some(index) = &package.index {
                        self.expr(&index.first, &mut locals);
                        self.expr(&index.last, &mut locals);
                    }
                    self.declarations(&package.decls)
                }
                DeclKind::Import(_)
                | DeclKind::Scene(_)
                | DeclKind::SelectEfforts(_)
                | DeclKind::Error => {}
            }
        }
    }

    fn occurrence(&mut self, span: Span, reference: Reference) {
        self.index.occurrences.push(Occurrence { span, reference });
    }

    /// A name use, as the checker resolved it.
    fn name(&mut self, ident: &Ident, locals: &[(Name, usize)]) -> Reference {
        let reference = match self.checked.resolutions.get(ident.span) {
            Some(Target::Local) => locals
                .iter()
                .rev()
                .find(|(name, _)| *name == ident.name)
                .map_or(Reference::Unresolved, |&(_, id)| Reference::Definition(id)),
            Some(Target::Global(scope)) => self.global(scope, &ident.name),
            Some(Target::Builtin) => Reference::Builtin,
            None => Reference::Unresolved,
        };
        self.occurrence(ident.span, reference);
        reference
    }

    fn global(&self, scope: ScopeId, name: &str) -> Reference {
        self.checked
            .scope(scope)
            .names
            .get(name)
            .and_then(|entry| self.by_span.get(&entry.span))
            .map_or(Reference::Unresolved, |&id| Reference::Definition(id))
    }

    fn expr(&mut self, expr: &Expr, locals: &mut Vec<(Name, usize)>) {
        match &expr.kind {
            ExprKind::Name(name) => {
                let ident = Ident {
                    name: *name,
                    span: expr.span,
                };
                self.name(&ident, locals);
            }
            ExprKind::Qualified(qualified) => {
                self.name(&qualified.package, locals);
                if let Some(index) = &qualified.index {
                    self.expr(index, locals);
                }
                let reference = match self.checked.resolutions.get(expr.span) {
                    Some(Target::Global(scope)) => self.global(scope, &qualified.name.name),
                    _ => Reference::Unresolved,
                };
                self.occurrence(qualified.name.span, reference);
            }
            ExprKind::Field(access) => {
                self.expr(&access.target, locals);
                self.occurrence(access.field.span, Reference::Field);
            }
            ExprKind::Vector(elements) => {
                for element in elements.iter() {
                    self.expr(element, locals);
                }
            }
            ExprKind::Call(call) => self.call(&call.callee, &call.args, locals),
            ExprKind::Binary(binary) => {
                self.expr(&binary.lhs, locals);
                self.expr(&binary.rhs, locals);
            }
            ExprKind::Neg(inner) | ExprKind::Prime(inner) => self.expr(inner, locals),
            ExprKind::Construct(c) => {
                let depth = locals.len();
                for param in c.params.iter() {
                    let id = self.local(
                        param,
                        DefinitionKind::Coordinate,
                        Some(Ty::Scalar),
                        expr.span,
                    );
                    locals.push((param.name, id));
                }
                self.fields(&c.fields, locals);
                locals.truncate(depth);
            }
            ExprKind::Local(local) => {
                let LocalExpr { bindings, body } = &**local;
                for binding in bindings.iter() {
                    self.expr(&binding.value, locals);
                }
                let depth = locals.len();
                for binding in bindings.iter() {
                    let id = self.local(&binding.name, DefinitionKind::Local, None, expr.span);
                    locals.push((binding.name.name, id));
                }
                self.expr(body, locals);
                locals.truncate(depth);
            }
            ExprKind::Unknown(_) | ExprKind::Int(_) | ExprKind::Float(_) | ExprKind::Error => {}
        }
    }

    fn fields(&mut self, fields: &[FieldInit], locals: &mut Vec<(Name, usize)>) {
        for field in fields {
            self.occurrence(field.name.span, Reference::Field);
            self.expr(&field.value, locals);
        }
    }

    /// A call: the callee, then the arguments; a named argument refers to the parameter of
    /// that name.
    fn call(&mut self, callee: &Callee, args: &[Arg], locals: &mut Vec<(Name, usize)>) {
        let reference = match callee {
            Callee::Name(ident) => self.name(ident, locals),
            Callee::Qualified(qualified) => {
                self.name(&qualified.package, locals);
                if let Some(index) = &qualified.index {
                    self.expr(index, locals);
                }
                self.name(&qualified.name, locals)
            }
            Callee::Unknown(_) => Reference::Unresolved,
        };
        let parameters = match reference {
            Reference::Definition(id) => match &self.index.definitions[id].kind {
                DefinitionKind::Function { parameters } => parameters.clone(),
                _ => Vec::new(),
            },
            _ => Vec::new(),
        };
        for arg in args {
            if let Some(name) = &arg.name {
                let parameter = parameters
                    .iter()
                    .find(|&&p| self.index.definitions[p].name == name.name);
                let reference =
                    parameter.map_or(Reference::Unresolved, |&p| Reference::Definition(p));
                self.occurrence(name.span, reference);
            }
            self.expr(&arg.value, locals);
        }
    }

    /// The root file's declarations, then those of the modules it opens, and each scope's
    /// members.
    fn visible_names(&mut self) {
        for (index, scope) in self.checked.scopes.iter().enumerate() {
            let members = scope
                .order
                .iter()
                .filter_map(|name| scope.names.get(name))
                .filter_map(|entry| self.by_span.get(&entry.span).copied())
                .collect();
            self.index
                .scope_members
                .insert(ScopeId(index as u32), members);
        }
        let root = self.workspace.roots.first();
        let Some(&scope) = root.and_then(|root| self.checked.module_scopes.get(root)) else {
            return;
        };
        let mut visible = self.index.scope_members[&scope].clone();
        for (opened, _) in &self.checked.scope(scope).opened {
            visible.extend(&self.index.scope_members[opened]);
        }
        self.index.visible = visible;
    }
}

/// The end of a file's leading comment, if it starts with one.
fn first_comment_end(text: &str) -> usize {
    let trimmed = text.trim_start();
    match comments_in_gap(trimmed).first() {
        Some(comment) if comment.start == 0 => text.len() - trimmed.len() + comment.end,
        _ => 0,
    }
}

/// The comment that ends just before `position` of `text` (only spaces and at most one line
/// break between them), without its `(*` and `*)`: a declaration's documentation. `text` holds
/// no code before `position` but the end of the previous declaration (`;`, `=`).
fn leading_comment(text: &str, position: usize) -> Option<String> {
    let before = &text[..position];
    let comment = comments_in_gap(before).pop()?;
    let between = &before[comment.end..];
    if !between.trim().is_empty() || between.matches('\n').count() > 1 {
        return None;
    }
    let inner = &before[comment.start + 2..comment.end - 2];
    Some(dedent(inner.trim()))
}

/// Removes the indentation a comment's continuation lines share.
fn dedent(text: &str) -> String {
    let indent = text
        .lines()
        .skip(1)
        .filter(|line| !line.trim().is_empty())
        .map(|line| line.len() - line.trim_start().len())
        .min()
        .unwrap_or(0);
    let mut lines = text.lines();
    let mut out = lines.next().unwrap_or("").to_string();
    for line in lines {
        out.push('\n');
        out.push_str(line.get(indent..).unwrap_or(line.trim_start()));
    }
    out
}
