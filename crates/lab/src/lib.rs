//! Experiments of manylights: the RON schema ([`experiment`]) and its expansion into cells
//! (`cells`), the durable, resumable, shardable runner ([`runner`]) and what it measures at each
//! camera pose (`evaluate`), results as CSV and JSON ([`results`]), culling timed in steady
//! state ([`steady`]), the tuner ([`tune`]), paper-style reports in Markdown and HTML ([`report`]) with their figures
//! (`figures`), the stability suite's verdicts ([`stability`]), a run's data exported as
//! NumPy arrays ([`export`]), the infinite-range reference cached in the run folder
//! ([`reference_cache`]), and stochastic light culling's noise measured over seeds (`noise`).
//!
//! Depends on every other crate; nothing depends on it but the CLI.

mod budgets;
mod camera_spec;
mod cell_row;
mod cell_run;
mod cells;
mod dynamic;
mod evaluate;
pub mod experiment;
pub mod export;
mod figures;
mod forward_deferred;
mod noise;
pub mod reference_cache;
mod renderers;
pub mod report;
pub mod result_files;
pub mod results;
pub mod runner;
pub mod score;
pub mod stability;
pub mod steady;
pub mod tune;

pub use cells::RADIUS_PREFIXES;
pub use experiment::{Cell, Config, Experiment};
pub use results::Row;

/// Errors of experiments.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// A malformed experiment file.
    #[error("{file}:{line}:{col}: {message}")]
    Parse {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// What is wrong.
        message: String,
    },
    /// A file or directory that cannot be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The path.
        path: String,
        /// Why.
        message: String,
    },
    /// A cell that failed to run.
    #[error("cell {index} `{name}` failed: {message}")]
    Cell {
        /// Its index.
        index: usize,
        /// Its name.
        name: String,
        /// Why.
        message: String,
    },
    /// Anything else, with its context.
    #[error("{0}")]
    Other(String),
}

/// Writes `path` through a temporary file in its directory (no partial files).
pub(crate) fn write_atomic(path: &std::path::Path, bytes: &[u8]) -> Result<(), LabError> {
    manylights_shade::image_out::write_atomic(path, |w| {
        std::io::Write::write_all(w, bytes).map_err(|e| e.to_string())
    })
    .map_err(|e| LabError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}
