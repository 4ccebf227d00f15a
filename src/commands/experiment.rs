//! `admm-ta experiment NAME`: the paper's experiments and the comparisons beyond it, each
//! printing a table and writing JSON and SVG.

use crate::cli::{Experiment, FigureArgs};
use crate::commands::shared::{agent_program, progress_bar};
use admm_ta::Method;
use admm_ta::runtime::options::run::RunOptions;
use admm_ta::runtime::transport::Execution;
use admm_ta_bench::figures::FigureConfig;
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::time::Duration;

fn check_sizes(sizes: &[usize]) -> Result<()> {
    if sizes.is_empty() || sizes.iter().any(|n| !(2..=500).contains(n)) {
        bail!("--sizes: every team size must be 2…500");
    }
    Ok(())
}

/// A figure experiment's result: what `--json` prints, the table, the files written.
type FigureOutput<T> = (T, String, Vec<PathBuf>);

/// Runs a figure experiment: its settings from `args` adjusted by `adjust`, a progress bar of
/// `steps(settings)` steps (a spinner when 0), then the table or the JSON and the files.
fn run_figure<T: serde::Serialize>(
    args: FigureArgs,
    adjust: impl FnOnce(&mut FigureConfig),
    steps: impl FnOnce(&FigureConfig) -> usize,
    body: impl FnOnce(&FigureConfig, &Path, &indicatif::ProgressBar) -> Result<FigureOutput<T>>,
) -> Result<()> {
    if args.trials == 0 || args.max_iters == 0 {
        bail!("--trials and --max-iters must be at least 1");
    }
    let mut config = FigureConfig {
        trials: args.trials,
        adaptive_rho: args.adaptive_rho,
        max_iters: args.max_iters,
        agent_program: Some(agent_program()?),
        ..FigureConfig::default()
    };
    adjust(&mut config);
    let steps = steps(&config);
    let bar = if steps > 0 {
        progress_bar(
            steps as u64,
            "{bar:30} {pos}/{len}, {elapsed} elapsed, ~{eta} left  {msg}",
        )
    } else {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(Duration::from_millis(200));
        bar
    };
    let result = body(&config, &args.out, &bar);
    bar.finish_and_clear();
    let (value, table, written) = result?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        print!("{table}");
    }
    for path in written {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

pub fn run(experiment: Experiment) -> Result<()> {
    use admm_ta_bench::{compare, figures, table1};
    match experiment {
        Experiment::Compare {
            robots,
            seeds,
            methods,
            transports,
            topology,
            adaptive_rho,
            max_iters,
            out,
        } => {
            if seeds == 0 || max_iters == 0 || robots.contains(&0) {
                bail!("--seeds, --max-iters and every --robots size must be at least 1");
            }
            let methods = if methods.is_empty() {
                Method::ALL.to_vec()
            } else {
                methods
            };
            let config = compare::CompareConfig {
                robots,
                seeds,
                methods,
                transports,
                topology: topology.parse()?,
                adaptive_rho,
                max_iters,
                agent_program: Some(agent_program()?),
            };
            println!("{}", compare::TABLE_HEADER);
            let rows = compare::run(&config, &|row| println!("{}", compare::render_row(row)))?;
            if let Some(dir) = out {
                std::fs::create_dir_all(&dir)
                    .with_context(|| format!("cannot create {}", dir.display()))?;
                let path = dir.join("compare.json");
                std::fs::write(&path, serde_json::to_string_pretty(&rows)?)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                eprintln!("wrote {}", path.display());
            }
            Ok(())
        }
        Experiment::Fig1Convergence { figure } => run_figure(
            figure,
            |_| {},
            |_| 0,
            |config, out, bar| {
                let (fig, written) =
                    figures::fig1_convergence(config, out, &|m| bar.set_message(m.to_string()))?;
                let table = figures::render_summaries(&fig.summaries);
                Ok((fig, table, written))
            },
        ),
        Experiment::Fig1Topologies { figure } => run_figure(
            figure,
            |_| {},
            |_| 0,
            |config, out, bar| {
                let (fig, written) =
                    figures::fig1_topologies(config, out, &|m| bar.set_message(m.to_string()))?;
                let table = figures::render_summaries(&fig.summaries);
                Ok((fig, table, written))
            },
        ),
        Experiment::Fig2Scaling {
            figure,
            sizes,
            decentralized_up_to,
        } => {
            check_sizes(&sizes)?;
            run_figure(
                figure,
                |c| {
                    c.sizes = sizes;
                    c.decentralized_up_to = decentralized_up_to;
                },
                figures::fig2_points,
                |config, out, bar| {
                    let (fig, written) = figures::fig2_scaling(config, out, &|p| {
                        bar.inc(1);
                        bar.set_message(format!("{} {} robots {}", p.topology, p.robots, p.series));
                    })?;
                    let table = figures::render_scaling(&fig.points);
                    Ok((fig, table, written))
                },
            )
        }
        Experiment::IpcScaling { figure, sizes } => {
            check_sizes(&sizes)?;
            run_figure(
                figure,
                |c| c.sizes = sizes,
                |c| c.sizes.len() * figures::ipc_methods().count(),
                |config, out, bar| {
                    let (fig, written) = figures::ipc_scaling(config, out, &|p| {
                        bar.inc(1);
                        bar.set_message(format!("{} robots {}", p.robots, p.method.name()));
                    })?;
                    let table = figures::render_ipc(&fig.points);
                    Ok((fig, table, written))
                },
            )
        }
        Experiment::Surveillance {
            episodes,
            scenario,
            transport,
            cold_start,
            max_iters,
            out,
            json,
        } => {
            use admm_ta::agents::surveillance::SurveillanceScenario;
            use admm_ta_bench::surveillance;
            if episodes == 0 || max_iters == 0 {
                bail!("--episodes and --max-iters must be at least 1");
            }
            let model = match &scenario {
                Some(path) => {
                    let text = std::fs::read_to_string(path)
                        .with_context(|| format!("cannot read {}", path.display()))?;
                    SurveillanceScenario::from_toml(&text)
                        .with_context(|| format!("{}", path.display()))?
                }
                None => SurveillanceScenario::default(),
            };
            if transport.capabilities().execution == Execution::Lockstep {
                bail!("--transport: the team runs on threads, ipc or uds");
            }
            let config = admm_ta::runtime::episodes::EpisodeRunConfig {
                max_rounds: max_iters,
                options: RunOptions::builder()
                    .transport(transport)
                    .agent_program(agent_program()?)
                    .build()?,
            };
            let bar = progress_bar(
                episodes as u64,
                "{bar:30} {pos}/{len} cold-start comparisons, {elapsed} elapsed, ~{eta} left",
            );
            bar.set_message("team running");
            let report = surveillance::run(model, episodes, !cold_start, &config, &|done| {
                bar.set_position(done as u64)
            });
            bar.finish_and_clear();
            let report = report?;
            let written = surveillance::write_outputs(&report, &out)?;
            if json {
                let mut value = serde_json::to_value(&report)?;
                // The per-episode detail is in surveillance.json; stdout stays one object.
                if let Some(map) = value.as_object_mut() {
                    map.remove("per_episode");
                }
                println!("{value}");
            } else {
                print!("{}", surveillance::render(&report));
            }
            for path in written {
                eprintln!("wrote {}", path.display());
            }
            Ok(())
        }
        Experiment::Table1 {
            trials,
            out,
            adaptive_rho,
            rho_scale,
            max_iters,
            json,
        } => {
            if trials == 0 || max_iters == 0 {
                bail!("--trials and --max-iters must be at least 1");
            }
            if !(rho_scale > 0.0 && rho_scale.is_finite()) {
                bail!("--rho-scale must be a positive number, got {rho_scale}");
            }
            let config = table1::Table1Config {
                trials,
                adaptive_rho,
                rho_scale,
                max_iters,
                ..table1::Table1Config::default()
            };
            let progress = |done: usize, total: usize| {
                if !json {
                    eprint!("\rtable1: {done}/{total} runs");
                    if done == total {
                        eprintln!();
                    }
                }
            };
            let table = table1::run(&config, &progress)?;
            let text = serde_json::to_string_pretty(&table)?;
            if let Some(dir) = out {
                std::fs::create_dir_all(&dir)
                    .with_context(|| format!("cannot create {}", dir.display()))?;
                let path = dir.join("table1.json");
                std::fs::write(&path, &text)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                if !json {
                    eprintln!("wrote {}", path.display());
                }
            }
            if json {
                println!("{text}");
            } else {
                print!("{}", table1::render(&table));
            }
            Ok(())
        }
    }
}
