//! The abstract syntax of LSD, with a span on every node. Boxed values and lists are
//! [`Node`]s and [`Nodes`]: as `Box` and `Box<[T]>`, carved from the chunks of
//! [`syntax::arena`](crate::syntax::arena) so that a freed tree gives its memory back.

use rustc_hash::FxHashMap;

use crate::source::Span;
pub use crate::syntax::arena::{Node, Nodes};
pub use crate::syntax::symbol::Symbol;

/// Identifiers are 4-byte symbols (`Copy`): the checker and elaborator copy names freely.
pub type Name = Symbol;

/// The names met while parsing one file: each spelling is looked up in the process's table
/// once per file, and its other occurrences found here without taking that table's lock.
#[derive(Default)]
pub struct Names(FxHashMap<&'static str, Name>);

impl Names {
    pub fn intern(&mut self, text: &str) -> Name {
        if let Some(&name) = self.0.get(text) {
            return name;
        }
        let name = Symbol::intern(text);
        self.0.insert(name.as_str(), name);
        name
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    pub name: Name,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    pub decls: Vec<Decl>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Decl {
    pub kind: DeclKind,
    pub span: Span,
}

/// A declaration. Its larger variants are boxed so that a declaration takes little room in the
/// program's list (from 384 bytes to 32; a generated chain has three declarations per body),
/// and its lists are boxed slices, at their exact length (a `let`'s single binding took room
/// for four in the list it was pushed into).
#[derive(Clone, Debug, PartialEq)]
pub enum DeclKind {
    /// `let a = e and b = e`
    Let(Nodes<Binding>),
    /// `let f(a, b : vector) = e`: a parameterised definition.
    Define(Node<DefineDecl>),
    /// `join <frame> and <frame> with <link> [as <name>]`
    Join(Node<JoinDecl>),
    /// `initial crank.q = 0.3 fixed, crank.q' = 1`: starting values of joint coordinates.
    Initial(Nodes<InitialValue>),
    /// `given L = 0.8, arm.mass = 2`: values of unknowns and generic quantities for simulation.
    Given(Nodes<GivenValue>),
    /// `drive crank.q = 2 * pi * time`: a join's coordinate imposed as a law of time.
    Drive(Node<DriveDecl>),
    /// `simulate duration = 10, integrator = dopri5 end`: how to simulate.
    Simulate(Nodes<FieldInit>),
    /// `output tip = position(arm.tip)`: a named quantity of the state, written by `simulate`
    /// at every output.
    Output(Node<OutputDecl>),
    /// `apply E on T`; `apply E between R and T`: E on T and its opposite on R (`reaction`);
    /// `apply F` for a force with a `field`: on every body with mass (a uniform field).
    Apply(Node<ApplyDecl>),
    /// `apply only weight, arm[1]`; `apply without damping`: in a scene, the applied efforts
    /// its study keeps (`load::scene` takes them out of the program).
    SelectEfforts(Node<EffortSelection>),
    /// `package P = decls end`
    Package(Node<PackageDecl>),
    /// `scene name = decls end`: a study of the program with its own settings, values, drives,
    /// locks, efforts and outputs (`load::scene` selects one).
    Scene(Node<SceneDecl>),
    /// `import joints`, `import "lib/robot.lsd"`, optionally `as P`
    Import(Node<ImportDecl>),
    /// A declaration the parser could not read; its error was already reported.
    Error,
}

/// `let name(params) = body`
#[derive(Clone, Debug, PartialEq)]
pub struct DefineDecl {
    pub name: Ident,
    pub params: Vec<Param>,
    pub body: Expr,
}

/// `package name = decls end`, or an array of packages `package name[i in a .. b] = decls end`:
/// one instance of the declarations for each integer `i` from `a` to `b`.
#[derive(Clone, Debug, PartialEq)]
pub struct PackageDecl {
    pub name: Ident,
    pub index: Option<PackageIndex>,
    pub decls: Vec<Decl>,
}

/// `scene name = decls end`: the declarations one study adds to the program's own.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDecl {
    pub name: Ident,
    pub decls: Vec<Decl>,
}

/// `[i in first .. last]`: the index of an array of packages and its range, both ends included.
#[derive(Clone, Debug, PartialEq)]
pub struct PackageIndex {
    pub variable: Ident,
    pub first: Expr,
    pub last: Expr,
}

/// `drive target = law`: `word` is `drive` in a well-formed program (the parser reads any
/// word there, so that a join may still be called `drive`; the checker refuses others).
#[derive(Clone, Debug, PartialEq)]
pub struct DriveDecl {
    pub word: Ident,
    pub target: Expr,
    pub value: Expr,
}

impl DriveDecl {
    /// The frame `F` of a position drive, `drive position(F) = law`; `None` for a drive of a
    /// coordinate (`drive crank.q = law`).
    pub fn position_target(&self) -> Option<&Expr> {
        let ExprKind::Call(call) = &self.target.kind else {
            return None;
        };
        match (&call.callee, &call.args[..]) {
            (Callee::Name(name), [frame])
                if name.name.as_str() == "position" && frame.name.is_none() =>
            {
                Some(&frame.value)
            }
            _ => None,
        }
    }

    /// The name a value input declares, `input voltage = 0` (a bare name after the word
    /// `input`); `None` for any other declaration, an effort input `input swing.q = 0` among
    /// them.
    pub fn value_input_name(&self) -> Option<Ident> {
        match (&self.target.kind, self.word.name.as_str()) {
            (ExprKind::Name(name), "input") => Some(Ident {
                name: *name,
                span: self.target.span,
            }),
            _ => None,
        }
    }
}

/// `join first and second with link [as name]`
#[derive(Clone, Debug, PartialEq)]
pub struct JoinDecl {
    pub first: Expr,
    pub second: Expr,
    pub link: Expr,
    pub name: Option<Ident>,
}

/// `output name = value`: a scalar, vector or matrix expression of the state, or a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputDecl {
    pub name: Ident,
    pub value: Expr,
}

/// `apply effort on target`; `apply effort between reaction and target`; `apply effort`.
#[derive(Clone, Debug, PartialEq)]
pub struct ApplyDecl {
    pub effort: Expr,
    pub target: Option<Expr>,
    pub reaction: Option<Expr>,
}

/// `apply only names` or `apply without names` (`word`): the applied efforts a scene keeps,
/// named by an effort's name, the definition that makes it, or a group that declares it.
#[derive(Clone, Debug, PartialEq)]
pub struct EffortSelection {
    pub word: Ident,
    pub names: Vec<SelectedName>,
}

/// A name of an effort selection as written (`arm[1]:push`), with where it is written.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectedName {
    pub path: String,
    pub span: Span,
}

