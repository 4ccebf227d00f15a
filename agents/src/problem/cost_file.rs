//! Cost files as people write them, read with the `csv` crate: comma, tab or semicolon
//! delimiters (detected from the first row, or given), RFC 4180 quoting, CRLF, a UTF-8 BOM,
//! `#` comment lines and blank lines, a trailing empty column on every row (an exporter's
//! trailing delimiter), a header row of task names and a first column of robot names
//! (pandas' `to_csv` writes both, with an empty corner cell); or JSON, a list of rows or
//! `{"costs": [[…]], "robots": […], "tasks": […]}` with `null` for a forbidden pair.
//!
//! Numbers are spelled as before: decimals with a point, scientific notation, `inf`,
//! `+inf`, `-inf`, `Infinity` (any case); `NaN`, a number beyond double precision, an empty
//! cell, ragged rows and an empty matrix are refused, naming line and column. A decimal
//! comma is never guessed.
//!
//! ```
//! use admm_ta_agents::problem::{cost_file, forbidden};
//! // pandas' `df.to_csv()`: a header of task names, a first column of robot names.
//! let file = cost_file::parse(",dock_A,dock_B\nuav3,9,1\nuav4,2,8\n", None).unwrap();
//! assert_eq!(file.costs.robot_names().unwrap(), ["uav3", "uav4"]);
//! assert_eq!(file.costs.task_names().unwrap(), ["dock_A", "dock_B"]);
//! assert_eq!(file.costs.values(), [9.0, 1.0, 2.0, 8.0]);
//! // Forbidden pairs by name; JSON with `null` marks them in the file itself.
//! assert_eq!(forbidden::parse("uav3,dock_A\n", &file.costs).unwrap(), [(0, 0)]);
//! let json = cost_file::parse(r#"{"costs": [[9, null], [2, 8]]}"#, None).unwrap();
//! assert_eq!(json.forbidden, [(0, 1)]);
//! // Refusals name line and column.
//! let bad = cost_file::parse("1,2\n3,x\n", None).unwrap_err().to_string();
//! assert!(bad.contains("line 2, column 2"), "{bad}");
//! ```

use crate::problem::costs::{CostMatrix, Names, ProblemError, read_cost_text};
use crate::problem::csv_text::{detect_delimiter, line_at, line_starts};
use std::path::Path;

/// What a cost file holds: the costs (with their names, if the file has them) and the pairs
/// it marks forbidden (JSON `null`s; a CSV marks them with `inf` in the costs themselves).
#[derive(Debug, Clone, PartialEq)]
pub struct CostFile {
    pub costs: CostMatrix,
    /// `(robot, task)` pairs the file marks forbidden (`null`), to apply with
    /// [`crate::problem::forbidden::apply`] once the direction (minimise or maximise) is
    /// known. A forbidden pair's entry in `costs` is 0.
    pub forbidden: Vec<(usize, usize)>,
}

/// What a JSON cost file starts with: an object or a list.
const JSON_STARTS: [char; 2] = ['\u{7b}', '['];

/// Reads a cost file's text: JSON when it starts with `{` or `[`, else CSV with `delimiter`
/// (`None`: detected from the first row).
pub fn parse(text: &str, delimiter: Option<u8>) -> Result<CostFile, ProblemError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim_start().starts_with(JSON_STARTS) {
        return parse_json(text);
    }
    let costs = parse_csv(text, delimiter)?;
    Ok(CostFile {
        costs,
        forbidden: Vec::new(),
    })
}

/// One row of the file: its line and its cells (trimmed).
struct Row {
    line: usize,
    cells: Vec<String>,
}

