//! `occlude bench --paper gvq`: the granular-visibility-queries paper's
//! Tables 1 to 3. Table 1 (section 4.1, shadow-volume culling) is
//! [`crate::gvq_shadows`]'s and Table 3 (section 4.2, culling parts of one
//! heavy object) [`crate::gvq_parts`]'s, both on the soft backend's
//! simulated clock (with `--backend wgpu`, both run on the GPU and are
//! timed there, [`crate::gvq_shadows_gpu`] and [`crate::gvq_parts_gpu`]),
//! printed and written after Table 2. Table 2
//! (section 4.1): summed-area-table queries of 100 to 500 randomly
//! placed objects of 606 triangles (`occlude_scenes::scattered`), the CPU
//! time of the overlap test, the colouring and split and merge, the
//! conflict objects, and the mean absolute and relative errors of the
//! counts against the exact ones, beside the paper's figures
//! (`published.toml`). The region sets and the exact counts come from the
//! soft backend (`occlude_soft::sat`); the counts from its summed area
//! tables, or with `--backend wgpu` from the GPU's
//! (`occlude_wgpu::GpuSat`, the same plans drawn, summed and looked up on
//! the GPU), at the paper's 512 x 512 query resolution unless told
//! otherwise, over the walkthrough circling the objects; both region modes
//! are run (the paper's Table 2 does not say which it used).

use crate::config::{BackendKind, BenchConfig};
use crate::error::{Error, Result};
use crate::gvq_parts::{self, PartsRow};
use crate::gvq_parts_gpu;
use crate::gvq_shadows::{self, ShadowRow};
use crate::gvq_shadows_gpu;
use crate::paper_tables::{PaperTables, Table};
use crate::progress::Progress;
use crate::published::{self, PublishedTable};
use occlude_core::gvq::{RegionMode, SatConfig};
use occlude_core::{Camera, Scene};
use occlude_scenes::scattered::scattered;
use occlude_soft::sat::{SatFrame, SatSummary, SoftSat};
use occlude_wgpu::{GpuContext, GpuSat};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::sync::Arc;

/// Object counts of the paper's rows.
pub const OBJECTS: [u32; 5] = [100, 200, 300, 400, 500];

/// The paper's query resolution ("All culling techniques use a 512²
/// resolution render target for determining visibility", Table 1).
pub const RESOLUTION: (u32, u32) = (512, 512);

/// What `--paper gvq --json FILE` writes.
pub type GvqTables = PaperTables<GvqRows>;

/// One table of the paper's.
pub type GvqTable = Table<GvqRows>;

/// The rows of one table, each table with columns of its own.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum GvqRows {
    /// Table 1: frame times of shadow-volume culling.
    Table1(Vec<ShadowRow>),
    /// Table 2: summed-area-table errors and CPU times.
    Table2(Vec<GvqRow>),
    /// Table 3: frame times of culling parts of one heavy object.
    Table3(Vec<PartsRow>),
}