/// `import target [as alias]`
#[derive(Clone, Debug, PartialEq)]
pub struct ImportDecl {
    pub target: ImportTarget,
    pub alias: Option<Ident>,
}

/// `package:name`, or `package[index]:name` in an array of packages.
#[derive(Clone, Debug, PartialEq)]
pub struct QualifiedName {
    pub package: Ident,
    pub index: Option<Expr>,
    pub name: Ident,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ImportTarget {
    /// `import joints`: `joints.lsd` on the search path, then in the standard library.
    Module(Ident),
    /// `import "path/file.lsd"`: relative to the importing file, then the search path.
    Path { path: String, span: Span },
}

#[derive(Clone, Debug, PartialEq)]
pub struct InitialValue {
    /// `join.coordinate`, possibly primed.
    pub target: Expr,
    pub value: Expr,
    /// `fixed`: held at this value when the mechanism is assembled.
    pub fixed: bool,
    /// `guess`: only a starting point for assembly, moved freely and silently.
    pub guess: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct GivenValue {
    /// An unknown (`L` bound by `let L = ?s;`) or a generic quantity (`arm.mass`, `arm.inertia`).
    pub target: Expr,
    pub value: Expr,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Binding {
    pub name: Ident,
    pub value: Expr,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    pub name: Ident,
    /// `a : vector`: an optional declared type, checked when the definition is used.
    pub ty: Option<Ident>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

impl Expr {
    /// A name or a chain of fields as written (`nacelle`, `leg.tip`), for naming what it
    /// designates; `None` for any other expression.
    pub fn as_path(&self) -> Option<String> {
        match &self.kind {
            ExprKind::Name(name) => Some(name.as_str().to_string()),
            ExprKind::Field(access) => Some(format!(
                "{}.{}",
                access.target.as_path()?,
                access.field.name.as_str()
            )),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinaryOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    /// `angle || axis`: a rotation.
    Rotation,
    /// `translation ++ rotation`: a displacement.
    Displacement,
    /// `displacement @ body`: a frame.
    Frame,
}

impl BinaryOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinaryOp::Add => "+",
            BinaryOp::Sub => "-",
            BinaryOp::Mul => "*",
            BinaryOp::Div => "/",
            BinaryOp::Pow => "^",
            BinaryOp::Rotation => "||",
            BinaryOp::Displacement => "++",
            BinaryOp::Frame => "@",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConstructKind {
    Body,
    Link,
    Force,
    Torque,
}

impl ConstructKind {
    pub fn keyword(self) -> &'static str {
        match self {
            ConstructKind::Body => "body",
            ConstructKind::Link => "link",
            ConstructKind::Force => "force",
            ConstructKind::Torque => "torque",
        }
    }
}

/// `target.field`
#[derive(Clone, Debug, PartialEq)]
pub struct FieldAccess {
    pub target: Expr,
    pub field: Ident,
}

#[derive(Clone, Debug, PartialEq)]
pub struct FieldInit {
    pub name: Ident,
    pub value: Expr,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Arg {
    /// `f(axis = [1,0,0])`: named arguments; positional ones have `None`.
    pub name: Option<Ident>,
    pub value: Expr,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Callee {
    Name(Ident),
    /// `P:f(...)`, `P[k]:f(...)`; boxed, so that a call's callee is the size of a name.
    Qualified(Node<QualifiedName>),
    /// `?fs(x, x')`: an unknown function.
    Unknown(Ident),
}

/// `body ... end`, `link(x) ... end`, `force ... end`, `torque ... end`
#[derive(Clone, Debug, PartialEq)]
pub struct Construct {
    pub kind: ConstructKind,
    pub params: Nodes<Ident>,
    pub fields: Nodes<FieldInit>,
}

/// `callee(args)`
#[derive(Clone, Debug, PartialEq)]
pub struct CallExpr {
    pub callee: Callee,
    pub args: Nodes<Arg>,
}

/// `lhs op rhs`: both operands in one box with the operator.
#[derive(Clone, Debug, PartialEq)]
pub struct BinaryExpr {
    pub op: BinaryOp,
    pub lhs: Expr,
    pub rhs: Expr,
}

/// `local a = e and b = e in body end`
#[derive(Clone, Debug, PartialEq)]
pub struct LocalExpr {
    pub bindings: Nodes<Binding>,
    pub body: Expr,
}

/// The kind of an expression. A name's span is its expression's, and every variant holds at
/// most 8 bytes (a call, a binary operation, a `local` and a constructor are boxed whole, and a
/// vector literal's elements), so that the kind is 16 bytes and an expression with its 8-byte span
/// 24: a generated chain holds some forty per body, inline in lists or boxed (24 bytes of a
/// chunk, see `syntax::arena`).
#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    Name(Name),
    /// `P:X`
    Qualified(Node<QualifiedName>),
    /// `e.field`, boxed whole so that a name does not make every expression larger.
    Field(Node<FieldAccess>),
    /// `?s`: a fresh unknown scalar at each occurrence.
    Unknown(Name),
    Int(i64),
    Float(f64),
    /// `[a, b, c]` (a vector) or `[[..], [..], [..]]` (a matrix, by rows).
    Vector(VectorLiteral),
    Call(Node<CallExpr>),
    Binary(Node<BinaryExpr>),
    Neg(Node<Expr>),
    /// `x'`: the time derivative of a joint coordinate.
    Prime(Node<Expr>),
    /// `body ... end`, `link(x) ... end`, `force ... end`, `torque ... end`
    Construct(Node<Construct>),
    /// `local a = e and b = e in body end`
    Local(Node<LocalExpr>),
    /// An expression the parser could not read.
    Error,
}

/// The elements of a vector literal, read as a slice. Vectors and matrices have three elements
/// (or rows), so three elements are one block of their own size; a literal of another length
/// (an error the checker reports) is a slice, boxed again so that its length is not in every
/// expression. Either form fits in eight bytes beside the expression's own tag.
#[derive(Clone, PartialEq)]
pub enum VectorLiteral {
    Three(Node<[Expr; 3]>),
    Other(Node<Nodes<Expr>>),
}

impl VectorLiteral {
    pub fn new(elements: Vec<Expr>) -> VectorLiteral {
        match <[Expr; 3]>::try_from(elements) {
            Ok(three) => VectorLiteral::Three(Node::new(three)),
            Err(other) => VectorLiteral::Other(Node::new(Nodes::from(other))),
        }
    }

    pub fn into_vec(self) -> Vec<Expr> {
        match self {
            VectorLiteral::Three(three) => Vec::from(three.into_inner()),
            VectorLiteral::Other(other) => other.into_inner().into_vec(),
        }
    }
}

impl std::ops::Deref for VectorLiteral {
    type Target = [Expr];

    fn deref(&self) -> &[Expr] {
        match self {
            VectorLiteral::Three(three) => &three[..],
            VectorLiteral::Other(other) => other,
        }
    }
}

/// Printed as the list of its elements, whichever its form.
impl std::fmt::Debug for VectorLiteral {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// Builds a binary expression node (used by the grammar's actions).
pub fn binary(
    file: crate::source::FileId,
    start: usize,
    end: usize,
    op: BinaryOp,
    lhs: Expr,
    rhs: Expr,
) -> Expr {
    Expr {
        kind: ExprKind::Binary(Node::new(BinaryExpr { op, lhs, rhs })),
        span: Span::new(file, start, end),
    }
}
