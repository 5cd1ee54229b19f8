//! Energy as the arbiter of singular passages. Where a mechanism passes a singular configuration
//! its branches of motion cross (a parallelogram and its anti-parallelogram at the flat
//! configuration), and an integration error there can carry the run onto the wrong one. The
//! physical motion keeps its energy (or its energy balance, with the work of the
//! non-conservative efforts) across the passage to the integration's accuracy; a switch of branch
//! costs a finite part of it at once. So a passage across which the energy jumps, far beyond what
//! it does between the other outputs, is a wrong answer: the run is reported failed there, with
//! every output kept.

use super::constraints::SingularPassage;

/// A jump of the energy across a passage, relative to the run's energy scale, above which the
/// run left its branch: a switch of branch costs a finite part of the energy (0.67 of it for a
/// row of two parallelograms), far above any integration error a run reports as a success.
const LEFT_BRANCH: f64 = 1e-3;

/// ... and the jump must also exceed the largest change between two other consecutive outputs
/// by this factor, so that a coarse run whose energy wanders everywhere is not blamed on a
/// passage.
const ABOVE_ELSEWHERE: f64 = 100.0;

/// What the check needs of an output: its time, the energy the run conserves there (its balance
/// with the work of non-conservative efforts when that work is integrated, else kinetic +
/// potential when the efforts are conservative; None if neither is known) and its kinetic
/// energy.
pub struct Output {
    pub time: f64,
    pub conserved: Option<f64>,
    pub kinetic: f64,
}

/// The passage the run left its branch at: when it began, and why it is a wrong answer.
pub struct LeftBranch {
    pub time: f64,
    pub message: String,
}

/// The first passage across which the energy jumped (see the module).
pub fn left_branch(samples: &[Output], passages: &[SingularPassage]) -> Option<LeftBranch> {
    let energies: Vec<f64> = samples.iter().map(|s| s.conserved).collect::<Option<_>>()?;
    let first = *energies.first()?;
    let scale = samples
        .iter()
        .map(|s| s.kinetic.abs())
        .fold(first.abs(), f64::max);
    if scale == 0.0 {
        return None;
    }
    let spans: Vec<(usize, usize)> = passages
        .iter()
        .filter_map(|p| span(samples, p.start, p.end?))
        .collect();
    let inside = |k: usize| spans.iter().any(|&(a, b)| a <= k && k < b);
    let elsewhere = (0..energies.len().saturating_sub(1))
        .filter(|&k| !inside(k))
        .map(|k| (energies[k + 1] - energies[k]).abs() / scale)
        .fold(0.0, f64::max);
    passages.iter().find_map(|passage| {
        let (a, b) = span(samples, passage.start, passage.end?)?;
        let jump = (energies[b] - energies[a]).abs() / scale;
        let bound = LEFT_BRANCH.max(ABOVE_ELSEWHERE * elsewhere * (b - a) as f64);
        (jump > bound).then(|| LeftBranch {
            time: passage.start,
            message: format!(
                "the run left its branch of motion at the singular configuration of the loop \
                 closed by `{}` (t = {} to {}): its energy changed by {jump:.1e} of its scale \
                 across the passage, against at most {elsewhere:.1e} between other outputs, so \
                 the motion after it is not the physical one; a different tolerance or step \
                 passes it differently (docs/loops.md, \"Singular configurations\")",
                passage.loop_name, samples[a].time, samples[b].time,
            ),
        })
    })
}

/// The outputs just before and just after a passage from `start` to `end`.
fn span(samples: &[Output], start: f64, end: f64) -> Option<(usize, usize)> {
    let before = samples.iter().rposition(|s| s.time <= start)?;
    let after = samples.iter().position(|s| s.time >= end)?;
    (after > before).then_some((before, after))
}
