//! `occlude raster-bench`: the options of the rasterizer benchmarks
//! (`occlude_bench::raster_bench`), their tables printed and their JSON
//! written.

use anyhow::{Context, Result};
use occlude_bench::limits::{parse_resolution, parse_seconds, parse_threads, parse_triangles_per_call};
use occlude_bench::raster_bench::{measure, render, RasterBenchConfig, WgpuRaster};
use occlude_wgpu::GpuContext;
use std::path::PathBuf;
use std::sync::Arc;

/// Options of `occlude raster-bench`.
#[derive(clap::Args, Debug, Clone)]
pub struct RasterBenchArgs {
    /// Leg lengths N of the fill-rate triangles, in pixels, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [10, 25, 50, 100, 250, 500],
          value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub sizes: Vec<u32>,
    /// Triangles drawn per call, 1 to 4000000 (default: about two screens of
    /// pixels, at least 64, at most 4000000).
    #[arg(long, value_parser = parse_triangles_per_call)]
    pub triangles_per_size: Option<u64>,
    /// Seconds to measure each fill-rate row for (calls repeat until they are
    /// spent, at least three; the median call is reported); query rows get a third
    /// of it; at most 600.
    #[arg(long, default_value_t = 0.75, value_parser = parse_seconds)]
    pub seconds_per_row: f64,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1920x1080", value_parser = parse_resolution)]
    pub resolution: (u32, u32),
    /// Thread counts to run the soft rasterizer with, comma-separated, each 1
    /// to 256.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2],
          value_parser = |s: &str| parse_threads(s).map(|t| t as u32))]
    pub threads: Vec<u32>,
    /// Whether to also measure the wgpu backend: `auto` when a GPU adapter opens,
    /// `off`, or `required` (a missing adapter is an error).
    #[arg(long, value_enum, default_value_t = GpuChoice::Auto)]
    pub gpu: GpuChoice,
    /// Write the results as JSON.
    #[arg(long, value_name = "FILE", value_parser = crate::output_path::parse_output_path)]
    pub json: Option<PathBuf>,
}

/// Whether `occlude raster-bench` measures the wgpu backend.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuChoice {
    /// When a GPU adapter opens.
    Auto,
    /// Never.
    Off,
    /// Always: a missing adapter is an error.
    Required,
}

impl RasterBenchArgs {
    /// What the options ask to measure.
    pub fn config(&self) -> RasterBenchConfig {
        RasterBenchConfig {
            sizes: self.sizes.clone(),
            triangles_per_size: self.triangles_per_size,
            seconds_per_row: self.seconds_per_row,
            resolution: self.resolution,
            threads: self.threads.clone(),
        }
    }
}

/// `occlude raster-bench`: measures the soft rasterizer and the masked
/// buffer on each thread count and the wgpu backend as `--gpu` says, prints
/// the tables and writes the JSON.
pub fn run(args: &RasterBenchArgs) -> Result<()> {
    let config = args.config();
    let mut backends = config.cpu_backends()?;
    if args.gpu != GpuChoice::Off {
        match GpuContext::new() {
            Ok(ctx) => backends.push(Box::new(WgpuRaster::new(Arc::new(ctx)))),
            Err(e) if args.gpu == GpuChoice::Auto => eprintln!("no wgpu rows: {e}"),
            Err(e) => return Err(e.into()),
        }
    }
    let progress = crate::progress::bar(0, "rows");
    let report = measure(&config, &mut backends, &progress)?;
    progress.finish_and_clear();
    if let Some(path) = &args.json {
        let json = serde_json::to_string_pretty(&report)?;
        std::fs::write(path, json + "\n").with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    crate::stdout::print(&render(&report, config.resolution))
}
