//! Hover and go to definition (references and rename, across files: `across.rs`).

use lsp_types::{Hover, HoverContents, Location, MarkupContent, MarkupKind};

use crate::check::types::{builtin_constant, builtin_function, Ty};
use crate::ide::analysis::{Analysis, Definition, DefinitionKind, Occurrence, Reference};
use crate::ide::convert;

/// The longest declaration a hover shows, in lines.
const HOVER_LINES: usize = 8;

/// The name at a byte offset of the root file.
fn occurrence(analysis: &Analysis, offset: usize) -> Option<&Occurrence> {
    analysis.index.occurrence_at(analysis.root, offset)
}

fn definition_at(analysis: &Analysis, offset: usize) -> Option<(usize, &Definition)> {
    match occurrence(analysis, offset)?.reference {
        Reference::Definition(id) => Some((id, &analysis.index.definitions[id])),
        _ => None,
    }
}

pub fn definition(analysis: &Analysis, offset: usize) -> Option<Location> {
    let (_, definition) = definition_at(analysis, offset)?;
    Some(convert::location(analysis, definition.span))
}

pub fn hover(analysis: &Analysis, offset: usize) -> Option<Hover> {
    let occurrence = occurrence(analysis, offset)?;
    let name = &analysis.text(analysis.root)[occurrence.span.range()];
    let text = analysis.text(analysis.root);
    let value = match occurrence.reference {
        Reference::Definition(id) => definition_hover(
            analysis,
            &analysis.index.definitions[id],
            qualifier(&text[..occurrence.span.start() as usize]),
        ),
        Reference::Builtin => builtin_hover(name)?,
        Reference::Field | Reference::Unresolved => return None,
    };
    Some(Hover {
        contents: HoverContents::Markup(MarkupContent {
            kind: MarkupKind::Markdown,
            value,
        }),
        range: Some(convert::span_range(analysis, occurrence.span)),
    })
}

fn builtin_hover(name: &str) -> Option<String> {
    if let Some(ty) = builtin_constant(name) {
        return Some(format!("built-in constant `{name}`: {ty}"));
    }
    if let Some((params, result)) = builtin_function(name) {
        let params: Vec<String> = params.iter().map(Ty::to_string).collect();
        return Some(format!(
            "built-in function `{name}({}) : {result}`",
            params.join(", ")
        ));
    }
    if let Some(arguments) = crate::check::types::reference_law(name) {
        let rest = match arguments {
            crate::check::types::LawArguments::Between(extra) => ["t0", "q0", "t1", "q1"]
                .iter()
                .chain(extra)
                .copied()
                .collect::<Vec<_>>()
                .join(", "),
            crate::check::types::LawArguments::Through => "t0, q0, t1, q1, ...".to_string(),
        };
        return Some(format!(
            "built-in reference law `{name}(t, {rest})`: q scalars or vectors"
        ));
    }
    if name == "derivative" {
        return Some(
            "built-in function `derivative(law)`: the time derivative of a law of time".to_string(),
        );
    }
    Ty::from_annotation(name).map(|ty| format!("type `{ty}`"))
}

/// The instance path written before a name, from the text that precedes it: `leg[1]:` in
/// `leg[1]:knee`, `Arm:` in `Arm:sh`; empty for a name written alone.
fn qualifier(before: &str) -> &str {
    if !before.ends_with(':') {
        return "";
    }
    let path = |c: char| c.is_alphanumeric() || matches!(c, '_' | '[' | ']' | ':' | '\'');
    let start = before
        .char_indices()
        .rev()
        .take_while(|&(_, c)| path(c))
        .last()
        .map_or(before.len(), |(i, _)| i);
    &before[start..]
}

/// The declaration's source, what the name is, what the mechanism makes of it (for the
/// instance `qualifier` names, when it names one) and its documentation.
fn definition_hover(analysis: &Analysis, definition: &Definition, qualifier: &str) -> String {
    let mut parts = Vec::new();
    let source = &analysis.text(definition.declaration.file())[definition.declaration.range()];
    let mut lines: Vec<&str> = source.lines().take(HOVER_LINES).collect();
    if source.lines().count() > HOVER_LINES {
        lines.push("...");
    }
    if !definition.is_local() {
        parts.push(format!("```lsd\n{}\n```", lines.join("\n")));
    }
    parts.push(describe(analysis, definition));
    if let Some(facts) = mechanism_facts(analysis, definition, qualifier) {
        parts.push(facts);
    }
    if let Some(doc) = &definition.doc {
        parts.push(doc.clone());
    }
    parts.join("\n\n")
}

