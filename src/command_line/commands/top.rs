//! `admm-ta top`: the user's running teams, live in a terminal (ratatui) or as one snapshot
//! (`--once`, `--json`). What it reads is `runtime::observe`'s: the boards, the run
//! directories and `/proc`, never the teams' messages.

use crate::command_line::exit::usage_bail;
use crate::command_line::output::outln;
use crate::runtime::observe::{Observer, Snapshot, TeamView};
use anyhow::Result;
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Modifier, Style};
use ratatui::widgets::{Block, Borders, Paragraph, Row, Table};
use std::io::IsTerminal;
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub struct TopArgs {
    /// Only this run (its id, as listed, or `team-NAME`).
    pub run: Option<String>,
    /// Print one snapshot and exit (round time and CPU measured over --interval).
    #[arg(long)]
    pub once: bool,
    /// With --once: the snapshot as JSON.
    #[arg(long, requires = "once")]
    pub json: bool,
    /// Milliseconds between refreshes (and the measuring interval of --once).
    #[arg(long, default_value_t = 500, value_parser = clap::value_parser!(u64).range(50..=60_000))]
    pub interval: u64,
}

pub fn run(args: TopArgs) -> Result<()> {
    let interval = Duration::from_millis(args.interval);
    let mut observer = Observer::new();
    let only = |snapshot: Snapshot| Snapshot {
        teams: snapshot
            .teams
            .into_iter()
            .filter(|t| args.run.as_ref().is_none_or(|r| &t.run == r))
            .collect(),
    };
    if args.once {
        observer.snapshot();
        std::thread::sleep(interval);
        let snapshot = only(observer.snapshot());
        if args.json {
            outln!("{}", serde_json::to_string(&snapshot)?);
        } else if snapshot.teams.is_empty() {
            outln!("no running team");
        } else {
            for team in &snapshot.teams {
                outln!("{}", team_title(team));
                for line in agent_lines(team) {
                    outln!("  {line}");
                }
            }
        }
        return Ok(());
    }
    if !std::io::stdout().is_terminal() {
        usage_bail!("admm-ta top needs a terminal; --once prints one snapshot");
    }
    let mut terminal = ratatui::init();
    let result = live(&mut terminal, &mut observer, interval, &only);
    ratatui::restore();
    result
}

/// Refreshes in place until `q`, Esc or Ctrl-C.
fn live(
    terminal: &mut ratatui::DefaultTerminal,
    observer: &mut Observer,
    interval: Duration,
    only: &dyn Fn(Snapshot) -> Snapshot,
) -> Result<()> {
    let mut selected = 0usize;
    loop {
        let snapshot = only(observer.snapshot());
        selected = selected.min(snapshot.teams.len().saturating_sub(1));
        terminal.draw(|frame| {
            let [list, detail, help] = Layout::vertical([
                Constraint::Length(snapshot.teams.len().clamp(1, 8) as u16 + 2),
                Constraint::Min(3),
                Constraint::Length(1),
            ])
            .areas(frame.area());
            let teams: Vec<Row> = if snapshot.teams.is_empty() {
                vec![Row::new(vec!["no running team".to_string()])]
            } else {
                snapshot
                    .teams
                    .iter()
                    .enumerate()
                    .map(|(k, t)| {
                        let row = Row::new(vec![team_title(t)]);
                        if k == selected {
                            row.style(Style::default().add_modifier(Modifier::REVERSED))
                        } else {
                            row
                        }
                    })
                    .collect()
            };
            frame.render_widget(
                Table::new(teams, [Constraint::Percentage(100)])
                    .block(Block::default().borders(Borders::ALL).title(" teams ")),
                list,
            );
            let rows: Vec<Row> = snapshot
                .teams
                .get(selected)
                .map(|team| {
                    team.agents
                        .iter()
                        .map(|a| {
                            Row::new(vec![
                                a.agent.to_string(),
                                a.round.to_string(),
                                state_text(a.state, &a.waiting_for),
                                a.round_ms.map_or("-".into(), |ms| format!("{ms:.3}")),
                                a.cpu_percent.map_or("-".into(), |c| format!("{c:.0}%")),
                                a.pid.map_or("-".into(), |p| p.to_string()),
                            ])
                        })
                        .collect()
                })
                .unwrap_or_default();
            frame.render_widget(
                Table::new(
                    rows,
                    [
                        Constraint::Length(6),
                        Constraint::Length(8),
                        Constraint::Min(24),
                        Constraint::Length(10),
                        Constraint::Length(6),
                        Constraint::Length(8),
                    ],
                )
                .header(
                    Row::new(vec!["agent", "round", "state", "ms/round", "CPU", "pid"])
                        .style(Style::default().add_modifier(Modifier::BOLD)),
                )
                .block(Block::default().borders(Borders::ALL).title(" agents ")),
                detail,
            );
            frame.render_widget(
                Paragraph::new(
                    "q quit · ↑/↓ choose a team · read-only: boards, run directories, /proc",
                ),
                help,
            );
        })?;
        if event::poll(interval)?
            && let Event::Key(key) = event::read()?
            && key.kind == KeyEventKind::Press
        {
            match key.code {
                KeyCode::Char('q') | KeyCode::Esc => return Ok(()),
                KeyCode::Char('c') if key.modifiers.contains(KeyModifiers::CONTROL) => {
                    return Ok(());
                }
                KeyCode::Up => selected = selected.saturating_sub(1),
                KeyCode::Down => selected += 1,
                _ => {}
            }
        }
    }
}

fn team_title(team: &TeamView) -> String {
    let rounds: Vec<u64> = team.agents.iter().map(|a| a.round).collect();
    let (low, high) = (
        rounds.iter().min().copied().unwrap_or(0),
        rounds.iter().max().copied().unwrap_or(0),
    );
    format!(
        "{} ({}, {} robots{}{}): rounds {low}–{high}{}",
        team.run,
        team.kind,
        team.robots,
        team.topology
            .as_ref()
            .map_or(String::new(), |t| format!(", {t}")),
        team.launcher_pid
            .map_or(String::new(), |p| format!(", launcher {p}")),
        team.stop_requested
            .as_ref()
            .map_or(String::new(), |s| format!(", stopping ({s})")),
    )
}

fn state_text(state: &str, waiting_for: &[usize]) -> String {
    if waiting_for.is_empty() {
        state.to_string()
    } else {
        let who: Vec<String> = waiting_for.iter().take(6).map(|j| j.to_string()).collect();
        let more = if waiting_for.len() > 6 { ", …" } else { "" };
        format!("{state} for {}{more}", who.join(", "))
    }
}

fn agent_lines(team: &TeamView) -> Vec<String> {
    team.agents
        .iter()
        .map(|a| {
            format!(
                "agent {:>3}  round {:>6}  {:<28} {:>9} ms/round  CPU {:>4}  pid {}",
                a.agent,
                a.round,
                state_text(a.state, &a.waiting_for),
                a.round_ms.map_or("-".into(), |ms| format!("{ms:.3}")),
                a.cpu_percent.map_or("-".into(), |c| format!("{c:.0}%")),
                a.pid.map_or("-".into(), |p| p.to_string()),
            )
        })
        .collect()
}
