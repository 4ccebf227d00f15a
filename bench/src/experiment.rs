//! The one run → report → write path every experiment shares: an experiment runs into a
//! report that implements [`Experiment`] (its JSON file, its printed table, its other files:
//! CSV tables and SVG charts), and [`write()`] puts all of it into the output directory.

use crate::plot::{Chart, PlotError};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// An experiment's report: what it prints and what it writes.
pub trait Experiment: Serialize {
    /// The file the whole report goes to as JSON, e.g. `table1.json`.
    fn json_file(&self) -> &'static str;

    /// The table or summary printed after the run.
    fn render(&self) -> String;

    /// Its other files by name: CSV tables and SVG charts.
    fn files(&self) -> Vec<(String, OutputFile)> {
        Vec::new()
    }
}

/// A file of an experiment besides its JSON.
pub enum OutputFile {
    Text(String),
    /// Drawn as SVG; a chart with nothing to draw is left out.
    Chart(Chart),
}

/// Why an experiment's files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot create {}", .dir.display())]
    Create {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write {}", .path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// Writes `report` into `dir` (created if missing): its JSON, then its other files in order.
/// Returns the paths written.
pub fn write(report: &impl Experiment, dir: &Path) -> Result<Vec<PathBuf>, OutputError> {
    std::fs::create_dir_all(dir).map_err(|source| OutputError::Create {
        dir: dir.to_path_buf(),
        source,
    })?;
    let json = serde_json::to_string_pretty(report).expect("reports serialise");
    let mut files = vec![(report.json_file().to_string(), OutputFile::Text(json))];
    files.extend(report.files());
    let mut written = Vec::new();
    for (name, file) in files {
        let path = dir.join(name);
        match file {
            OutputFile::Text(text) => {
                std::fs::write(&path, text).map_err(|source| OutputError::Write {
                    path: path.clone(),
                    source,
                })?
            }
            OutputFile::Chart(chart) => match chart.write(&path) {
                Ok(()) => {}
                Err(PlotError::Empty(_)) => continue,
                Err(e) => return Err(e.into()),
            },
        }
        written.push(path);
    }
    Ok(written)
}

/// Mean of the values (`None` when there are none).
pub fn mean_of(values: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (sum, count) = values
        .into_iter()
        .fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
    (count > 0).then(|| sum / count as f64)
}