fn parse_csv(text: &str, delimiter: Option<u8>) -> Result<CostMatrix, ProblemError> {
    let delimiter = delimiter.unwrap_or_else(|| detect_delimiter(text));
    let mut rows = read_rows(text, delimiter)?;
    let header = is_header(&rows[0].cells).then(|| rows.remove(0));
    if rows.is_empty() {
        return Err(ProblemError::Empty);
    }
    // Robot names: a first column of names (none a number), or any first column under a
    // header whose corner cell is empty (pandas' index, numbers or not). A first column
    // that mixes numbers and text is costs with a bad cell, never half names.
    let named_rows = rows.iter().all(|r| number(&r.cells[0]).is_none())
        || header.as_ref().is_some_and(|h| h.cells[0].is_empty());
    let skip = usize::from(named_rows);
    let tasks = rows[0].cells.len() - skip;
    let mut values = Vec::with_capacity(rows.len() * tasks);
    let mut robot_names = Vec::new();
    for (robot, row) in rows.iter().enumerate() {
        if row.cells.len() - skip != tasks || row.cells.len() <= skip {
            return Err(ProblemError::Ragged {
                line: row.line,
                found: row.cells.len() - skip,
                expected: tasks,
            });
        }
        if named_rows {
            robot_names.push(row.cells[0].clone());
        }
        for (column, cell) in row.cells.iter().enumerate().skip(skip) {
            values.push(cell_value(
                cell,
                row.line,
                column + 1,
                robot,
                column - skip,
                delimiter,
            )?);
        }
        crate::problem::costs::check_size(robot + 1, tasks)?;
    }
    if tasks == 0 {
        return Err(ProblemError::Empty);
    }
    CostMatrix::new(rows.len(), tasks, values)?.with_names(Names {
        robots: named_rows.then_some(robot_names),
        tasks: header_names(header, skip, tasks)?,
    })
}

/// The rows of a CSV text with `delimiter`, blank lines and comments left out, and an
/// exporter's trailing delimiter (an empty last cell on every row) dropped; refused when
/// empty.
fn read_rows(text: &str, delimiter: u8) -> Result<Vec<Row>, ProblemError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .delimiter(delimiter)
        .comment(Some(b'#'))
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let starts = line_starts(text);
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| line_at(text, &starts, p.byte()));
            ProblemError::Format(format!("line {line}: {}", csv_reason(&e)))
        })?;
        let line = record
            .position()
            .map_or(0, |p| line_at(text, &starts, p.byte()));
        let cells: Vec<String> = record.iter().map(str::to_string).collect();
        // A blank line, or one of spaces only.
        if cells.iter().all(String::is_empty) {
            continue;
        }
        rows.push(Row { line, cells });
    }
    if rows.is_empty() {
        return Err(ProblemError::Empty);
    }
    if rows
        .iter()
        .all(|r| r.cells.len() > 1 && r.cells.last().is_some_and(String::is_empty))
    {
        for row in &mut rows {
            row.cells.pop();
        }
    }
    Ok(rows)
}

/// The task names of a `header` row (its first `skip` cells are the robot names' corner),
/// which must name the rows' `tasks` columns.
fn header_names(
    header: Option<Row>,
    skip: usize,
    tasks: usize,
) -> Result<Option<Vec<String>>, ProblemError> {
    let Some(h) = header else {
        return Ok(None);
    };
    let names: Vec<String> = h.cells.into_iter().skip(skip).collect();
    if names.len() != tasks {
        return Err(ProblemError::Format(format!(
            "line {}: the header names {} tasks but the rows have {tasks} costs",
            h.line,
            names.len()
        )));
    }
    Ok(Some(names))
}

/// Whether a first row is a header of task names: every cell a name (none a number, none
/// empty), except the corner, which may be empty or a label (pandas writes an empty corner
/// above its index, and numbers as names when the columns have none). A first row of costs
/// with one bad cell is not a header: it is refused where the cell is.
fn is_header(cells: &[String]) -> bool {
    let names = |cells: &[String]| cells.iter().all(|c| !c.is_empty() && number(c).is_none());
    match cells.split_first() {
        Some((corner, rest)) if corner.is_empty() => {
            !rest.is_empty() && rest.iter().all(|c| !c.is_empty())
        }
        Some((corner, rest)) => number(corner).is_none() && (names(rest) || rest.is_empty()),
        None => false,
    }
}

/// What the `csv` crate found wrong, in a cost file's terms.
fn csv_reason(error: &csv::Error) -> String {
    match error.kind() {
        csv::ErrorKind::Utf8 { .. } => "not UTF-8 text".into(),
        _ => error.to_string(),
    }
}

/// A cell's number, as cost files spell them (`None`: not a number).
fn number(cell: &str) -> Option<f64> {
    cell.parse::<f64>().ok()
}

