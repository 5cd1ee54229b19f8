//! The standard library, embedded in the binary so `import joints;` works from any directory.

const MODULES: &[(&str, &str)] = &[
    ("forces", include_str!("../../stdlib/forces.lsd")),
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
