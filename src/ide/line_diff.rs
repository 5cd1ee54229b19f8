//! A unified diff of two texts, line by line (`diff -u`'s format, 3 lines of context), for
//! `lsdc fmt --check` to show what formatting would change. The lines are matched by a longest
//! common subsequence (the classic dynamic programme, Hunt & McIlroy 1976) between the common
//! first and last lines; past `LARGEST_TABLE` cells the middle is shown as removed then added.

use std::fmt::Write;

/// Lines of context around each change.
const CONTEXT: usize = 3;

/// The most cells of the subsequence table (4 bytes each) spent on one diff.
const LARGEST_TABLE: usize = 4_000_000;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Line {
    Same(usize, usize),
    Removed(usize),
    Added(usize),
}

/// The unified diff from `old` to `new`, under `--- old_name` and `+++ new_name`; empty when the
/// texts have the same lines.
pub fn unified(old: &str, new: &str, old_name: &str, new_name: &str) -> String {
    let (a, b): (Vec<&str>, Vec<&str>) = (old.lines().collect(), new.lines().collect());
    let script = edit_script(&a, &b);
    let changed: Vec<usize> = (0..script.len())
        .filter(|&i| !matches!(script[i], Line::Same(..)))
        .collect();
    if changed.is_empty() {
        return String::new();
    }
    let mut text = format!("--- {old_name}\n+++ {new_name}\n");
    // Hunks: changes closer than twice the context share one.
    let mut first = 0;
    while first < changed.len() {
        let mut last = first;
        while last + 1 < changed.len() && changed[last + 1] - changed[last] <= 2 * CONTEXT {
            last += 1;
        }
        let start = changed[first].saturating_sub(CONTEXT);
        let end = (changed[last] + CONTEXT + 1).min(script.len());
        write_hunk(&mut text, &script[start..end], &a, &b);
        first = last + 1;
    }
    text
}

/// One hunk: its header (1-based first lines and counts) and its lines.
fn write_hunk(text: &mut String, lines: &[Line], a: &[&str], b: &[&str]) {
    let old_start = lines.iter().find_map(|l| match *l {
        Line::Same(i, _) | Line::Removed(i) => Some(i),
        Line::Added(_) => None,
    });
    let new_start = lines.iter().find_map(|l| match *l {
        Line::Same(_, j) | Line::Added(j) => Some(j),
        Line::Removed(_) => None,
    });
    let old_count = (lines.iter())
        .filter(|l| !matches!(l, Line::Added(_)))
        .count();
    let new_count = (lines.iter())
        .filter(|l| !matches!(l, Line::Removed(_)))
        .count();
    // An empty side is numbered by the line before it (`diff -u`'s convention).
    let start = |first: Option<usize>, count: usize| match count {
        0 => first.unwrap_or(0),
        _ => first.map_or(0, |i| i + 1),
    };
    let _ = writeln!(
        text,
        "@@ -{},{old_count} +{},{new_count} @@",
        start(old_start, old_count),
        start(new_start, new_count)
    );
    for line in lines {
        let _ = match *line {
            Line::Same(i, _) => writeln!(text, " {}", a[i]),
            Line::Removed(i) => writeln!(text, "-{}", a[i]),
            Line::Added(j) => writeln!(text, "+{}", b[j]),
        };
    }
}

/// The lines of `a` and `b` in order, each kept, removed or added.
fn edit_script(a: &[&str], b: &[&str]) -> Vec<Line> {
    let prefix = (a.iter().zip(b)).take_while(|(x, y)| x == y).count();
    let suffix = (a[prefix..].iter().rev())
        .zip(b[prefix..].iter().rev())
        .take_while(|(x, y)| x == y)
        .count();
    let (middle_a, middle_b) = (&a[prefix..a.len() - suffix], &b[prefix..b.len() - suffix]);
    let mut script: Vec<Line> = (0..prefix).map(|i| Line::Same(i, i)).collect();
    script.extend(
        middle_script(middle_a, middle_b)
            .into_iter()
            .map(|line| match line {
                Line::Same(i, j) => Line::Same(prefix + i, prefix + j),
                Line::Removed(i) => Line::Removed(prefix + i),
                Line::Added(j) => Line::Added(prefix + j),
            }),
    );
    let (tail_a, tail_b) = (a.len() - suffix, b.len() - suffix);
    script.extend((0..suffix).map(|k| Line::Same(tail_a + k, tail_b + k)));
    script
}

/// The edit script of the lines between the common first and last ones.
fn middle_script(a: &[&str], b: &[&str]) -> Vec<Line> {
    let (n, m) = (a.len(), b.len());
    if n.saturating_mul(m) > LARGEST_TABLE {
        return (0..n)
            .map(Line::Removed)
            .chain((0..m).map(Line::Added))
            .collect();
    }
    // common[i][j]: the longest common subsequence of a[i..] and b[j..].
    let mut common = vec![0u32; (n + 1) * (m + 1)];
    let at = |i: usize, j: usize| i * (m + 1) + j;
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            common[at(i, j)] = match a[i] == b[j] {
                true => common[at(i + 1, j + 1)] + 1,
                false => common[at(i + 1, j)].max(common[at(i, j + 1)]),
            };
        }
    }
    let (mut i, mut j, mut script) = (0, 0, Vec::with_capacity(n + m));
    while i < n || j < m {
        if i < n && j < m && a[i] == b[j] {
            script.push(Line::Same(i, j));
            (i, j) = (i + 1, j + 1);
        } else if j == m || (i < n && common[at(i + 1, j)] >= common[at(i, j + 1)]) {
            script.push(Line::Removed(i));
            i += 1;
        } else {
            script.push(Line::Added(j));
            j += 1;
        }
    }
    script
}