/// The cost in `cell` (line `line`, column `column` of the file; robot `robot`, task
/// `task`).
fn cell_value(
    cell: &str,
    line: usize,
    column: usize,
    robot: usize,
    task: usize,
    delimiter: u8,
) -> Result<f64, ProblemError> {
    let shown: String = cell.chars().take(40).collect();
    let Some(value) = number(cell) else {
        let decimal_comma = delimiter != b','
            && cell.split_once(',').is_some_and(|(a, b)| {
                !a.is_empty()
                    && a.trim_start_matches(['+', '-'])
                        .bytes()
                        .all(|c| c.is_ascii_digit())
                    && !b.is_empty()
                    && b.bytes().all(|c| c.is_ascii_digit())
            });
        if decimal_comma {
            return Err(ProblemError::Format(format!(
                "line {line}, column {column}: '{shown}' has a decimal comma; export the costs with a decimal point (in a spreadsheet: a locale with '.' as the decimal separator, or a CSV/TSV export of plain numbers)"
            )));
        }
        return Err(ProblemError::NotANumber {
            line,
            column,
            text: shown,
        });
    };
    let spelled_infinite = matches!(
        cell.trim_start_matches(['+', '-'])
            .to_ascii_lowercase()
            .as_str(),
        "inf" | "infinity"
    );
    if value.is_infinite() && !spelled_infinite {
        return Err(ProblemError::OutOfRange {
            line,
            column,
            text: shown,
        });
    }
    if value.is_nan() {
        return Err(ProblemError::NonFinite { robot, task, value });
    }
    Ok(value)
}

impl CostMatrix {
    /// Parses a cost file's text ([`crate::problem::cost_file`]): CSV (comma, tab or
    /// semicolon, detected; quoting, a header row of task names and a first column of robot
    /// names allowed; blank lines and `#` comments skipped; `inf`, `+inf`, `-inf`,
    /// `Infinity` in any case are infinities, `nan` is refused) or JSON. JSON `null`s are
    /// forbidden pairs, here `+∞` (minimising; [`parse`] returns them apart, for a caller
    /// that maximises).
    pub fn from_csv_str(text: &str) -> Result<Self, ProblemError> {
        let file = parse(text, None)?;
        crate::problem::forbidden::apply(&file.costs, &file.forbidden, false)
    }

    /// Reads a cost file (see [`CostMatrix::from_csv_str`]), `-` for standard input, with a
    /// size bound ([`crate::problem::read_bounded`]).
    pub fn read_csv(path: &Path) -> Result<Self, ProblemError> {
        Self::from_csv_str(&read_cost_text(path)?)
    }
}

