//! Scenes: `scene name = decls end` at the top level of a program, each one study of it (its
//! own `simulate` settings, initial and given values, drives, locks, efforts and outputs).
//!
//! A scene is selected once the program is parsed: the program becomes its own declarations
//! (without its scenes) followed by the selected scene's, and the scene's `simulate` takes the
//! place of the program's. The phases after loading never see a scene; `lsdc check` loads the
//! program once per scene to check them all. The scenes of an imported library are its own
//! studies and are left out where it is imported.

use crate::diag::suggest::did_you_mean;
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::{Decl, DeclKind, Program};

/// The scenes a root program declares, and the one its declarations were selected for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Scenes {
    /// Every scene's name, in declaration order.
    pub names: Vec<String>,
    /// The scene selected: the one asked for, else the first declared; `None` for a program
    /// without scenes.
    pub selected: Option<String>,
    /// Where the selected scene is declared (its declarations are inside).
    pub selected_span: Option<Span>,
    /// The selected scene's `apply only` and `apply without`: the applied efforts it keeps.
    pub efforts: EffortChoice,
}

/// The applied efforts a scene keeps (`apply only weight, arm[1] ;`, `apply without damping ;`):
/// each name as written (`arm[1]:push`) with where it is written. An application is kept when
/// no `only` is written or one of its names is among them, and none is among the `without`
/// (`elab::effort_choice` names the applications).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EffortChoice {
    pub only: Vec<(String, Span)>,
    pub without: Vec<(String, Span)>,
}

impl EffortChoice {
    /// Whether the scene chooses among the applied efforts at all.
    pub fn is_empty(&self) -> bool {
        self.only.is_empty() && self.without.is_empty()
    }
}

/// A scene as declared: its name, where the name and the whole declaration are, its
/// declarations.
struct Declared {
    name: String,
    name_span: Span,
    span: Span,
    decls: Vec<Decl>,
}

/// Selects the scene `wanted` (the first declared when `None`) in a root program: its
/// declarations follow the program's and its `simulate` replaces the program's. Errors: a scene
/// inside a package (E0712), two scenes of one name (E0713), a scene asked for that the
/// program does not declare (E0714).
pub fn select(
    program: &mut Program,
    wanted: Option<&str>,
    diagnostics: &mut Vec<Diagnostic>,
) -> Scenes {
    refuse_nested(&program.decls, diagnostics);
    let mut scenes: Vec<Declared> = Vec::new();
    let mut own = Vec::new();
    for decl in std::mem::take(&mut program.decls) {
        match decl.kind {
            DeclKind::Scene(scene) => {
                let scene = scene.into_inner();
                if let Some(first) = scenes.iter().find(|s| *s.name == *scene.name.name) {
                    diagnostics.push(
                        Diagnostic::error(
                            "E0713",
                            format!("the scene `{}` is declared twice", scene.name.name),
                        )
                        .primary(scene.name.span, "a second scene of this name")
                        .secondary(first.name_span, "the first one")
                        .help("give each scene its own name: `--scene NAME` selects one"),
                    );
                    continue;
                }
                scenes.push(Declared {
                    name: scene.name.name.to_string(),
                    name_span: scene.name.span,
                    span: decl.span,
                    decls: scene.decls,
                });
            }
            kind => own.push(Decl {
                kind,
                span: decl.span,
            }),
        }
    }
    let names: Vec<String> = scenes.iter().map(|s| s.name.clone()).collect();
    let chosen = match wanted {
        None => names.first().cloned(),
        Some(wanted) if names.iter().any(|n| n == wanted) => Some(wanted.to_string()),
        Some(wanted) => {
            diagnostics.push(unknown_scene(wanted, &names));
            None
        }
    };
    let selected = (chosen.as_ref()).and_then(|name| scenes.into_iter().find(|s| s.name == *name));
    let selected_span = selected.as_ref().map(|s| s.span);
    let mut added = selected.map(|s| s.decls).unwrap_or_default();
    let efforts = effort_choice(&mut added, diagnostics);
    let is_simulate = |decl: &Decl| matches!(decl.kind, DeclKind::Simulate(_));
    // The scene's settings replace the program's; when the program has two, they stay for the
    // checker's E0418 and the scene's are set aside (one error, where the fault is).
    if added.iter().any(is_simulate) {
        match own.iter().filter(|d| is_simulate(d)).count() {
            0 => {}
            1 => own.retain(|decl| !is_simulate(decl)),
            _ => added.retain(|decl| !is_simulate(decl)),
        }
    }
    own.extend(added);
    program.decls = own;
    Scenes {
        names,
        selected: chosen,
        selected_span,
        efforts,
    }
}

/// Takes the effort selections (`apply only ...`, `apply without ...`) out of a scene's
/// declarations. E0716: another word in their place.
fn effort_choice(decls: &mut Vec<Decl>, diagnostics: &mut Vec<Diagnostic>) -> EffortChoice {
    let mut choice = EffortChoice::default();
    decls.retain(|decl| {
        let DeclKind::SelectEfforts(selection) = &decl.kind else {
            return true;
        };
        let names = selection.names.iter().map(|n| (n.path.clone(), n.span));
        match selection.word.name.as_str() {
            "only" => choice.only.extend(names),
            "without" => choice.without.extend(names),
            word => diagnostics.push(
                Diagnostic::error(
                    "E0716",
                    format!("`apply {word}` is not an effort selection"),
                )
                .primary(selection.word.span, "`only` or `without` expected here")
                .help("a scene keeps some applied efforts with `apply only weight, arm[1] ;` or leaves some out with `apply without damping ;`"),
            ),
        }
        false
    });
    choice
}

/// Leaves out the scenes of an imported library: they are the library's own studies.
pub fn leave_out(program: &mut Program) {
    program
        .decls
        .retain(|decl| !matches!(decl.kind, DeclKind::Scene(_)));
}

/// E0714: `--scene NAME` names no scene of the program.
fn unknown_scene(wanted: &str, names: &[String]) -> Diagnostic {
    let diagnostic =
        Diagnostic::error("E0714", format!("the program declares no scene `{wanted}`"));
    if names.is_empty() {
        return diagnostic.help("declare one (`scene lifting = ... end;`), or leave out `--scene`");
    }
    let listed = names.join(", ");
    match did_you_mean(wanted, names.iter().map(String::as_str)) {
        Some(close) => diagnostic.help(format!("did you mean `{close}`? its scenes: {listed}")),
        None => diagnostic.help(format!("its scenes: {listed}")),
    }
}

/// E0712: a scene is a study of the whole program, declared at its top level.
fn refuse_nested(decls: &[Decl], diagnostics: &mut Vec<Diagnostic>) {
    for decl in decls {
        let inner = match &decl.kind {
            DeclKind::Package(package) => &package.decls,
            DeclKind::Scene(scene) => &scene.decls,
            _ => continue,
        };
        for nested in inner {
            if let DeclKind::Scene(scene) = &nested.kind {
                diagnostics.push(
                    Diagnostic::error("E0712", "a scene is declared at the top level of a program")
                        .primary(scene.name.span, "a scene inside another declaration")
                        .help("move the scene out to the program's top level: it studies the whole program"),
                );
            }
        }
        refuse_nested(inner, diagnostics);
    }
}
