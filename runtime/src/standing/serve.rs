//! The sidecar protocol: `admm-ta agent --team FILE --robot I --serve` runs robot `I` of a
//! private team ([`crate::standing`]) for a robot program in any language, one JSON object
//! per line each way.
//!
//! **Out** (standard output), one line each (nothing else: rows written before the sidecar
//! has joined its team wait in the pipe):
//! * per episode, the [`Answer`]: `{"episode": k, "robot": I, "task": j or null,
//!   "certified": bool, "rounds": r, "agreement_rounds": a, "sent_bytes": b, "cost": c,
//!   "total_cost": C,
//!   "assignment": [...], "feasible": bool, "ms": t}`, plus, when it applies, `"missing"`,
//!   `"unavailable"`, `"left"`, `"leave_refused"`, `"lost"`, `"joined"` and `"crashed"`
//!   (lists of robots: the roster's changes);
//! * a row it cannot use: `{"error": "...", "episode": k, "robot": I}`; the team keeps
//!   waiting for a valid row until the episode deadline;
//! * its leave refused (the others would fall apart without it): `{"error": "...",
//!   "leave_refused": true, "episode": k, "robot": I}`, once; it keeps relaying and asking
//!   until it may go;
//! * the team failed (a signal, a failure nobody recovers from) or went on without this
//!   robot (cut off): `{"error": "...", "failed": true, "episode": k, "robot": I}`, and the
//!   sidecar exits with the code of `agent` (4, or the signal's).
//!
//! **In** (standard input), one line per episode: `{"costs": [c_0, …, c_{M−1}]}`, numbers,
//! `null` for a task this robot may not take, one per task of the team file (`M`); an
//! episode with fewer tasks says so, `{"costs": [c_0, …, c_{k−1}], "tasks": k}` (the first
//! `k` tasks exist, the same `k` at every robot); or `{"available": false}`: this robot takes
//! no task this episode and relays for its neighbours; or `{"leave": true}`: the robot leaves
//! as at the end of input (below) and the sidecar exits 0. No row within the team file's
//! `episode_timeout`: every robot's answer names this one in `missing`, and the team solves
//! nothing (`on_failure = "abort"`, the default) or solves without it (`"continue"`). End of
//! input: the robot leaves at the next episode boundary (it relays in that episode) and the
//! sidecar exits 0; the team goes on without it.

use crate::process::member_error::MemberError;
use crate::standing::answer::{Answer, LeaveRefused, RowError};
use crate::standing::member::TeamMember;
use serde::Deserialize;
use std::io::{BufRead, Write};
use std::path::Path;
use std::sync::mpsc::{Receiver, RecvTimeoutError, sync_channel};
use std::time::{Duration, Instant};

/// Longest line read (a row of a million costs fits).
const MAX_LINE: u64 = 64 << 20;

/// How a served robot ended without failing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ServeEnd {
    /// Its program closed its input: it left the team.
    Left,
    /// Its program stopped reading its answers: it left the team.
    OutputClosed,
}

/// One line of a robot program.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RowLine {
    #[serde(default)]
    costs: Option<Vec<Option<f64>>>,
    #[serde(default)]
    available: Option<bool>,
    /// The episode the row is for (optional: a row for another episode is refused).
    #[serde(default)]
    episode: Option<u64>,
    /// The episode's tasks, when fewer than the team's (the row then has that many costs).
    #[serde(default)]
    tasks: Option<usize>,
    /// The robot leaves the team (as at the end of input).
    #[serde(default)]
    leave: Option<bool>,
}

/// What a robot program's line asks for.
enum Request {
    Row(Vec<Option<f64>>),
    Unavailable,
    Leave,
}

/// What the robot program sent: the input of [`serve_from`] (standard input's lines, or the
/// messages of a ROS 2 topic).
pub(crate) enum Input {
    Line(String),
    /// A line that is no text, or too long: an error line, and the next line.
    Bad(String),
    /// End of input, or an input that cannot be read (the same for the robot).
    End(Option<String>),
}

/// Where the robot program's lines come from: a channel fed by a thread (standard input),
/// or a source polled in place (a ROS 2 subscription).
pub(crate) trait Lines {
    /// The next line, waiting up to `timeout`.
    fn next_line(&mut self, timeout: Duration) -> Result<Input, RecvTimeoutError>;
}

