//! `occlude bench --paper gvq`: the granular-visibility-queries paper's
//! Table 2 (section 4.1): summed-area-table queries of 100 to 500 randomly
//! placed objects of 606 triangles (`occlude_scenes::scattered`), the CPU
//! time of the overlap test, the colouring and split and merge, the
//! conflict objects, and the mean absolute and relative errors of the
//! counts against the exact ones, beside the paper's figures
//! (`published.toml`). Counts come from the soft backend
//! (`occlude_soft::sat`), at the paper's 512 x 512 query resolution unless
//! told otherwise, over the walkthrough circling the objects; both region
//! modes are run (the paper's Table 2 does not say which it used).

use super::config::{BackendKind, BenchConfig, NEAR_PLANE};
use super::published::{self, PublishedTable};
use super::runner::far_plane;
use anyhow::Result;
use indicatif::ProgressBar;
use occlude_core::gvq::{RegionMode, SatConfig};
use occlude_scenes::scattered::scattered;
use occlude_soft::sat::{SatSummary, SoftSat};
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// Object counts of the paper's rows.
pub const OBJECTS: [u32; 5] = [100, 200, 300, 400, 500];

/// The paper's query resolution ("All culling techniques use a 512²
/// resolution render target for determining visibility", Table 1).
pub const RESOLUTION: (u32, u32) = (512, 512);

/// What `--paper gvq --json FILE` writes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GvqTables {
    /// `gvq`.
    pub paper: String,
    /// Its tables, in the order printed.
    pub tables: Vec<GvqTable>,
}

/// One table of the paper's.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GvqTable {
    /// The paper's name for it.
    pub name: String,
    /// Where the published figures come from.
    pub source: Option<String>,
    /// Our rows.
    pub rows: Vec<GvqRow>,
}

/// One row of Table 2: per-frame means over the walkthrough.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GvqRow {
    /// Objects in the scene.
    pub objects: u32,
    /// Region mode (`conservative` or `approximate`).
    pub mode: RegionMode,
    /// Colour targets (four channels each).
    pub targets: u32,
    /// Objects on screen (the queries).
    pub queries: f64,
    /// Conflict objects.
    pub conflicts: f64,
    /// The paper's.
    pub published_conflicts: Option<f64>,
    /// Summed-area-table lookups.
    pub lookups: f64,
    /// Overlap test, CPU ms.
    pub overlap_ms: f64,
    /// The paper's.
    pub published_overlap_ms: Option<f64>,
    /// Colouring, CPU ms.
    pub colouring_ms: f64,
    /// The paper's.
    pub published_colouring_ms: Option<f64>,
    /// Split and merge, CPU ms.
    pub split_merge_ms: f64,
    /// The paper's.
    pub published_split_merge_ms: Option<f64>,
    /// Mean absolute error of the counts, pixels.
    pub abs_error_px: f64,
    /// The paper's.
    pub published_abs_error_px: Option<f64>,
    /// Mean relative error of the counts, percent.
    pub rel_error_pct: f64,
    /// The paper's.
    pub published_rel_error_pct: Option<f64>,
    /// Relative error of the summed counts, percent
    /// (`CountErrors::rel_error_of_sums_pct`; the paper gives none).
    #[serde(default)]
    pub rel_error_of_sums_pct: f64,
    /// Frames averaged.
    pub frames: usize,
}

impl GvqRow {
    /// The mean of `frames`' summaries, beside `published`'s row of
    /// `objects`.
    fn new(objects: u32, config: &SatConfig, frames: &[SatSummary], published: Option<&PublishedTable>) -> Self {
        let mean = |f: fn(&SatSummary) -> f64| frames.iter().map(f).sum::<f64>() / frames.len().max(1) as f64;
        let p = published.and_then(|t| t.rows.iter().find(|r| r.objects == Some(objects)));
        Self {
            objects,
            mode: config.mode,
            targets: config.targets,
            queries: mean(|s| f64::from(s.objects)),
            conflicts: mean(|s| f64::from(s.conflicts)),
            published_conflicts: p.and_then(|r| r.conflicts),
            lookups: mean(|s| f64::from(s.lookups)),
            overlap_ms: mean(|s| s.timings.overlap_ms),
            published_overlap_ms: p.and_then(|r| r.overlap_ms),
            colouring_ms: mean(|s| s.timings.colouring_ms),
            published_colouring_ms: p.and_then(|r| r.colouring_ms),
            split_merge_ms: mean(|s| s.timings.split_merge_ms),
            published_split_merge_ms: p.and_then(|r| r.split_merge_ms),
            abs_error_px: mean(|s| s.errors.abs_error_px),
            published_abs_error_px: p.and_then(|r| r.abs_error_px),
            rel_error_pct: mean(|s| s.errors.rel_error_pct),
            published_rel_error_pct: p.and_then(|r| r.rel_error_pct),
            rel_error_of_sums_pct: mean(|s| s.errors.rel_error_of_sums_pct),
            frames: frames.len(),
        }
    }
}

