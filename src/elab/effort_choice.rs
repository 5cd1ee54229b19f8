//! Which applied efforts a scene keeps (`apply only weight, arm[1] ;`, `apply without damping ;`,
//! chosen by `load::scene`). Each `apply` declaration answers to the names of its effort (the
//! effort's own name, `arm[1]:push`, and the name written in the declaration), of the
//! definition that makes it (`weight` in `apply weight(column) on ...`) and of the groups that
//! declare it (the packages around it, an instance of an array `arm[1]` and the array `arm`),
//! and to the names written qualified by those groups (`arm[1]:weight`, `arm:weight`).
//! An application is kept when the scene writes no `only` or one of its names is among them,
//! and none is among the `without`: a `between` declaration is kept or left out whole (the
//! effort and its reaction). A name that answers for no application is refused (E0715): a
//! choice that chooses nothing is a slip, never silently ignored.

use std::collections::BTreeSet;

use crate::diag::suggest::did_you_mean;
use crate::diag::Diagnostic;
use crate::load::scene::EffortChoice;
use crate::source::Span;
use crate::syntax::ast::{Callee, Expr, ExprKind, QualifiedName};

/// The scene's choice, applied to each `apply` declaration as it is elaborated.
pub(super) struct EffortFilter {
    choice: EffortChoice,
    /// Whether each name of `only`, then of `without`, answered for an application.
    answered: Vec<bool>,
    /// Every name an application answered to, for the suggestion of E0715.
    names_seen: BTreeSet<String>,
    /// The `apply` declarations left out (once each, whatever their targets).
    pub(super) left_out: usize,
}

impl EffortFilter {
    /// The filter of a scene's choice; `None` when it chooses nothing (every effort applies).
    pub(super) fn new(choice: &EffortChoice) -> Option<EffortFilter> {
        (!choice.is_empty()).then(|| EffortFilter {
            answered: vec![false; choice.only.len() + choice.without.len()],
            choice: choice.clone(),
            names_seen: BTreeSet::new(),
            left_out: 0,
        })
    }

    /// Whether an application that answers to `names` is kept.
    pub(super) fn keeps(&mut self, names: Vec<String>) -> bool {
        let written = self.choice.only.iter().chain(&self.choice.without);
        for ((name, _), answered) in written.zip(&mut self.answered) {
            *answered |= names.contains(name);
        }
        let named = |list: &[(String, Span)]| list.iter().any(|(n, _)| names.contains(n));
        let only = &self.choice.only;
        let kept = (only.is_empty() || named(only)) && !named(&self.choice.without);
        self.names_seen.extend(names);
        if !kept {
            self.left_out += 1;
        }
        kept
    }

    /// E0715 for the first name written that answered for no application.
    pub(super) fn unanswered(&self) -> Option<Diagnostic> {
        let written = self.choice.only.iter().chain(&self.choice.without);
        let (name, span) = (written.zip(&self.answered)).find(|(_, &a)| !a)?.0;
        let seen = self.names_seen.iter().map(String::as_str);
        let help = match did_you_mean(name, seen) {
            Some(close) => format!("did you mean `{close}`? an applied effort answers to its own name, the definition that makes it (`weight`) and the groups that declare it (`arm[1]`, `arm`)"),
            None => "an applied effort answers to its own name, the definition that makes it (`weight`) and the groups that declare it (`arm[1]`, `arm`)".to_string(),
        };
        Some(
            Diagnostic::error("E0715", format!("no applied effort answers to `{name}`"))
                .primary(*span, "names no `apply` of the program")
                .help(help),
        )
    }
}

/// The names an `apply` declaration answers to: its effort's own name (`effort_name`), the name
/// or definition written (`effort`), and the groups around it (`groups`, outermost first: a
/// package `P`, an instance `arm[1]`), each as the program qualifies it (`row[2]:cell[1]`),
/// an instance also by its array (`row[2]:cell`).
pub(super) fn application_names(
    effort_name: Option<String>,
    effort: &Expr,
    groups: &[String],
) -> Vec<String> {
    let qualified = |q: &QualifiedName| {
        (q.index.is_none()).then(|| format!("{}:{}", q.package.name, q.name.name))
    };
    let mut written: Vec<String> = Vec::new();
    match &effort.kind {
        ExprKind::Name(name) => written.push(name.to_string()),
        ExprKind::Qualified(q) => written.extend(qualified(q)),
        ExprKind::Call(call) => match &call.callee {
            Callee::Name(name) => written.push(name.name.to_string()),
            Callee::Qualified(q) => {
                written.push(q.name.name.to_string());
                written.extend(qualified(q));
            }
            Callee::Unknown(_) => {}
        },
        _ => {}
    }
    let mut names: Vec<String> = effort_name.into_iter().collect();
    for depth in 1..=groups.len() {
        let path = groups[..depth].join(":");
        let array = (path.strip_suffix(']').and_then(|p| p.rsplit_once('[')))
            .map(|(array, _)| array.to_string());
        for group in array.into_iter().chain([path]) {
            // The names written, in the group: `arm[2]:weight`, `arm:weight`.
            names.extend(written.iter().map(|w| format!("{group}:{w}")));
            names.push(group);
        }
    }
    names.extend(written);
    names
}
