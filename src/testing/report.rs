//! What `lsdc test` prints: a summary (text), the same as JSON, and JUnit XML for CI systems.

use std::fmt::Write;

use serde::Serialize;

use super::case::{describe, Outcome, Status};
use super::record::Recorded;
use crate::output::xml::escape;

/// The counts of a run of cases.
#[derive(Clone, Debug, Serialize)]
pub struct Summary<'a> {
    pub passed: usize,
    pub failed: usize,
    pub errors: usize,
    pub jobs: usize,
    pub seconds: f64,
    pub cases: &'a [Outcome],
}

impl<'a> Summary<'a> {
    pub fn new(cases: &'a [Outcome], jobs: usize, seconds: f64) -> Summary<'a> {
        let count = |status| cases.iter().filter(|c| c.status == status).count();
        Summary {
            passed: count(Status::Passed),
            failed: count(Status::Failed),
            errors: count(Status::Error),
            jobs,
            seconds,
            cases,
        }
    }

    pub fn all_passed(&self) -> bool {
        self.failed + self.errors == 0
    }
}

/// One line per case, the failures' details under it, and the counts.
pub fn text(summary: &Summary) -> String {
    let mut out = String::new();
    for case in summary.cases {
        let label = match case.status {
            Status::Passed => "ok   ",
            Status::Failed => "FAIL ",
            Status::Error => "ERROR",
        };
        let closest = match (&case.worst, case.status) {
            (Some(w), Status::Passed) => {
                format!(
                    ", closest: `{}` at {:.1e} of its tolerance",
                    w.variable, w.margin
                )
            }
            _ => String::new(),
        };
        let _ = writeln!(
            out,
            "{label} {} ({:.2} s{closest})",
            case.name, case.seconds
        );
        for failure in &case.failures {
            let _ = writeln!(out, "      {failure}");
        }
        for variable in case.failed_variables.iter().skip(1).take(4) {
            let _ = writeln!(out, "      also {}", describe(variable));
        }
        if case.status != Status::Passed {
            let _ = writeln!(out, "      ({}:{})", case.manifest, case.line);
        }
    }
    let _ = writeln!(
        out,
        "{} passed, {} failed, {} errors; {:.2} s on {} thread{}",
        summary.passed,
        summary.failed,
        summary.errors,
        summary.seconds,
        summary.jobs,
        if summary.jobs == 1 { "" } else { "s" }
    );
    out
}

/// JUnit XML: one test suite per manifest, a test case per case with its failure or error.
pub fn junit(summary: &Summary) -> String {
    let mut manifests: Vec<&str> = summary.cases.iter().map(|c| c.manifest.as_str()).collect();
    manifests.dedup();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites name=\"lsdc test\" tests=\"{}\" failures=\"{}\" errors=\"{}\" time=\"{:.3}\">",
        summary.cases.len(),
        summary.failed,
        summary.errors,
        summary.seconds
    );
    for manifest in manifests {
        let cases: Vec<&Outcome> = (summary.cases.iter())
            .filter(|c| c.manifest == manifest)
            .collect();
        let count = |status| cases.iter().filter(|c| c.status == status).count();
        let _ = writeln!(
            out,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" time=\"{:.3}\">",
            escape(manifest),
            cases.len(),
            count(Status::Failed),
            count(Status::Error),
            cases.iter().map(|c| c.seconds).sum::<f64>()
        );
        cases.iter().for_each(|case| junit_case(&mut out, case));
        out += "  </testsuite>\n";
    }
    out += "</testsuites>\n";
    out
}

fn junit_case(out: &mut String, case: &Outcome) {
    let _ = write!(
        out,
        "    <testcase name=\"{}\" classname=\"{}\" time=\"{:.3}\"",
        escape(&case.name),
        escape(&case.manifest),
        case.seconds
    );
    let element = match case.status {
        Status::Passed => {
            out.push_str("/>\n");
            return;
        }
        Status::Failed => "failure",
        Status::Error => "error",
    };
    let message = case.failures.first().map_or("", String::as_str);
    let details: Vec<String> = (case.failures.iter().cloned())
        .chain(case.failed_variables.iter().map(describe))
        .collect();
    let _ = write!(
        out,
        ">\n      <{element} message=\"{}\">{}</{element}>\n    </testcase>\n",
        escape(message),
        escape(&details.join("\n"))
    );
}

/// What `--update` did, one case per paragraph.
pub fn recorded_text(recorded: &Recorded) -> String {
    let mut out = format!("recorded {} ({})\n", recorded.name, recorded.path);
    if !recorded.replaced {
        let _ = writeln!(out, "      new reference, {} rows", recorded.rows_after);
        return out;
    }
    if recorded.rows_before != recorded.rows_after {
        let _ = writeln!(
            out,
            "      rows: {} -> {}",
            recorded.rows_before, recorded.rows_after
        );
    }
    for (what, columns) in [
        ("added", &recorded.added_columns),
        ("removed", &recorded.removed_columns),
    ] {
        if !columns.is_empty() {
            let _ = writeln!(out, "      {what} columns: {}", columns.join(", "));
        }
    }
    match &recorded.largest {
        Some(largest) => {
            let _ = writeln!(
                out,
                "      largest change: `{}` by {:.3e} at t = {}; {} variable{} moved beyond {} tolerance",
                largest.variable,
                largest.difference,
                largest.time,
                recorded.moved.len(),
                if recorded.moved.len() == 1 { "" } else { "s" },
                if recorded.moved.len() == 1 { "its" } else { "their" },
            );
        }
        None => out.push_str("      the old and new references have no times in common\n"),
    }
    for moved in recorded.moved.iter().take(5) {
        let _ = writeln!(out, "      moved: {}", describe(moved));
    }
    out
}
