//! The rasterizer benchmarks of `occlude raster-bench`: the field's rasterizer benchmarks, for comparing the soft
//! rasterizer with other depth rasterizers on the same triangles.
//!
//! - Fill rate: random right triangles with legs of `N` pixels at random positions
//!   and rotations, drawn back to front (every fragment passes the depth test),
//!   reported in MTris/s and GPixels/s (pixels = triangles x N^2 / 2).
//! - Occlusion queries: query boxes covering 1%, 10% and 50% of the screen against a
//!   screen-filling occluder, in front of it (visible) and behind it (hidden), counting
//!   the passing fragments or only asking whether any passes; in queries per second.
//!
//! The workloads come from [`occlude_soft::workload`]. Each measured configuration is
//! a [`RasterBackend`]: the soft rasterizer on each thread count ([`SoftRaster`]), the
//! masked occlusion buffer of `occlude-moc` ([`MocRaster`], fill rate only) and,
//! when a GPU adapter opens (lavapipe counts), the wgpu backend ([`WgpuRaster`]), all
//! in the same run so that their ratios are measured side by side. Adding another
//! backend's rows is implementing that trait and passing the backend to [`measure`].

use std::sync::Arc;
use std::time::Instant;

use glam::Vec4;
use occlude_moc::{CullMode, MaskedBuffer};
use occlude_soft::raster::{Command, CommandKind, DepthBuffer, DepthTest, Rasterizer};
use occlude_soft::workload;
use occlude_wgpu::{DepthRaster, GpuContext};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::limits::MAX_TRIANGLES_PER_CALL;
use crate::progress::Progress;

/// What `occlude raster-bench` measures.
#[derive(Clone, Debug, PartialEq)]
pub struct RasterBenchConfig {
    /// Leg lengths N of the fill-rate triangles, in pixels.
    pub sizes: Vec<u32>,
    /// Triangles drawn per call (`None`: about two screens of pixels, at
    /// least 64, at most [`MAX_TRIANGLES_PER_CALL`]).
    pub triangles_per_size: Option<u64>,
    /// Seconds to measure each fill-rate row for (calls repeat until they
    /// are spent, at least three; the median call is reported); query rows
    /// get a third of it.
    pub seconds_per_row: f64,
    /// Image size in pixels.
    pub resolution: (u32, u32),
    /// Thread counts to run the CPU backends with.
    pub threads: Vec<u32>,
}

impl RasterBenchConfig {
    /// The CPU backends: the soft rasterizer on each thread count, then the
    /// masked buffer on each.
    pub fn cpu_backends(&self) -> Result<Vec<Box<dyn RasterBackend>>> {
        let mut backends: Vec<Box<dyn RasterBackend>> = Vec::new();
        for &threads in &self.threads {
            backends.push(Box::new(SoftRaster::new(threads)?));
        }
        for &threads in &self.threads {
            backends.push(Box::new(MocRaster::new(threads)?));
        }
        Ok(backends)
    }
}

/// One fill-rate measurement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FillRow {
    /// Leg length of the triangles, in pixels.
    pub n: u32,
    /// Backend name: `soft`, `moc` or `wgpu`.
    pub backend: String,
    /// Threads the backend ran on (0 for the GPU).
    pub threads: u32,
    /// Millions of triangles drawn per second.
    pub mtris_per_s: f64,
    /// Billions of pixels (triangles x N^2 / 2) drawn per second.
    pub gpixels_per_s: f64,
}

/// Whether an occlusion query counts its passing fragments or only asks whether one
/// passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum QueryMode {
    /// Hardware-occlusion-query counts (`CommandKind::Query`).
    Count,
    /// Visibility only, stopping at the first passing fragment
    /// (`CommandKind::QueryAny`).
    Any,
}

