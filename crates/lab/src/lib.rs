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
mod columns;
mod evaluate;
pub mod experiment;
pub mod export;
mod figures;
mod forward_deferred;
mod frame_lights;
mod noise;
mod old_rows;
pub mod reference_cache;
mod references;
mod renderers;
pub mod report;
pub mod result_files;
pub mod results;
pub mod runner;
pub mod score;
pub mod stability;
pub mod steady;
pub mod tune;

pub use cells::RADIUS_AXES;
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
    /// Cells of a run that failed (each recorded with its error in the results).
    #[error("{count} cells failed: {cells} (their rows hold why; run again to retry them)")]
    CellsFailed {
        /// How many.
        count: usize,
        /// Each one's error, `; ` between them.
        cells: String,
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
    /// A scene that could not be built, loaded or lit (its field and value named).
    #[error(transparent)]
    Scene(#[from] manylights_scene::SceneError),
    /// The device refused or failed (a limit, a missing feature, a lost device).
    #[error(transparent)]
    Gpu(#[from] manylights_gpu::GpuError),
    /// Culling or shading refused or failed (a parameter, a limit, the GPU).
    #[error(transparent)]
    Cull(#[from] manylights_cull::CullError),
    /// A frame could not be rendered.
    #[error(transparent)]
    Shade(#[from] manylights_shade::ShadeError),
    /// Steady-state timing failed.
    #[error(transparent)]
    Steady(#[from] steady::SteadyError),
    /// An image could not be encoded.
    #[error(transparent)]
    Image(#[from] image::ImageError),
    /// A step of a cell failed: what it was doing, and why.
    #[error("{step}: {source}")]
    Step {
        /// What the cell was doing (`export`, `msaa = 4`, ...).
        step: String,
        /// Why it failed.
        source: Box<LabError>,
    },
    /// The lighting grid hierarchy's build dropped splats: its tables or boxes were too small
    /// for the frame's lights.
    #[error(
        "the lighting grid hierarchy dropped {outside} splats outside its grids' boxes and {full} \
         into full tables (its shape is planned from the lights at every frame the cell renders, \
         its boxes with room for moving lights to go their radius from home)"
    )]
    HierarchyDropped {
        /// Splats outside the grids' boxes.
        outside: u64,
        /// Splats into full tables.
        full: u64,
    },
    /// A figure of a report could not be drawn.
    #[error("report figure: {0}")]
    Figure(String),
    /// A request the workbench refuses: what was asked, and why.
    #[error("{what}: {why}")]
    Refused {
        /// What was asked (`export`, `merge`, `tune`, a directory).
        what: String,
        /// Why, and what would do.
        why: String,
    },
}

impl LabError {
    /// A refusal of `what`, for `why`.
    pub(crate) fn refused(what: impl Into<String>, why: impl Into<String>) -> Self {
        Self::Refused {
            what: what.into(),
            why: why.into(),
        }
    }
}

impl LabError {
    /// This error as the failure of `step`.
    pub(crate) fn during(self, step: impl Into<String>) -> Self {
        Self::Step {
            step: step.into(),
            source: Box::new(self),
        }
    }
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
