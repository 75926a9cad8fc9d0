//! The occlude benchmark harness as a library: every culling method run
//! over the same scene, hierarchy and walkthrough, each frame checked
//! against view-frustum culling's depth image ([`runner`]), summarised into
//! the report the `occlude` command prints and writes ([`summary`],
//! [`table`], [`output`]); the papers' experiments ([`paper`], [`gvq`]),
//! the GPU model's calibration ([`calibrate`]) and the rasterizer
//! benchmarks ([`raster_bench`]).
//!
//! A comparison of two methods on a small generated scene, on the soft
//! backend (deterministic, simulated GPU times):
//!
//! ```
//! use occlude_bench::{BenchConfig, Error};
//!
//! let config = BenchConfig {
//!     methods: vec!["vfc".into(), "chcpp".into()],
//!     frames: 6,
//!     resolution: (160, 120),
//!     ..BenchConfig::default()
//! };
//! // `&()`: no progress shown.
//! let report = occlude_bench::run(&config, &())?.report(&config);
//! let [vfc, chcpp] = &report.methods[..] else { panic!("two methods") };
//! // Every frame of chcpp's is vfc's image, pixel for pixel...
//! assert!(chcpp.per_frame.iter().all(|f| f.missing_pixels == 0));
//! // ...drawing no more than vfc, which draws everything in view.
//! let triangles = |m: &occlude_bench::MethodSummary| m.per_frame.iter().map(|f| f.triangles).sum::<u64>();
//! assert!(triangles(chcpp) <= triangles(vfc));
//! # Ok::<(), Error>(())
//! ```

#![warn(missing_docs)]

pub mod calibrate;
pub mod camera_path;
pub mod config;
pub mod error;
pub mod figures;
pub mod gvq;
pub mod gvq_parts;
pub mod gvq_parts_gpu;
pub mod gvq_shadows;
pub mod gvq_shadows_gpu;
pub mod ideal;
pub mod limits;
pub mod output;
pub mod paper;
pub mod paper_tables;
pub mod progress;
pub mod published;
pub mod raster_bench;
pub mod runner;
pub mod scenes;
pub mod sim_gpu;
pub mod summary;
pub mod table;

pub use config::{BackendKind, BenchConfig};
pub use error::{Error, Result};
pub use progress::Progress;
pub use runner::{run, BenchRun};
pub use summary::{BenchReport, MethodSummary};