/// One occlusion-query measurement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QueryRow {
    /// Screen area the box's front face covers, in percent.
    pub coverage_percent: u32,
    /// Whether the box is in front of the occluder (visible) or behind it (hidden).
    pub visible: bool,
    /// What the query asks.
    pub mode: QueryMode,
    /// Backend name: `soft` or `wgpu`.
    pub backend: String,
    /// Threads the backend ran on (0 for the GPU).
    pub threads: u32,
    /// Queries answered per second.
    pub queries_per_s: f64,
}

/// Everything `occlude raster-bench` measured, as written with `--json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RasterBenchReport {
    /// Fill-rate rows.
    pub rows: Vec<FillRow>,
    /// Occlusion-query rows.
    pub queries: Vec<QueryRow>,
    /// The CPU model (from /proc/cpuinfo), or "unknown".
    pub cpu: String,
    /// The GPU adapter of GPU backends' rows; `None` when no GPU backend ran.
    pub adapter: Option<String>,
}

/// A depth rasterizer configuration the benchmark measures.
pub trait RasterBackend {
    /// Name in the tables.
    fn name(&self) -> String;

    /// Threads it runs on (0 for a GPU).
    fn threads(&self) -> u32;

    /// The GPU adapter it runs on, `None` for a CPU backend.
    fn adapter(&self) -> Option<String> {
        None
    }

    /// Draws `triangles` (clip space, depth test LESS with depth write, two-sided)
    /// into a cleared `width` x `height` depth buffer; returns the seconds the draw
    /// took (the clear excluded). Fails where the GPU does (a lost device).
    fn draw(&mut self, width: u32, height: u32, triangles: &[[Vec4; 3]]) -> Result<f64>;

    /// Draws `occluder` into a cleared `width` x `height` depth buffer, then runs one
    /// occlusion query (depth test LESS, back faces culled) per element of `boxes`,
    /// all in one submission; returns the seconds the queries took. `None` where the
    /// backend cannot answer queries in `mode`. Fails where the GPU does.
    fn queries(
        &mut self,
        width: u32,
        height: u32,
        occluder: &[[Vec4; 3]],
        boxes: &[[[Vec4; 3]; 12]],
        mode: QueryMode,
    ) -> Result<Option<f64>>;
}

/// The soft rasterizer on a rayon pool of a given number of threads.
pub struct SoftRaster {
    pool: rayon::ThreadPool,
    threads: u32,
    rasterizer: Rasterizer,
    depth: DepthBuffer,
    /// Scratch: triangles and commands of a query submission.
    triangles: Vec<[Vec4; 3]>,
    commands: Vec<Command>,
}

impl SoftRaster {
    /// The soft rasterizer on `threads` threads.
    pub fn new(threads: u32) -> Result<Self> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads as usize).build().map_err(Error::ThreadPool)?;
        Ok(Self {
            pool,
            threads,
            rasterizer: Rasterizer::new(),
            depth: DepthBuffer::new(0, 0),
            triangles: Vec::new(),
            commands: Vec::new(),
        })
    }

    /// A cleared `width` x `height` depth buffer, reusing the last one's memory.
    fn cleared(&mut self, width: u32, height: u32) -> &mut DepthBuffer {
        if (self.depth.width(), self.depth.height()) == (width, height) {
            self.depth.clear();
        } else {
            self.depth = DepthBuffer::new(width, height);
        }
        &mut self.depth
    }
}

impl RasterBackend for SoftRaster {
    fn name(&self) -> String {
        "soft".into()
    }

    fn threads(&self) -> u32 {
        self.threads
    }

    fn draw(&mut self, width: u32, height: u32, triangles: &[[Vec4; 3]]) -> Result<f64> {
        self.cleared(width, height);
        let commands = [Command { kind: CommandKind::Draw, triangles: 0..triangles.len() as u32, cull_back: false }];
        let (pool, rasterizer, depth) = (&self.pool, &mut self.rasterizer, &mut self.depth);
        Ok(pool.install(|| timed(|| drop(rasterizer.execute(depth, triangles, &commands)))))
    }

