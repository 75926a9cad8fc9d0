//! The `occlude` tool as a library: the benchmark runner and its reports, and
//! the viewer, so that tests drive exactly what the command line runs.

#![warn(missing_docs)]

pub mod bench;
pub mod calibrate;
pub mod camera_path;
pub mod figures;
pub mod limits;
pub mod output_path;
pub mod progress;
pub mod raster_bench;
pub mod report;
pub mod scenes;
pub mod stdout;
pub mod view;
