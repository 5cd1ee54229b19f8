//! Diagnostics: one structure for every error and warning of every phase, rendered in one place
//! (`render`) as text with source snippets or as JSON.

pub mod number;
pub mod render;
pub mod suggest;

use crate::source::Span;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    Error,
    Warning,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Label {
    pub span: Span,
    pub message: String,
    /// The primary label is where the problem is; secondary labels give context (the use site of
    /// an instantiated definition, the import that brought a library in, an earlier definition).
    pub primary: bool,
}

/// An edit that fixes the problem, for editors to apply: replace the text of `span` (empty for
/// an insertion) by `replacement`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fix {
    pub span: Span,
    pub replacement: String,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    pub severity: Severity,
    /// Stable code, documented in `docs/diagnostics.md`.
    pub code: &'static str,
    pub message: String,
    pub labels: Vec<Label>,
    pub notes: Vec<String>,
    pub help: Option<String>,
    /// An edit that fixes the problem, when one is certain enough to offer. Boxed: every
    /// diagnostic travels in the `Err` of results, and few have a fix.
    pub fix: Option<Box<Fix>>,
}

impl Diagnostic {
    pub fn error(code: &'static str, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Error,
            code,
            message: message.into(),
            labels: Vec::new(),
            notes: Vec::new(),
            help: None,
            fix: None,
        }
    }

    pub fn warning(code: &'static str, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, message)
        }
    }

    pub fn primary(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: true,
        });
        self
    }

    pub fn secondary(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: false,
        });
        self
    }

    pub fn note(mut self, note: impl Into<String>) -> Diagnostic {
        self.notes.push(note.into());
        self
    }

    pub fn help(mut self, help: impl Into<String>) -> Diagnostic {
        self.help = Some(help.into());
        self
    }

    pub fn with_help(self, help: Option<String>) -> Diagnostic {
        match help {
            Some(h) => self.help(h),
            None => self,
        }
    }

    /// Offers an edit that fixes the problem: `span`'s text replaced by `replacement`.
    pub fn fix(mut self, span: Span, replacement: impl Into<String>) -> Diagnostic {
        self.fix = Some(Box::new(Fix {
            span,
            replacement: replacement.into(),
        }));
        self
    }

    /// A did-you-mean: the help "did you mean `candidate`?" and the fix that writes `candidate`
    /// in place of `span`, when there is a candidate.
    pub fn did_you_mean(self, span: Span, candidate: Option<&str>) -> Diagnostic {
        match candidate {
            Some(candidate) => self
                .help(format!("did you mean `{candidate}`?"))
                .fix(span, candidate),
            None => self,
        }
    }

    /// Where the problem is: the span of the primary label.
    pub fn primary_span(&self) -> Option<Span> {
        self.labels.iter().find(|l| l.primary).map(|l| l.span)
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

impl std::fmt::Display for Diagnostic {
    /// The one-line form, without the source: `error[E0301]: unknown name `x``. The full form
    /// with the source lines is `render::to_text`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let severity = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        write!(f, "{severity}[{}]: {}", self.code, self.message)
    }
}

impl std::error::Error for Diagnostic {}

/// Diagnostics collected by one phase, in the order found.
#[derive(Default, Debug)]
pub struct Diagnostics {
    pub list: Vec<Diagnostic>,
    /// Code, message and place of each diagnostic pushed, so that a duplicate is found in
    /// constant time (a file of n errors is checked in linear time).
    pushed: std::collections::HashSet<Identity>,
}

/// What makes two diagnostics the same report: code, message and place.
type Identity = (&'static str, String, Option<crate::source::Span>);

fn identity(diagnostic: &Diagnostic) -> Identity {
    (
        diagnostic.code,
        diagnostic.message.clone(),
        diagnostic.primary_span(),
    )
}

impl Diagnostics {
    pub fn push(&mut self, diagnostic: Diagnostic) {
        // A definition's body is checked when it is declared and again at each use: the same
        // error at the same place is reported once, with the context of its first report.
        if self.pushed.insert(identity(&diagnostic)) {
            self.list.push(diagnostic);
        }
    }

    /// Drops the diagnostics after the first `len`, which can then be reported again (the
    /// checker looks at an expression's type silently this way).
    pub fn truncate(&mut self, len: usize) {
        for dropped in self.list.drain(len.min(self.list.len())..) {
            self.pushed.remove(&identity(&dropped));
        }
    }

    pub fn has_errors(&self) -> bool {
        self.list.iter().any(Diagnostic::is_error)
    }
}