    fn queries(
        &mut self,
        width: u32,
        height: u32,
        occluder: &[[Vec4; 3]],
        boxes: &[[[Vec4; 3]; 12]],
        mode: QueryMode,
    ) -> Result<Option<f64>> {
        self.cleared(width, height);
        let draw = [Command { kind: CommandKind::Draw, triangles: 0..occluder.len() as u32, cull_back: false }];
        self.pool.install(|| self.rasterizer.execute(&mut self.depth, occluder, &draw));
        let kind = match mode {
            QueryMode::Count => CommandKind::Query(DepthTest::Less),
            QueryMode::Any => CommandKind::QueryAny(DepthTest::Less),
        };
        self.triangles.clear();
        self.commands.clear();
        let queries = append_boxes(&mut self.triangles, boxes);
        self.commands.extend(queries.map(|triangles| Command { kind, triangles, cull_back: true }));
        let (pool, rasterizer, depth) = (&self.pool, &mut self.rasterizer, &mut self.depth);
        let (triangles, commands) = (&self.triangles, &self.commands);
        Ok(Some(pool.install(|| timed(|| drop(rasterizer.execute(depth, triangles, commands))))))
    }
}

/// The masked occlusion buffer (`occlude_moc::MaskedBuffer`) on a rayon pool of
/// a given number of threads: the fill-rate rows of the coarse CPU buffer,
/// beside the exact rasterizer's. Its tests answer boxes, not fragment counts of
/// triangles, so it has no query rows.
pub struct MocRaster {
    pool: rayon::ThreadPool,
    threads: u32,
    buffer: Option<MaskedBuffer>,
}

impl MocRaster {
    /// The masked buffer on `threads` threads; its size is set by the first draw.
    pub fn new(threads: u32) -> Result<Self> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads as usize).build().map_err(Error::ThreadPool)?;
        Ok(Self { pool, threads, buffer: None })
    }
}

impl RasterBackend for MocRaster {
    fn name(&self) -> String {
        "moc".into()
    }

    fn threads(&self) -> u32 {
        self.threads
    }

    fn draw(&mut self, width: u32, height: u32, triangles: &[[Vec4; 3]]) -> Result<f64> {
        let buffer = match &mut self.buffer {
            Some(b) if (b.width(), b.height()) == (width, height) => {
                b.clear();
                b
            }
            slot => slot.insert(MaskedBuffer::new(width, height)?),
        };
        Ok(self.pool.install(|| {
            timed(|| {
                buffer.render_clip_triangles(triangles, CullMode::None);
            })
        }))
    }

    fn queries(
        &mut self,
        _width: u32,
        _height: u32,
        _occluder: &[[Vec4; 3]],
        _boxes: &[[[Vec4; 3]; 12]],
        _mode: QueryMode,
    ) -> Result<Option<f64>> {
        Ok(None)
    }
}

/// The seconds `f` takes. The soft rows time their calls on a thread of the
/// rasterizer's pool, as `occlude bench` makes them: handing a call into the
/// pool from outside and waking the caller afterwards is not the rasterizer's
/// work (tens of microseconds, a large part of a call of 64 small queries).
fn timed(f: impl FnOnce()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64()
}

/// Appends the triangles of `boxes` to `triangles`, yielding each box's range of
/// them: one occlusion query per box.
fn append_boxes<'a>(
    triangles: &'a mut Vec<[Vec4; 3]>,
    boxes: &'a [[[Vec4; 3]; 12]],
) -> impl Iterator<Item = std::ops::Range<u32>> + 'a {
    boxes.iter().map(move |b| {
        let first = triangles.len() as u32;
        triangles.extend_from_slice(b);
        first..triangles.len() as u32
    })
}

/// The wgpu backend's depth rasterization ([`DepthRaster`]) on a GPU adapter. Its
/// times are from submission to the GPU's completion; uploading the triangles and
/// clearing the depth buffer are not timed. Queries count samples (a GPU occlusion
/// query has no early-out), so it has no rows in [`QueryMode::Any`].
pub struct WgpuRaster {
    raster: DepthRaster,
    adapter: String,
    /// Scratch: the triangles and per-box ranges of a query submission.
    triangles: Vec<[Vec4; 3]>,
    groups: Vec<std::ops::Range<u32>>,
}