fn describe(analysis: &Analysis, definition: &Definition) -> String {
    let name = &definition.name;
    let typed = |what: &str| match definition.ty {
        Some(ty) if ty != Ty::Error => format!("{what} `{name}`: {ty}"),
        _ => format!("{what} `{name}`"),
    };
    match &definition.kind {
        DefinitionKind::Value => match analysis.index.values.get(&definition.span) {
            Some(value) => format!("{} = {value}", typed("value")),
            None => typed("value"),
        },
        DefinitionKind::Function { parameters } => {
            let names: Vec<String> = parameters
                .iter()
                .map(|&p| {
                    let parameter = &analysis.index.definitions[p];
                    match parameter.ty {
                        Some(ty) => format!("{} : {ty}", parameter.name),
                        None => parameter.name.to_string(),
                    }
                })
                .collect();
            format!("parameterised definition `{name}({})`", names.join(", "))
        }
        DefinitionKind::Package(_) => format!("package `{name}`"),
        DefinitionKind::Module(_) => {
            let file = &analysis
                .compilation
                .workspace
                .sources
                .file(definition.span.file());
            format!("library `{name}` ({})", file.name)
        }
        DefinitionKind::Join => format!("named join `{name}`"),
        DefinitionKind::Parameter => typed("parameter"),
        DefinitionKind::Coordinate => format!("joint coordinate `{name}` (a scalar of time)"),
        DefinitionKind::Local => typed("local binding"),
        DefinitionKind::Input => format!(
            "input `{name}`: a scalar that holds its start value until set from outside the \
             program (`--set {name}=VALUE`, `Simulator::set_input`, an FMI unit's input)"
        ),
    }
}

/// A body's mass properties, a join's coordinates: from the elaborated mechanism, when the
/// program has no errors. A join declared in an array of packages has one instance per element
/// (`leg[1]:knee`, `leg[2]:knee`): the one `qualifier` names, or all of them.
fn mechanism_facts(
    analysis: &Analysis,
    definition: &Definition,
    qualifier: &str,
) -> Option<String> {
    let mechanism = analysis.mechanism()?;
    let inside = |span: crate::source::Span| {
        let declaration = definition.declaration;
        span.file() == declaration.file()
            && declaration.start() <= span.start()
            && span.end() <= declaration.end()
    };
    let named = |name: &Option<crate::syntax::ast::Name>| name.as_ref() == Some(&definition.name);
    match (&definition.kind, definition.ty) {
        (DefinitionKind::Value, Some(Ty::Body)) => {
            let body = mechanism
                .bodies
                .iter()
                .find(|b| named(&b.name) && inside(b.span))?;
            let quantity = |declared: bool, value: String| {
                if declared {
                    value
                } else {
                    format!("generic ({value})")
                }
            };
            let inertia = body.inertia.value();
            Some(format!(
                "mass: {}  \nprincipal moments of inertia: {}  \ninertia frame: {}",
                quantity(body.mass.is_declared(), body.mass.value().to_string()),
                quantity(
                    body.inertia.is_declared(),
                    format!("[{}, {}, {}]", inertia[0], inertia[1], inertia[2])
                ),
                if body.iframe.is_declared() {
                    "declared"
                } else {
                    "generic"
                }
            ))
        }
        (DefinitionKind::Join, _) => {
            let instance = format!("{}:{}", qualifier.trim_end_matches(':'), definition.name);
            let instances: Vec<_> = (mechanism.joins.iter())
                .filter(|j| inside(j.span))
                .filter(|j| {
                    let name = j.name.as_deref().unwrap_or_default();
                    named(&j.name) || name.ends_with(&format!(":{}", definition.name))
                })
                .collect();
            let named_here: Vec<_> = (instances.iter())
                .filter(|j| j.name.as_deref() == Some(instance.as_str()))
                .copied()
                .collect();
            let shown = if named_here.is_empty() {
                instances
            } else {
                named_here
            };
            let coordinates: Vec<String> = (shown.iter())
                .flat_map(|join| {
                    let name = join.name.as_deref().unwrap_or_default();
                    let link = &mechanism.links[join.link.0 as usize];
                    (link.coordinates.iter()).map(move |c| format!("`{name}.{c}`"))
                })
                .collect();
            (!coordinates.is_empty()).then(|| format!("coordinates: {}", coordinates.join(", ")))
        }
        _ => None,
    }
}