impl Lines for Receiver<Input> {
    fn next_line(&mut self, timeout: Duration) -> Result<Input, RecvTimeoutError> {
        self.recv_timeout(timeout)
    }
}

/// Reads `input` line by line on its own thread (a blocking read has no deadline).
fn read_lines(input: impl BufRead + Send + 'static) -> Receiver<Input> {
    let (sender, receiver) = sync_channel(4);
    std::thread::Builder::new()
        .name("serve-input".into())
        .spawn(move || {
            let mut input = input;
            let input = &mut input;
            loop {
                let mut bytes = Vec::new();
                let read = std::io::Read::take(&mut *input, MAX_LINE).read_until(b'\n', &mut bytes);
                let message = match read {
                    Ok(0) => Input::End(None),
                    Ok(_) if !bytes.ends_with(b"\n") && bytes.len() as u64 >= MAX_LINE => {
                        // The rest of the line goes too.
                        let mut rest = Vec::new();
                        loop {
                            rest.clear();
                            match std::io::Read::take(&mut *input, MAX_LINE)
                                .read_until(b'\n', &mut rest)
                            {
                                Ok(0) | Err(_) => break,
                                Ok(_) if rest.ends_with(b"\n") => break,
                                Ok(_) => {}
                            }
                        }
                        Input::Bad(format!("a line longer than {MAX_LINE} bytes"))
                    }
                    Ok(_) => match String::from_utf8(bytes) {
                        Ok(line) => Input::Line(line),
                        Err(_) => Input::Bad("a line that is not UTF-8 text".into()),
                    },
                    Err(e) => Input::End(Some(e.to_string())),
                };
                let end = matches!(message, Input::End(_));
                if sender.send(message).is_err() || end {
                    return;
                }
            }
        })
        .expect("a thread for the robot program's input");
    receiver
}

/// Writes one JSON line; `false` when the program no longer reads.
fn send(output: &mut dyn Write, value: &serde_json::Value) -> bool {
    writeln!(output, "{value}")
        .and_then(|()| output.flush())
        .is_ok()
}

fn row_error(episode: u64, robot: usize, error: &str) -> serde_json::Value {
    serde_json::json!({"error": error, "episode": episode, "robot": robot})
}

/// The robot program learns why its robot stopped (the same line goes to standard error).
pub(crate) fn tell_failure(
    output: &mut dyn Write,
    episode: u64,
    robot: usize,
    error: &MemberError,
) {
    let line = serde_json::json!({
        "error": error.text(),
        "failed": true,
        "episode": episode,
        "robot": robot,
    });
    let _ = send(output, &line);
}

/// A line of a robot program that gives no usable row.
#[derive(Debug, thiserror::Error)]
enum BadLine {
    #[error(
        "not a row: {0} (expected {{\"costs\": [numbers or null]}} or {{\"available\": false}} on one line)"
    )]
    Json(#[from] serde_json::Error),
    #[error(transparent)]
    Row(#[from] RowError),
    #[error("give costs, or \"available\": false for an episode without this robot")]
    Neither,
    #[error("an unavailable robot gives no costs")]
    Both,
    #[error("a robot that leaves gives no costs and no availability")]
    LeaveWithRow,
    #[error(
        "a row for episode {given}, but the team is at episode {current} (a row after its episode's deadline?)"
    )]
    OtherEpisode { given: u64, current: u64 },
    #[error(
        "{got} costs for {tasks} tasks (an episode with fewer tasks says so: \"tasks\": {got})"
    )]
    Length { got: usize, tasks: usize },
    #[error("\"tasks\": {said}, but {got} costs")]
    TasksDiffer { said: usize, got: usize },
}