impl WgpuRaster {
    /// The depth rasterizer on `ctx`'s adapter.
    pub fn new(ctx: Arc<GpuContext>) -> Self {
        let adapter = ctx.adapter_name();
        Self { raster: DepthRaster::new(ctx), adapter, triangles: Vec::new(), groups: Vec::new() }
    }

    /// [`RasterBackend::draw`], with the GPU's errors.
    fn try_draw(&mut self, width: u32, height: u32, triangles: &[[Vec4; 3]]) -> Result<f64, String> {
        self.raster.upload(triangles)?;
        self.raster.clear(width, height)?;
        let start = Instant::now();
        self.raster.draw(0..triangles.len() as u32)?;
        Ok(start.elapsed().as_secs_f64())
    }

    /// [`RasterBackend::queries`] counting samples, with the GPU's errors.
    fn try_queries(
        &mut self,
        width: u32,
        height: u32,
        occluder: &[[Vec4; 3]],
        boxes: &[[[Vec4; 3]; 12]],
    ) -> Result<f64, String> {
        self.triangles.clear();
        self.triangles.extend_from_slice(occluder);
        self.groups.clear();
        self.groups.extend(append_boxes(&mut self.triangles, boxes));
        self.raster.upload(&self.triangles)?;
        self.raster.clear(width, height)?;
        self.raster.draw(0..occluder.len() as u32)?;
        let start = Instant::now();
        self.raster.queries(&self.groups)?;
        Ok(start.elapsed().as_secs_f64())
    }
}

impl RasterBackend for WgpuRaster {
    fn name(&self) -> String {
        "wgpu".into()
    }

    fn threads(&self) -> u32 {
        0
    }

    fn adapter(&self) -> Option<String> {
        Some(self.adapter.clone())
    }

    fn draw(&mut self, width: u32, height: u32, triangles: &[[Vec4; 3]]) -> Result<f64> {
        self.try_draw(width, height, triangles)
            .map_err(|e| Error::Backend(format!("GPU '{}' failed to draw: {e}", self.adapter)))
    }

    fn queries(
        &mut self,
        width: u32,
        height: u32,
        occluder: &[[Vec4; 3]],
        boxes: &[[[Vec4; 3]; 12]],
        mode: QueryMode,
    ) -> Result<Option<f64>> {
        if mode != QueryMode::Count {
            return Ok(None);
        }
        let seconds = self
            .try_queries(width, height, occluder, boxes)
            .map_err(|e| Error::Backend(format!("GPU '{}' failed to run occlusion queries: {e}", self.adapter)))?;
        Ok(Some(seconds))
    }
}

/// Runs `measure` (which returns seconds) until `budget` seconds of it are spent, at
/// least three times, after one untimed warm-up run; returns the median run's
/// seconds (robust against the other processes of a shared machine), or the first
/// error.
fn median_seconds(budget: f64, mut measure: impl FnMut() -> Result<f64>) -> Result<f64> {
    measure()?;
    let mut runs = Vec::new();
    while runs.len() < 3 || runs.iter().sum::<f64>() < budget {
        runs.push(measure()?);
    }
    runs.sort_by(f64::total_cmp);
    Ok(runs[runs.len() / 2])
}

/// The fill-rate row of `backend` for triangles of legs `n`.
pub fn fill_row(
    backend: &mut dyn RasterBackend,
    size: (u32, u32),
    n: u32,
    triangles: &[[Vec4; 3]],
    budget: f64,
) -> Result<FillRow> {
    let seconds = median_seconds(budget, || backend.draw(size.0, size.1, triangles))?;
    let tris_per_s = triangles.len() as f64 / seconds;
    Ok(FillRow {
        n,
        backend: backend.name(),
        threads: backend.threads(),
        mtris_per_s: tris_per_s * 1e-6,
        gpixels_per_s: tris_per_s * workload::pixels_per_triangle(n) * 1e-9,
    })
}

