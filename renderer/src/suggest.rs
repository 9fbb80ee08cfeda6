//! "Did you mean …?": the closest names to a misspelt one, by edit distance (insertions,
//! deletions and substitutions of one character, and swaps of two neighbours, each one
//! edit: the optimal string alignment distance). Every suggestion the project makes comes
//! from here: unknown keys, enum values, materials and definitions in a scene file, and
//! catalog scene names in the conformance harness.

/// The edit distance between `a` and `b`, in characters: insertions, deletions,
/// substitutions and swaps of two neighbouring characters (`veiw` → `view` is one edit).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    // Three rows of the table: i − 2, i − 1 and i.
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut cur = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = (a[i - 1] != b[j - 1]) as usize;
            cur[j] = (prev[j - 1] + cost).min(prev[j] + 1).min(cur[j - 1] + 1);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                cur[j] = cur[j].min(before[j - 2] + 1);
            }
        }
        before = std::mem::replace(&mut prev, cur);
    }
    prev[b.len()]
}

/// The largest distance at which a name still counts as a misspelling of `wanted`: one edit
/// for every three characters, at least one.
pub fn max_distance(wanted: &str) -> usize {
    (wanted.chars().count() / 3).max(1)
}

/// The candidates within [`max_distance`] of `wanted`, closest first (ties by name, so the
/// order of the candidates does not matter), at most `limit` of them.
pub fn closest<'a>(
    wanted: &str,
    candidates: impl IntoIterator<Item = &'a str>,
    limit: usize,
) -> Vec<&'a str> {
    let mut scored: Vec<(usize, &str)> = candidates
        .into_iter()
        .map(|c| (edit_distance(wanted, c), c))
        .filter(|(d, _)| *d <= max_distance(wanted))
        .collect();
    scored.sort();
    scored.dedup();
    scored.into_iter().take(limit).map(|(_, c)| c).collect()
}

/// ` (did you mean 'x'?)`, or ` (did you mean 'x' or 'y'?)`, for the closest candidates;
/// empty when none is close.
pub fn did_you_mean<'a>(wanted: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    let close = closest(wanted, candidates, 2);
    match close.as_slice() {
        [] => String::new(),
        [one] => format!(" (did you mean '{one}'?)"),
        [one, two, ..] => format!(" (did you mean '{one}' or '{two}'?)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test01_edit_distance() {
        for (a, b, d) in [
            ("", "", 0),
            ("abc", "", 3),
            ("", "abc", 3),
            ("shiny", "shiny", 0),
            ("shinny", "shiny", 1),
            ("kitten", "sitting", 3),
            ("lookat", "look_at", 1),
            ("veiw", "view", 1),
            ("ab", "ba", 1),
            ("abc", "ca", 3),
            ("fov", "vof", 2),
            ("é", "e", 1),
        ] {
            assert_eq!(edit_distance(a, b), d, "edit_distance({a:?}, {b:?})");
            assert_eq!(edit_distance(b, a), d, "edit_distance({b:?}, {a:?})");
        }
    }

    #[test]
    fn test02_suggestions_are_close_and_ordered() {
        let names = ["shiny", "matte", "shine", "glass"];
        assert_eq!(closest("shinny", names, 8), ["shiny", "shine"]);
        assert_eq!(
            did_you_mean("shinny", names),
            " (did you mean 'shiny' or 'shine'?)"
        );
        assert_eq!(did_you_mean("mate", names), " (did you mean 'matte'?)");
        assert_eq!(did_you_mean("wood", names), "");
        // A short name allows one edit only.
        assert_eq!(did_you_mean("ab", ["xy", "ax"]), " (did you mean 'ax'?)");
    }
}
