//! `occlude bench`: every method on the same scene, hierarchy and camera path,
//! with the comparison table of the CHC paper (Table 1) and JSON/CSV output in
//! the schema of `docs/design.md`.

pub mod config;
pub mod dump;
pub mod gvq;
pub mod gvq_parts;
pub mod gvq_parts_gpu;
pub mod gvq_shadows;
pub mod gvq_shadows_gpu;
pub mod ideal;
pub mod output;
pub mod paper;
pub mod paper_figures;
pub mod paper_tables;
pub mod plot;
pub mod published;
pub mod runner;
pub mod sim_gpu;
pub mod summary;
pub mod table;

pub use config::BenchConfig;
pub use runner::{run, BenchRun};
pub use summary::{BenchReport, MethodSummary};