/// Screen areas the query boxes cover, in percent.
pub const QUERY_COVERAGES: [u32; 3] = [1, 10, 50];

/// The query rows of `backend`: every coverage, visible and hidden, in both modes
/// (those the backend supports); `progress` advances once per combination, run
/// or not.
pub fn query_rows(
    backend: &mut dyn RasterBackend,
    size: (u32, u32),
    budget: f64,
    progress: &dyn Progress,
) -> Result<Vec<QueryRow>> {
    let occluder = workload::screen_quad(workload::OCCLUDER_DEPTH);
    let mut rows = Vec::new();
    for percent in QUERY_COVERAGES {
        for visible in [true, false] {
            let boxes = workload::query_boxes(percent as f32 / 100.0, visible);
            for mode in [QueryMode::Count, QueryMode::Any] {
                progress.message(&format!("queries, {percent}% boxes, {}", label(backend)));
                if backend.queries(size.0, size.1, &occluder, &boxes, mode)?.is_some() {
                    let seconds = median_seconds(budget, || {
                        Ok(backend.queries(size.0, size.1, &occluder, &boxes, mode)?.unwrap_or(f64::NAN))
                    })?;
                    rows.push(QueryRow {
                        coverage_percent: percent,
                        visible,
                        mode,
                        backend: backend.name(),
                        threads: backend.threads(),
                        queries_per_s: boxes.len() as f64 / seconds,
                    });
                }
                progress.advance(1);
            }
        }
    }
    Ok(rows)
}

/// The CPU model name from /proc/cpuinfo, or "unknown".
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, name)| name.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// "soft, 2 threads" or "wgpu": a backend as the progress message names it.
fn label(backend: &dyn RasterBackend) -> String {
    match backend.threads() {
        0 => backend.name(),
        1 => format!("{}, 1 thread", backend.name()),
        t => format!("{}, {t} threads", backend.name()),
    }
}

/// Measures every row of `config` on `backends`, or fails with the first backend that
/// does; `progress` advances once per fill-rate row and per query workload.
pub fn measure(
    config: &RasterBenchConfig,
    backends: &mut [Box<dyn RasterBackend>],
    progress: &dyn Progress,
) -> Result<RasterBenchReport> {
    let (width, height) = config.resolution;
    // Per backend: its fill-rate rows, and the query workloads of `query_rows`
    // (each coverage, visible or hidden, counted or any).
    let per_backend = config.sizes.len() + QUERY_COVERAGES.len() * 2 * 2;
    progress.start((per_backend * backends.len()) as u64);
    let mut rows = Vec::new();
    for &n in &config.sizes {
        let count = config.triangles_per_size.unwrap_or_else(|| {
            (workload::triangles_for_screens(width, height, n, 2.0) as u64).min(MAX_TRIANGLES_PER_CALL)
        }) as usize;
        let triangles = workload::right_triangles(width, height, n as f32, count);
        for backend in backends.iter_mut() {
            progress.message(&format!("fill rate, N = {n}, {}", label(backend.as_ref())));
            rows.push(fill_row(backend.as_mut(), config.resolution, n, &triangles, config.seconds_per_row)?);
            progress.advance(1);
        }
    }
    let mut queries = Vec::new();
    for backend in backends.iter_mut() {
        queries.extend(query_rows(backend.as_mut(), config.resolution, config.seconds_per_row / 3.0, progress)?);
    }
    let adapter = backends.iter().find_map(|b| b.adapter());
    Ok(RasterBenchReport { rows, queries, cpu: cpu_model(), adapter })
}

