//! Did-you-mean suggestions for misspelt names and fields.

/// Edit distance with an early exit once `limit` is exceeded: the optimal string alignment
/// distance (Levenshtein's insertions, deletions and substitutions, on characters and ignoring
/// ASCII case, plus Damerau's transposition of two adjacent characters), so that `earht` is one
/// edit from `earth`, as a typist would count it, not two.
fn edit_distance(a: &str, b: &str, limit: usize) -> Option<usize> {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    if a.len().abs_diff(b.len()) > limit {
        return None;
    }
    let same = |x: &char, y: &char| x.eq_ignore_ascii_case(y);
    // Rows i − 2, i − 1 and i of the table of distances between prefixes.
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut previous: Vec<usize> = (0..=b.len()).collect();
    let mut current = vec![0; b.len() + 1];
    let mut previous_min = 0;
    for (i, ca) in a.iter().enumerate() {
        current[0] = i + 1;
        let mut row_min = current[0];
        for (j, cb) in b.iter().enumerate() {
            let substitution = previous[j] + usize::from(!same(ca, cb));
            let mut best = substitution.min(previous[j + 1] + 1).min(current[j] + 1);
            if i > 0 && j > 0 && same(ca, &b[j - 1]) && same(&a[i - 1], cb) {
                best = best.min(before[j - 1] + 1);
            }
            current[j + 1] = best;
            row_min = row_min.min(best);
        }
        // A transposition reaches back two rows: give up only when both rows exceed the limit.
        if row_min.min(previous_min) > limit {
            return None;
        }
        previous_min = row_min;
        std::mem::swap(&mut before, &mut previous);
        std::mem::swap(&mut previous, &mut current);
    }
    let distance = previous[b.len()];
    (distance <= limit).then_some(distance)
}

/// The candidate closest to `name`, if one is close enough to be a plausible typo.
pub fn did_you_mean<'a>(
    name: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).max(1);
    let mut best: Option<(usize, &str)> = None;
    for candidate in candidates {
        if candidate == name {
            continue;
        }
        if let Some(d) = edit_distance(name, candidate, limit) {
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, candidate));
            }
        }
    }
    best.map(|(_, c)| c)
}

/// The body number in the thesis's notation `S1`, `S_1`, `S12`: bodies are written `S_i`, so a
/// user who types `S1` means the first body.
pub fn thesis_body_number(name: &str) -> Option<usize> {
    let digits = name.strip_prefix('S')?;
    let digits = digits.strip_prefix('_').unwrap_or(digits);
    if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok().filter(|&n| n >= 1)
}