/// A JSON cost file: `[[…], …]` or `{"costs": [[…]], "robots": […], "tasks": […]}`; a cell
/// is a number, `null` (a forbidden pair) or a string spelled as in a CSV (`"inf"`).
fn parse_json(text: &str) -> Result<CostFile, ProblemError> {
    let bad = |why: String| ProblemError::Format(format!("JSON costs: {why}"));
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| bad(format!("line {}: {e}", e.line())))?;
    let (rows, names) = match value {
        serde_json::Value::Array(rows) => (rows, Names::default()),
        serde_json::Value::Object(mut object) => {
            let names =
                |object: &mut serde_json::Map<String, serde_json::Value>, key: &str| match object
                    .remove(key)
                {
                    None | Some(serde_json::Value::Null) => Ok(None),
                    Some(serde_json::Value::Array(items)) => items
                        .into_iter()
                        .map(|item| match item {
                            serde_json::Value::String(name) => Ok(name),
                            other => Ok(other.to_string()),
                        })
                        .collect::<Result<Vec<String>, ProblemError>>()
                        .map(Some),
                    Some(other) => Err(bad(format!(
                        "\"{key}\" must be a list of names, got {other}"
                    ))),
                };
            let robots = names(&mut object, "robots")?;
            let tasks = names(&mut object, "tasks")?;
            let Some(serde_json::Value::Array(rows)) = object.remove("costs") else {
                return Err(bad(
                    "expected a list of rows, or an object with \"costs\": [[…], …]".into(),
                ));
            };
            if let Some(key) = object.keys().next() {
                return Err(bad(format!(
                    "unknown key \"{key}\" (use \"costs\", \"robots\" and \"tasks\")"
                )));
            }
            (rows, Names { robots, tasks })
        }
        _ => {
            return Err(bad(
                "expected a list of rows, or an object with \"costs\"".into()
            ));
        }
    };
    if rows.is_empty() {
        return Err(ProblemError::Empty);
    }
    let mut values = Vec::new();
    let mut forbidden = Vec::new();
    let mut tasks = None;
    for (robot, row) in rows.into_iter().enumerate() {
        let serde_json::Value::Array(cells) = row else {
            return Err(bad(format!("row {robot} is not a list of costs")));
        };
        match tasks {
            None => tasks = Some(cells.len()),
            Some(expected) if expected != cells.len() => {
                return Err(bad(format!(
                    "row {robot} has {} costs but the first row has {expected} (ragged rows)",
                    cells.len()
                )));
            }
            Some(_) => {}
        }
        crate::problem::costs::check_size(robot + 1, cells.len())?;
        for (task, cell) in cells.into_iter().enumerate() {
            let value = match cell {
                serde_json::Value::Null => {
                    forbidden.push((robot, task));
                    0.0
                }
                serde_json::Value::Number(n) => n.as_f64().ok_or_else(|| {
                    bad(format!(
                        "robot {robot}, task {task}: {n} is beyond double precision"
                    ))
                })?,
                serde_json::Value::String(s) => {
                    cell_value(s.trim(), robot + 1, task + 1, robot, task, b',').map_err(|_| {
                        bad(format!("robot {robot}, task {task}: '{s}' is not a number"))
                    })?
                }
                other => {
                    return Err(bad(format!(
                        "robot {robot}, task {task}: {other} is not a cost (a number, or null for a forbidden pair)"
                    )));
                }
            };
            values.push(value);
        }
    }
    let tasks = tasks.unwrap_or(0);
    if tasks == 0 {
        return Err(ProblemError::Empty);
    }
    let robots = values.len() / tasks;
    Ok(CostFile {
        costs: CostMatrix::new(robots, tasks, values)?.with_names(names)?,
        forbidden,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn costs(text: &str) -> CostMatrix {
        parse(text, None).unwrap().costs
    }

    #[test]
    fn every_common_export_reads_the_same_costs() {
        let plain = costs("62.29,74.18\n10,20\n");
        for text in [
            "\u{feff}62.29,74.18\r\n10,20\r\n",
            "\"62.29\",\"74.18\"\n\"10\",\"20\"\n",
            "62.29\t74.18\n10\t20\n",
            "62.29;74.18\n10;20\n",
            "62.29,74.18,\n10,20,\n",
            "# a comment\n\n62.29 , 74.18\n   \n10,20\n",
        ] {
            let read = costs(text);
            assert_eq!(read.values(), plain.values(), "{text:?}");
            assert_eq!(read.names(), None, "{text:?}");
        }
        let pandas = costs(",t0,t1\nuav3,62.29,74.18\nuav4,10,20\n");
        assert_eq!(pandas.values(), plain.values());
        assert_eq!(pandas.robot_names().unwrap(), ["uav3", "uav4"]);
        assert_eq!(pandas.task_names().unwrap(), ["t0", "t1"]);
        // pandas' default integer index and column names.
        let numbered = costs(",0,1\n0,62.29,74.18\n1,10,20\n");
        assert_eq!(numbered.values(), plain.values());
        assert_eq!(numbered.robot_names().unwrap(), ["0", "1"]);
        let header_only = costs("dock_A,dock_B\n62.29,74.18\n10,20\n");
        assert_eq!(header_only.values(), plain.values());
        assert_eq!(header_only.robot_names(), None);
        let json = parse(
            r#"{"costs": [[62.29, null], [10, 20]], "robots": ["a", "b"], "tasks": ["x", "y"]}"#,
            None,
        )
        .unwrap();
        assert_eq!(json.forbidden, [(0, 1)]);
        assert_eq!(json.costs.task_names().unwrap(), ["x", "y"]);
        assert_eq!(costs("[[62.29, 74.18], [10, 20]]").values(), plain.values());
    }

    #[test]
    fn refusals_name_line_and_column() {
        let err = |text: &str| parse(text, None).unwrap_err().to_string();
        assert!(
            err("1,2\n3\n").contains("line 2 has 1 values"),
            "{}",
            err("1,2\n3\n")
        );
        assert!(err("1,2\n3,x\n").contains("line 2, column 2: 'x'"));
        assert!(err("1,,2\n").contains("column 2"));
        assert!(err("# c\n\n1,2\n3,x\n").contains("line 4, column 2"));
        assert!(err("1,NaN\n").contains("NaN"));
        assert!(err("1,1e999\n").contains("beyond the range"));
        assert!(err("").contains("empty"));
        assert!(err("# only\n\n").contains("empty"));
        assert!(err("1;2,5\n3;4\n").contains("decimal comma"));
        assert!(err(",a,a\nr,1,2\n").contains("two tasks are called 'a'"));
        assert!(err("[[1, true]]").contains("not a cost"));
        assert!(err("{\"cost\": [[1]]}").contains("\"costs\""));
    }
}
