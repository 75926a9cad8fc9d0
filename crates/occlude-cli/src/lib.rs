//! The `occlude` tool as a library: its output (plots, frame dumps, the
//! HTML report), the viewer and the progress bar over the benchmark harness
//! of `occlude-bench`, so that tests drive exactly what the command line
//! runs.

#![warn(missing_docs)]

pub mod bench;
pub mod output_path;
pub mod progress;
pub mod raster_bench;
pub mod report;
pub mod stdout;
pub mod view;