/// What one line asks for, or why it cannot be used.
fn parse_line(member: &TeamMember, line: &str, current: u64) -> Result<Request, BadLine> {
    let line: RowLine = serde_json::from_str(line)?;
    // A leave is for whatever episode comes: its episode number does not matter.
    if line.leave == Some(true) {
        return if line.costs.is_some() || line.available == Some(false) {
            Err(BadLine::LeaveWithRow)
        } else {
            Ok(Request::Leave)
        };
    }
    if let Some(given) = line.episode.filter(|&given| given != current) {
        return Err(BadLine::OtherEpisode { given, current });
    }
    match (line.costs, line.available) {
        (Some(_), Some(false)) => Err(BadLine::Both),
        (None, Some(false)) => Ok(Request::Unavailable),
        (None, _) => Err(BadLine::Neither),
        (Some(costs), _) => {
            match line.tasks {
                Some(said) if said != costs.len() => {
                    return Err(BadLine::TasksDiffer {
                        said,
                        got: costs.len(),
                    });
                }
                None if costs.len() != member.tasks() => {
                    return Err(BadLine::Length {
                        got: costs.len(),
                        tasks: member.tasks(),
                    });
                }
                _ => {}
            }
            member.check_row(&costs)?;
            Ok(Request::Row(costs))
        }
    }
}

/// A robot's row file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum RowFileError {
    #[error("row file {}", path.display())]
    Read {
        path: std::path::PathBuf,
        #[source]
        source: admm_ta_agents::problem::ProblemError,
    },
    #[error("row file {}: one row of costs, got {rows} rows", path.display())]
    Rows {
        path: std::path::PathBuf,
        rows: usize,
    },
}

/// A robot's own row from a file (`-`: standard input): one CSV line or a JSON list (`null`,
/// or `inf` — `-inf` with `maximize` — for a task it may not take), as the cost files of
/// `solve` are read.
pub fn read_row(path: &Path, maximize: bool) -> Result<Vec<Option<f64>>, RowFileError> {
    use admm_ta_agents::problem::{cost_file, read_cost_text};
    let read = |source| RowFileError::Read {
        path: path.to_path_buf(),
        source,
    };
    let file = read_cost_text(path)
        .and_then(|text| cost_file::parse(&text, None))
        .map_err(read)?;
    if file.costs.robots() != 1 {
        return Err(RowFileError::Rows {
            path: path.to_path_buf(),
            rows: file.costs.robots(),
        });
    }
    let forbidden = if maximize {
        f64::NEG_INFINITY
    } else {
        f64::INFINITY
    };
    Ok(file
        .costs
        .row(0)
        .iter()
        .enumerate()
        .map(|(t, &v)| (!file.forbidden.contains(&(0, t)) && v != forbidden).then_some(v))
        .collect())
}

/// Robot `id` of the private team in `team_path` for one episode with the row in
/// `row_path` ([`read_row`]): it joins, gives its row, and leaves with the others.
pub fn one_episode(team_path: &Path, id: usize, row_path: &Path) -> Result<Answer, MemberError> {
    let _signals = admm_ta_transport::signals::install();
    let team = crate::team::team_file::Team::read(team_path).map_err(MemberError::refused)?;
    let row = read_row(row_path, team.file.maximize).map_err(MemberError::refused)?;
    let mut member = TeamMember::join(team_path, id)?;
    let answer = member.assign(&row)?;
    leave_for_good(&mut member, &mut std::io::sink(), false)?;
    Ok(answer)
}

/// Leaves the team for a program that ended (or no longer reads): each refused leave is an
/// episode in which the robot relays; the first refusal is told (when the program reads).
fn leave_for_good(
    member: &mut TeamMember,
    output: &mut dyn Write,
    mut tell: bool,
) -> Result<(), MemberError> {
    tracing::info!(robot = member.id(), "leaving the team");
    loop {
        let episode = member.episode();
        let id = member.id();
        match member.leave() {
            Ok(()) => return Ok(()),
            Err(MemberError::Refused(cause)) if cause.is::<LeaveRefused>() => {
                if tell {
                    let line = serde_json::json!({
                        "error": cause.to_string(),
                        "leave_refused": true,
                        "episode": episode,
                        "robot": id,
                    });
                    tell = send(output, &line);
                }
            }
            Err(e) => {
                if tell {
                    tell_failure(output, episode, id, &e);
                }
                return Err(e);
            }
        }
    }
}

/// What the robot program asks for next (waiting up to the episode deadline, looking at the
/// team meanwhile): a row or an unavailable episode, an abstention at the deadline, or an end.
enum Next {
    Answer(Box<Answer>),
    End(ServeEnd),
}

