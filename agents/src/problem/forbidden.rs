//! `--forbidden FILE`: robot–task pairs that may not be used, one `robot,task` pair per line
//! (0-based indices, or names when the cost file names robots and tasks; blank lines and `#`
//! comments allowed; a pair listed twice is the same pair).

use crate::problem::costs::{CostMatrix, ProblemError, read_bounded};
use crate::problem::csv_text::{detect_delimiter, line_at, line_starts};
use std::path::Path;

/// Largest forbidden-pairs file read (bytes).
pub const MAX_FORBIDDEN_BYTES: u64 = 1 << 30;

/// Parses the pairs of a forbidden-pairs file for `costs`: a robot and a task per row, by
/// 0-based index or, when the costs have names, by name. Read with the `csv` crate: comma,
/// tab or semicolon (detected), quoting, CRLF, a BOM, blank lines and `#` comments (a `#`
/// after a pair starts a comment too).
pub fn parse(text: &str, costs: &CostMatrix) -> Result<Vec<(usize, usize)>, ProblemError> {
    let (robots, tasks) = (costs.robots(), costs.tasks());
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Comments after a pair, as before.
    let text: String = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .delimiter(detect_delimiter(&text))
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let starts = line_starts(&text);
    let line_of = |p: &csv::Position| line_at(&text, &starts, p.byte());
    let mut pairs = Vec::new();
    for record in reader.records() {
        let bad_line = |line: usize, why: &str| {
            ProblemError::Forbid(format!(
                "forbidden pairs, line {line}: {why} (expected 'robot,task', 0-based indices{})",
                if costs.names().is_some() {
                    " or names"
                } else {
                    ""
                }
            ))
        };
        let record =
            record.map_err(|e| bad_line(e.position().map_or(0, line_of), &e.to_string()))?;
        let line = record.position().map_or(0, line_of);
        let cells: Vec<&str> = record.iter().collect();
        if cells.iter().all(|c| c.is_empty()) {
            continue;
        }
        let shown = || short(&cells.join(","));
        let [r, t] = cells[..] else {
            return Err(bad_line(line, &format!("'{}' is not one pair", shown())));
        };
        let find = |cell: &str, names: Option<&[String]>| {
            cell.parse::<usize>()
                .ok()
                .or_else(|| names?.iter().position(|n| n == cell))
        };
        let (Some(r), Some(t)) = (find(r, costs.robot_names()), find(t, costs.task_names())) else {
            let what = if costs.names().is_some() {
                "two indices or names"
            } else {
                "two indices"
            };
            return Err(bad_line(line, &format!("'{}' is not {what}", shown())));
        };
        if r >= robots || t >= tasks {
            return Err(bad_line(
                line,
                &format!("pair ({r}, {t}) is outside the {robots} robots × {tasks} tasks"),
            ));
        }
        pairs.push((r, t));
    }
    Ok(pairs)
}

fn short(text: &str) -> String {
    text.chars().take(40).collect()
}

/// Reads a forbidden-pairs file (`-`: standard input) of bounded size for `costs`.
pub fn read(path: &Path, costs: &CostMatrix) -> Result<Vec<(usize, usize)>, ProblemError> {
    let text = read_bounded(path, MAX_FORBIDDEN_BYTES)?;
    parse(&text, costs)
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
    let marked = CostMatrix::new(costs.robots(), costs.tasks(), values)?;
    match costs.names() {
        Some(names) => marked.with_names(names.clone()),
        None => Ok(marked),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_pairs_and_names_bad_lines() {
        let costs = CostMatrix::uniform(3, 2, 1).unwrap();
        assert_eq!(
            parse("# pairs\n0,1\n\n2, 0 # late\n0,1\n", &costs).unwrap(),
            vec![(0, 1), (2, 0), (0, 1)]
        );
        assert_eq!(parse("\"0\"\t\"1\"\r\n", &costs).unwrap(), vec![(0, 1)]);
        for (text, needle) in [
            ("0\n", "line 1: '0' is not one pair"),
            ("0,1,2\n", "not one pair"),
            ("a,1\n", "not two indices"),
            ("\n3,0\n", "line 2: pair (3, 0) is outside"),
        ] {
            let err = parse(text, &costs).unwrap_err().to_string();
            assert!(err.contains(needle), "{err}");
        }
    }

    #[test]
    fn names_stand_for_indices_when_the_costs_have_them() {
        let costs = CostMatrix::new(2, 2, vec![1.0, 2.0, 3.0, 4.0])
            .unwrap()
            .with_names(crate::problem::costs::Names {
                robots: Some(vec!["uav3".into(), "uav4".into()]),
                tasks: Some(vec!["dock_A".into(), "dock_B".into()]),
            })
            .unwrap();
        assert_eq!(
            parse("uav4,dock_A\n0,dock_B\nuav3,1\n", &costs).unwrap(),
            vec![(1, 0), (0, 1), (0, 1)]
        );
        let err = parse("uav9,dock_A\n", &costs).unwrap_err().to_string();
        assert!(err.contains("not two indices or names"), "{err}");
        // Names survive forbidding.
        let marked = apply(&costs, &[(1, 0)], false).unwrap();
        assert_eq!(marked.robot_names(), costs.robot_names());
    }
}