/// Runs Table 2 with the seed, frames and resolution of `base` (module
/// documentation); returns the printed table and its JSON.
pub fn run(base: &BenchConfig, progress: &ProgressBar) -> Result<(String, GvqTables)> {
    if base.backend != BackendKind::Soft {
        anyhow::bail!(
            "--paper gvq runs on the soft backend only (the wgpu backend's counts, occlude_wgpu::GpuSat, are tested against it but not benchmarked yet)"
        );
    }
    let published = published::table("gvq", "Table 2");
    let configs =
        [RegionMode::Conservative, RegionMode::Approximate].map(|mode| SatConfig { mode, ..SatConfig::default() });
    let (w, h) = base.resolution;
    let mut text = format!(
        "Granular visibility queries — Table 2: summed-area-table queries, per frame ({w}x{h}, {} target(s), \
         soft backend, CPU ms measured; paper's figures in brackets)\n\
         objects  mode          queries  conflicts  (paper)  lookups  overlap ms (paper)  colouring ms (paper)  \
         split+merge ms (paper)  abs err px (paper)  rel err % (paper)  rel err of sums %\n",
        configs[0].targets
    );
    let mut rows = Vec::new();
    for objects in OBJECTS {
        let scene = scattered(objects, base.seed);
        let cameras = scene.path.sample_with(base.sampling(), w as f32 / h as f32, NEAR_PLANE, far_plane(&scene));
        progress.set_message(format!("gvq: {objects} objects"));
        progress.inc_length(cameras.len() as u64);
        let mut sat = SoftSat::new(w, h);
        let mut summaries = vec![Vec::with_capacity(cameras.len()); configs.len()];
        for camera in &cameras {
            for (frames, frame) in summaries.iter_mut().zip(sat.query(&scene, camera, &configs)) {
                frames.push(frame.summary());
            }
            progress.inc(1);
        }
        for (config, frames) in configs.iter().zip(&summaries) {
            let row = GvqRow::new(objects, config, frames, published);
            let paper = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v}"));
            let _ = writeln!(
                text,
                "{:>7}  {:<12} {:>8.1} {:>10.1} {:>8} {:>8.1} {:>11.3} {:>6} {:>13.3} {:>6} {:>15.3} {:>6} {:>11.2} {:>6} {:>10.2} {:>6} {:>18.2}",
                row.objects,
                format!("{:?}", row.mode).to_lowercase(),
                row.queries,
                row.conflicts,
                paper(row.published_conflicts),
                row.lookups,
                row.overlap_ms,
                paper(row.published_overlap_ms),
                row.colouring_ms,
                paper(row.published_colouring_ms),
                row.split_merge_ms,
                paper(row.published_split_merge_ms),
                row.abs_error_px,
                paper(row.published_abs_error_px),
                row.rel_error_pct,
                paper(row.published_rel_error_pct),
                row.rel_error_of_sums_pct,
            );
            rows.push(row);
        }
    }
    let table = GvqTable { name: "Table 2".into(), source: published.map(|t| t.source.clone()), rows };
    Ok((text, GvqTables { paper: "gvq".into(), tables: vec![table] }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_2_has_a_row_per_count_and_mode_beside_the_papers_figures() {
        let base = BenchConfig { frames: 2, resolution: (64, 64), ..BenchConfig::default() };
        let (text, tables) = run(&base, &ProgressBar::hidden()).unwrap();
        let rows = &tables.tables[0].rows;
        assert_eq!(rows.len(), 10);
        let row500 = rows.iter().find(|r| r.objects == 500 && r.mode == RegionMode::Conservative).unwrap();
        assert_eq!((row500.published_abs_error_px, row500.published_rel_error_pct), (Some(7.4), Some(11.6)));
        assert_eq!(row500.published_conflicts, Some(249.0));
        assert!(row500.queries > 0.0 && row500.frames == 2);
        assert!(tables.tables[0].source.as_deref().is_some_and(|s| s.contains("Table 2")));
        assert!(text.contains("Table 2"));
        let json = serde_json::to_value(&tables).unwrap();
        for key in ["objects", "conflicts", "abs_error_px", "rel_error_pct", "published_abs_error_px"] {
            assert!(json["tables"][0]["rows"][0].get(key).is_some(), "{key}");
        }
        let wgpu = BenchConfig { backend: BackendKind::Wgpu, ..base };
        assert!(run(&wgpu, &ProgressBar::hidden()).is_err());
    }
}