/// Serves one episode: the program's next usable line, or the deadline.
fn serve_episode(
    member: &mut TeamMember,
    lines: &mut dyn Lines,
    output: &mut dyn Write,
) -> Result<Next, MemberError> {
    let id = member.id();
    let mut deadline = Instant::now() + member.episode_timeout();
    loop {
        let episode = member.episode();
        let checked = Instant::now();
        member
            .check()
            .inspect_err(|e| tell_failure(output, episode, id, e))?;
        // The time the team took to form a roster again is not the program's.
        deadline += checked.elapsed().saturating_sub(Duration::from_millis(5));
        // A line already written goes first, whatever the time.
        let slice = deadline
            .saturating_duration_since(Instant::now())
            .min(Duration::from_millis(50));
        let bad = match lines.next_line(slice) {
            Ok(Input::Line(line)) if line.trim().is_empty() => None,
            Ok(Input::Line(line)) => match parse_line(member, &line, episode) {
                Ok(request) => {
                    let answer = match request {
                        Request::Row(row) => member.assign(&row),
                        Request::Unavailable => member.unavailable(),
                        Request::Leave => {
                            leave_for_good(member, output, true)?;
                            return Ok(Next::End(ServeEnd::Left));
                        }
                    };
                    let answer = answer.inspect_err(|e| tell_failure(output, episode, id, e))?;
                    return Ok(Next::Answer(Box::new(answer)));
                }
                Err(error) => Some(error.to_string()),
            },
            Ok(Input::Bad(why)) => Some(why),
            Ok(Input::End(why)) => {
                if let Some(why) = why {
                    tracing::warn!(error = %why, "the robot program's input failed");
                }
                leave_for_good(member, output, true)?;
                return Ok(Next::End(ServeEnd::Left));
            }
            Err(RecvTimeoutError::Disconnected) => {
                leave_for_good(member, output, true)?;
                return Ok(Next::End(ServeEnd::Left));
            }
            Err(RecvTimeoutError::Timeout) => {
                if Instant::now() >= deadline {
                    tracing::info!(episode, "no row within the episode deadline");
                    let answer = member
                        .abstain()
                        .inspect_err(|e| tell_failure(output, episode, id, e))?;
                    return Ok(Next::Answer(Box::new(answer)));
                }
                None
            }
        };
        if let Some(why) = bad
            && !send(output, &row_error(episode, id, &why))
        {
            leave_for_good(member, output, false)?;
            return Ok(Next::End(ServeEnd::OutputClosed));
        }
    }
}

/// Serves robot `id` of the private team in `team_path` to the program on the other end of
/// `input` and `output` until it closes its input (the robot leaves), the team goes on
/// without it, or the team fails.
pub fn serve(
    team_path: &Path,
    id: usize,
    input: impl BufRead + Send + 'static,
    output: &mut dyn Write,
) -> Result<ServeEnd, MemberError> {
    // Termination signals stop the team cleanly, between episodes too.
    let _signals = admm_ta_transport::signals::install();
    let mut member = TeamMember::join(team_path, id)?;
    serve_from(&mut member, &mut read_lines(input), output)
}

/// Serves `member` to the program whose lines come from `lines` and whose answers go to
/// `output`, one JSON line each, until the program leaves, the team goes on without the
/// robot, or the team fails. The caller installs the signal handling.
pub(crate) fn serve_from(
    member: &mut TeamMember,
    lines: &mut dyn Lines,
    output: &mut dyn Write,
) -> Result<ServeEnd, MemberError> {
    let id = member.id();
    tracing::info!(
        robot = id,
        robots = member.robots(),
        tasks = member.tasks(),
        roster = ?member.roster(),
        "joined the team: reading rows"
    );
    loop {
        let answer = match serve_episode(member, lines, output)? {
            Next::Answer(answer) => answer,
            Next::End(end) => return Ok(end),
        };
        let json = serde_json::to_value(&answer).expect("an answer serialises");
        let delivered = send(output, &json);
        if answer.lost.contains(&id) {
            let cut = MemberError::failed(RowError::Lost(format!(
                "robot(s) {:?} left and the team went on without it",
                answer.left
            )));
            tell_failure(output, answer.episode + 1, id, &cut);
            return Err(cut);
        }
        if !delivered {
            leave_for_good(member, output, false)?;
            return Ok(ServeEnd::OutputClosed);
        }
    }
}