/// The report, measured at `resolution`, as two plain-text tables.
pub fn render(report: &RasterBenchReport, (width, height): (u32, u32)) -> String {
    let mut out =
        format!("fill rate, {width}x{height}: right triangles with legs of N pixels, back to front ({})\n", report.cpu);
    if let Some(adapter) = &report.adapter {
        out += &format!("wgpu adapter: {adapter}\n");
    }
    out += &format!("{:>5}  {:<8}{:>8}{:>11}{:>11}\n", "N", "backend", "threads", "MTris/s", "GPix/s");
    for r in &report.rows {
        out +=
            &format!("{:>5}  {:<8}{:>8}{:>11.3}{:>11.3}\n", r.n, r.backend, r.threads, r.mtris_per_s, r.gpixels_per_s);
    }
    out += &format!(
        "\nocclusion queries, {width}x{height}: boxes against a screen-filling occluder, {} per submission\n",
        workload::QUERIES_PER_SUBMISSION
    );
    out +=
        &format!("{:>9}  {:<9}{:<7}{:<8}{:>8}{:>13}\n", "coverage", "box", "mode", "backend", "threads", "queries/s");
    for q in &report.queries {
        let mode = match q.mode {
            QueryMode::Count => "count",
            QueryMode::Any => "any",
        };
        out += &format!(
            "{:>8}%  {:<9}{:<7}{:<8}{:>8}{:>13.0}\n",
            q.coverage_percent,
            if q.visible { "visible" } else { "hidden" },
            mode,
            q.backend,
            q.threads,
            q.queries_per_s
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_boxes_are_visible_or_hidden_as_asked() {
        // 64x64: boxes of 10% of the screen; count every query's passing fragments.
        let mut soft = SoftRaster::new(1).unwrap();
        let occluder = workload::screen_quad(workload::OCCLUDER_DEPTH);
        for visible in [true, false] {
            let boxes = workload::query_boxes(0.1, visible);
            soft.queries(64, 64, &occluder, &boxes, QueryMode::Count).unwrap().unwrap();
            let mut depth = DepthBuffer::new(64, 64);
            let mut raster = Rasterizer::new();
            raster.execute(
                &mut depth,
                &occluder,
                &[Command { kind: CommandKind::Draw, triangles: 0..2, cull_back: false }],
            );
            for b in &boxes {
                let r = raster.execute(
                    &mut depth,
                    b,
                    &[Command { kind: CommandKind::Query(DepthTest::Less), triangles: 0..12, cull_back: true }],
                )[0];
                // About 10% of 4096 pixels, all passing or none.
                assert!((300..=520).contains(&r.fragments), "{r:?}");
                assert_eq!(r.passed, if visible { r.fragments } else { 0 });
            }
        }
    }

    #[test]
    fn tables_list_every_row() {
        let config = RasterBenchConfig {
            sizes: vec![10, 50],
            triangles_per_size: Some(64),
            seconds_per_row: 1e-4,
            resolution: (96, 80),
            threads: vec![1, 2],
        };
        let mut backends = config.cpu_backends().unwrap();
        let report = measure(&config, &mut backends, &()).unwrap();
        assert_eq!(report.rows.len(), 8);
        let moc: Vec<_> = report.rows.iter().filter(|r| r.backend == "moc").map(|r| (r.n, r.threads)).collect();
        assert_eq!(moc, [(10, 1), (10, 2), (50, 1), (50, 2)]);
        assert_eq!(report.queries.len(), 2 * QUERY_COVERAGES.len() * 2 * 2);
        assert!(report.rows.iter().all(|r| r.mtris_per_s > 0.0 && r.gpixels_per_s > 0.0));
        // GPix/s = MTris/s * N^2 / 2 / 1000.
        for r in &report.rows {
            let expected = r.mtris_per_s * f64::from(r.n * r.n) / 2.0 / 1000.0;
            assert!((r.gpixels_per_s - expected).abs() < 1e-9 * expected.max(1.0));
        }
        let text = render(&report, config.resolution);
        assert_eq!(text.lines().filter(|l| l.contains("soft")).count(), 4 + 24);
        assert_eq!(text.lines().filter(|l| l.contains("moc")).count(), 4);
    }
}
