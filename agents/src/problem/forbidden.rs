//! `--forbidden FILE`: robot–task pairs that may not be used, one `robot,task` pair per line
//! (0-based; blank lines and `#` comments allowed; a pair listed twice is the same pair).

use crate::problem::{CostMatrix, ProblemError, read_bounded};
use std::path::Path;

/// Largest forbidden-pairs file read (bytes).
pub const MAX_FORBIDDEN_BYTES: u64 = 1 << 30;

/// Parses the pairs of a forbidden-pairs file for a `robots × tasks` problem.
pub fn parse(text: &str, robots: usize, tasks: usize) -> Result<Vec<(usize, usize)>, ProblemError> {
    let mut pairs = Vec::new();
    // A UTF-8 byte-order mark (spreadsheets write one) is not part of the first robot.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (index, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad = |why: &str| {
            ProblemError::Forbid(format!(
                "forbidden pairs, line {}: {why} (expected 'robot,task', 0-based)",
                index + 1
            ))
        };
        let mut fields = line.split(',').map(str::trim);
        let (Some(r), Some(t), None) = (fields.next(), fields.next(), fields.next()) else {
            return Err(bad(&format!("'{}' is not one pair", short(line))));
        };
        let (Ok(r), Ok(t)) = (r.parse::<usize>(), t.parse::<usize>()) else {
            return Err(bad(&format!("'{}' is not two indices", short(line))));
        };
        if r >= robots || t >= tasks {
            return Err(bad(&format!(
                "pair ({r}, {t}) is outside the {robots} robots × {tasks} tasks"
            )));
        }
        pairs.push((r, t));
    }
    Ok(pairs)
}

fn short(text: &str) -> String {
    text.chars().take(40).collect()
}

/// Reads a forbidden-pairs file (a regular file of bounded size).
pub fn read(path: &Path, robots: usize, tasks: usize) -> Result<Vec<(usize, usize)>, ProblemError> {
    let text = read_bounded(path, MAX_FORBIDDEN_BYTES)?;
    parse(&text, robots, tasks)
}

/// The costs with these pairs forbidden: `+∞`, or `−∞` for profits (`maximize`).
pub fn apply(
    costs: &CostMatrix,
    pairs: &[(usize, usize)],
    maximize: bool,
) -> Result<CostMatrix, ProblemError> {
    let mut values = costs.values().to_vec();
    let marker = if maximize {
        f64::NEG_INFINITY
    } else {
        f64::INFINITY
    };
    for &(r, t) in pairs {
        values[r * costs.tasks() + t] = marker;
    }
    CostMatrix::new(costs.robots(), costs.tasks(), values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_pairs_and_names_bad_lines() {
        assert_eq!(
            parse("# pairs\n0,1\n\n2, 0 # late\n0,1\n", 3, 2).unwrap(),
            vec![(0, 1), (2, 0), (0, 1)]
        );
        for (text, needle) in [
            ("0\n", "line 1: '0' is not one pair"),
            ("0,1,2\n", "not one pair"),
            ("a,1\n", "not two indices"),
            ("\n3,0\n", "line 2: pair (3, 0) is outside"),
        ] {
            let err = parse(text, 3, 2).unwrap_err().to_string();
            assert!(err.contains(needle), "{err}");
        }
    }
}
