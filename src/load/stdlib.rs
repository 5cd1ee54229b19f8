//! The standard library, embedded in the binary so `import joints;` works from any directory.

const MODULES: &[(&str, &str)] = &[
    ("forces", include_str!("../../stdlib/forces.lsd")),
    ("motors", include_str!("../../stdlib/motors.lsd")),
    ("gravity", include_str!("../../stdlib/gravity.lsd")),
    ("joints", include_str!("../../stdlib/joints.lsd")),
];

/// The embedded module called `name`, with its name as a `'static` string.
pub fn find(name: &str) -> Option<(&'static str, &'static str)> {
    MODULES.iter().find(|(n, _)| *n == name).copied()
}

pub fn names() -> impl Iterator<Item = &'static str> {
    MODULES.iter().map(|(n, _)| *n)
}

/// The standard library module that declares `name` at its top level, for the help of an
/// unknown name (`revolute` without `import joints`).
pub fn module_declaring(name: &str) -> Option<&'static str> {
    use crate::syntax::ast::DeclKind;
    MODULES.iter().find_map(|(module, text)| {
        let (program, _) = crate::syntax::parser::parse(crate::source::FileId(0), text);
        let declares = program.decls.iter().any(|decl| match &decl.kind {
            DeclKind::Let(bindings) => bindings.iter().any(|b| &*b.name.name == name),
            DeclKind::Define(define) => &*define.name.name == name,
            _ => false,
        });
        declares.then_some(*module)
    })
}