/// One row of Table 2: per-frame means over the walkthrough.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GvqRow {
    /// Objects in the scene.
    pub objects: u32,
    /// Region mode (`conservative` or `approximate`).
    pub mode: RegionMode,
    /// The backend whose summed area tables counted (`soft` or `wgpu`).
    #[serde(default)]
    pub backend: String,
    /// Objects per frame whose count differs from the soft backend's
    /// count of the same plan (0 on the soft backend).
    #[serde(default)]
    pub differing_from_soft: f64,
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
    /// The mean of `frames`' summaries counted on `backend`, beside
    /// `published`'s row of `objects`.
    fn new(
        objects: u32,
        config: &SatConfig,
        backend: &str,
        frames: &[Counted],
        published: Option<&PublishedTable>,
    ) -> Self {
        let differing = frames.iter().map(|f| f64::from(f.differing_from_soft)).sum::<f64>();
        let frames: Vec<SatSummary> = frames.iter().map(|f| f.summary).collect();
        let frames = frames.as_slice();
        let mean = |f: fn(&SatSummary) -> f64| frames.iter().map(f).sum::<f64>() / frames.len().max(1) as f64;
        let p = published.and_then(|t| t.rows.iter().find(|r| r.objects == Some(objects)));
        Self {
            objects,
            mode: config.mode,
            backend: backend.to_string(),
            differing_from_soft: differing / frames.len().max(1) as f64,
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

/// One frame's counts of one region mode on the backend benchmarked.
#[derive(Clone, Copy, Debug)]
struct Counted {
    /// The Table 2 row of the frame, its errors those of the backend's counts.
    summary: SatSummary,
    /// Objects whose count differs from the soft backend's.
    differing_from_soft: u32,
}

/// Where the counts come from: the soft backend's summed area tables, or
/// the GPU's of the same plans.
enum Counter {
    Soft,
    Wgpu(GpuSat),
}

impl Counter {
    /// Counters for `configs` on `base`'s backend and resolution (one GPU
    /// opened for all).
    fn for_configs(base: &BenchConfig, configs: &[SatConfig]) -> Result<Vec<Self>> {
        let (w, h) = base.resolution;
        Ok(match base.backend {
            BackendKind::Soft => configs.iter().map(|_| Self::Soft).collect(),
            BackendKind::Wgpu => {
                let ctx = Arc::new(GpuContext::new()?);
                configs.iter().map(|c| Self::Wgpu(GpuSat::new(Arc::clone(&ctx), w, h, c.targets))).collect()
            }
        })
    }

    fn name(&self) -> &'static str {
        match self {
            Self::Soft => "soft",
            Self::Wgpu(_) => "wgpu",
        }
    }

    /// `frame`'s counts on this backend, against the exact counts.
    fn count(&self, scene: &Scene, camera: &Camera, frame: &SatFrame) -> Result<Counted> {
        let mut summary = frame.summary();
        let differing_from_soft = match self {
            Self::Soft => 0,
            Self::Wgpu(gpu) => {
                let counts = gpu.query(scene, camera, &frame.plan).map_err(Error::Backend)?.counts;
                summary.errors = frame.errors_of(&counts);
                counts.iter().zip(&frame.counts).filter(|(g, s)| g != s).count() as u32
            }
        };
        Ok(Counted { summary, differing_from_soft })
    }
}

/// Runs Table 2 with the seed, frames, resolution and backend of `base`,
/// Table 3 at its resolution with its GPU model (or on its backend's GPU,
/// at most [`gvq_parts_gpu::FRAMES`] of its frames), and Table 1 with its
/// seed, resolution and GPU model (or on its backend's GPU) on at most
/// [`gvq_shadows::FRAMES`] of its frames (module documentation); returns
/// the printed tables and their JSON, in that order.
pub fn run(base: &BenchConfig, progress: &dyn Progress) -> Result<(String, GvqTables)> {
    let (mut text, table_2) = table_2(base, &OBJECTS, progress)?;
    progress.message("gvq: Table 3");
    let (w, h) = base.resolution;
    let published = published::table("gvq", "Table 3");
    let ctx = match base.backend {
        BackendKind::Soft => None,
        BackendKind::Wgpu => Some(Arc::new(GpuContext::new()?)),
    };
    let clock = match &ctx {
        None => format!("soft backend, simulated clock, GPU model {}", base.gpu_model.name),
        Some(ctx) => format!("wgpu backend on {}, measured wall-clock ms", ctx.adapter_name()),
    };
    let parts = match &ctx {
        None => gvq_parts::table_3(w, h, &base.gpu_model, published),
        Some(ctx) => {
            let frames = base.frames.clamp(1, gvq_parts_gpu::FRAMES);
            gvq_parts_gpu::table_3(Arc::clone(ctx), w, h, frames, published)?
        }
    };
    text.push('\n');
    text.push_str(&gvq_parts::print(&parts, w, h, &clock));
    let table_3 = Table::unordered("Table 3", published, GvqRows::Table3(parts));
    let published = published::table("gvq", "Table 1");
    let shadows = match ctx {
        None => gvq_shadows::table_1(base, &OBJECTS, published, progress),
        Some(ctx) => gvq_shadows_gpu::table_1(ctx, base, &OBJECTS, published, progress)?,
    };
    text.push('\n');
    text.push_str(&gvq_shadows::print(&shadows, w, h, &clock));
    let table_1 = Table::unordered("Table 1", published, GvqRows::Table1(shadows));
    Ok((text, GvqTables { paper: "gvq".into(), tables: vec![table_2, table_3, table_1], reports: Vec::new() }))
}

/// Table 2 over scenes of `counts` objects: the printed table and its rows.
fn table_2(base: &BenchConfig, counts: &[u32], progress: &dyn Progress) -> Result<(String, GvqTable)> {
    let published = published::table("gvq", "Table 2");
    let configs =
        [RegionMode::Conservative, RegionMode::Approximate].map(|mode| SatConfig { mode, ..SatConfig::default() });
    let counters = Counter::for_configs(base, &configs)?;
    let backend = counters[0].name();
    let (w, h) = base.resolution;
    let mut text = format!(
        "Granular visibility queries — Table 2: summed-area-table queries, per frame ({w}x{h}, {} target(s), \
         {backend} backend's counts, CPU ms measured; paper's figures in brackets)\n\
         objects  mode          queries  conflicts  (paper)  lookups  overlap ms (paper)  colouring ms (paper)  \
         split+merge ms (paper)  abs err px (paper)  rel err % (paper)  rel err of sums %  differ from soft\n",
        configs[0].targets
    );
    let mut rows = Vec::new();
    for &objects in counts {
        let scene = scattered(objects, base.seed);
        let cameras = crate::runner::cameras(&scene, base)?;
        progress.message(&format!("gvq: {objects} objects"));
        progress.add_steps(cameras.len() as u64);
        let mut sat = SoftSat::new(w, h);
        let mut counted = vec![Vec::with_capacity(cameras.len()); configs.len()];
        for camera in &cameras {
            let frames = sat.query(&scene, camera, &configs);
            for ((into, counter), frame) in counted.iter_mut().zip(&counters).zip(&frames) {
                into.push(counter.count(&scene, camera, frame)?);
            }
            progress.advance(1);
        }
        for (config, frames) in configs.iter().zip(&counted) {
            let row = GvqRow::new(objects, config, backend, frames, published);
            let paper = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v}"));
            let _ = writeln!(
                text,
                "{:>7}  {:<12} {:>8.1} {:>10.1} {:>8} {:>8.1} {:>11.3} {:>6} {:>13.3} {:>6} {:>15.3} {:>6} {:>11.2} {:>6} {:>10.2} {:>6} {:>18.2} {:>17.2}",
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
                row.differing_from_soft,
            );
            rows.push(row);
        }
    }
    Ok((text, Table::unordered("Table 2", published, GvqRows::Table2(rows))))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table 2's rows.
    fn rows_2(table: &GvqTable) -> &[GvqRow] {
        match &table.rows {
            GvqRows::Table2(rows) => rows,
            _ => panic!("{} has no Table 2 rows", table.name),
        }
    }

    #[test]
    fn tables_2_and_3_have_their_rows_beside_the_papers_figures() {
        let base = BenchConfig { frames: 2, resolution: (64, 64), ..BenchConfig::default() };
        let (text, tables) = run(&base, &()).unwrap();
        let rows = rows_2(&tables.tables[0]);
        assert_eq!(rows.len(), 10);
        let row500 = rows.iter().find(|r| r.objects == 500 && r.mode == RegionMode::Conservative).unwrap();
        assert_eq!((row500.published_abs_error_px, row500.published_rel_error_pct), (Some(7.4), Some(11.6)));
        assert_eq!(row500.published_conflicts, Some(249.0));
        assert!(row500.queries > 0.0 && row500.frames == 2);
        assert!(tables.tables[0].source.as_deref().is_some_and(|s| s.contains("Table 2")));
        assert!(text.contains("Table 2"));
        let json = serde_json::to_value(&tables).unwrap();
        assert!(json.get("reports").is_none() && json["tables"][0].get("ordering_agrees").is_none(), "{json}");
        for key in ["objects", "conflicts", "abs_error_px", "rel_error_pct", "published_abs_error_px"] {
            assert!(json["tables"][0]["rows"][0].get(key).is_some(), "{key}");
        }
        assert!(rows.iter().all(|r| r.backend == "soft" && r.differing_from_soft == 0.0));
        assert_eq!(tables.tables[1].name, "Table 3");
        assert!(matches!(&tables.tables[1].rows, GvqRows::Table3(rows) if !rows.is_empty()));
        for key in ["method", "view", "frame_ms"] {
            assert!(json["tables"][1]["rows"][0].get(key).is_some(), "{key}");
        }
        let back: GvqTables = serde_json::from_value(json.clone()).unwrap();
        assert!(
            matches!(&back.tables[0].rows, GvqRows::Table2(_)) && matches!(&back.tables[1].rows, GvqRows::Table3(_))
        );
        assert!(text.contains("Table 3"));
        assert_eq!(back.tables[2].name, "Table 1");
        assert!(matches!(&back.tables[2].rows, GvqRows::Table1(rows) if rows.len() == 25));
        for key in ["objects", "method", "frame_ms", "published_frame_ms", "published_fps_gtx280"] {
            assert!(json["tables"][2]["rows"][0].get(key).is_some(), "{key}");
        }
        assert!(text.contains("Table 1"));
    }

    /// `--backend wgpu`: the GPU's summed area tables count the soft
    /// backend's plans of the same frames as the soft backend does.
    #[test]
    fn wgpu_table_2_counts_equal_the_soft_backends() {
        if occlude_wgpu::GpuContext::for_test("wgpu_table_2_counts_equal_the_soft_backends").is_none() {
            return;
        }
        let soft = BenchConfig { frames: 3, resolution: (64, 48), ..BenchConfig::default() };
        let wgpu = BenchConfig { backend: BackendKind::Wgpu, ..soft.clone() };
        let (_, on_soft) = table_2(&soft, &[150], &()).unwrap();
        let (text, on_gpu) = table_2(&wgpu, &[150], &()).unwrap();
        assert!(text.contains("wgpu backend"));
        let (soft_rows, gpu_rows) = (rows_2(&on_soft), rows_2(&on_gpu));
        assert_eq!(gpu_rows.len(), 2);
        for (s, g) in soft_rows.iter().zip(gpu_rows) {
            assert_eq!(g.backend, "wgpu");
            assert!(g.queries > 0.0 && g.conflicts > 0.0, "{g:?}: no conflict to count");
            assert_eq!(g.differing_from_soft, 0.0, "{:?}: counts differ from soft's", g.mode);
            assert_eq!((g.abs_error_px, g.rel_error_pct), (s.abs_error_px, s.rel_error_pct), "{:?}", g.mode);
        }
    }
}
