//! Writing a report as JSON (the schema in `docs/design.md`) or CSV (one row per method and
//! frame, for spreadsheets and plotting tools).

use super::summary::BenchReport;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::Path;

/// Writes a report (or, for `--paper`, a list of them) as pretty JSON.
pub fn write_json<T: serde::Serialize + ?Sized>(report: &T, path: &Path) -> Result<()> {
    let file = std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    serde_json::to_writer_pretty(std::io::BufWriter::new(file), report)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// The CSV header row.
pub const CSV_HEADER: &str = "method,frame,frame_ms,cpu_ms,gpu_ms,wait_ms,queries,query_boxes,draw_calls,state_changes,triangles,fragments,visible_objects,traversal_steps,missing_pixels,wall_ms";

/// Writes one row per method and frame.
pub fn write_csv(report: &BenchReport, path: &Path) -> Result<()> {
    let file = std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut w = std::io::BufWriter::new(file);
    let context = || format!("cannot write {}", path.display());
    writeln!(w, "{CSV_HEADER}").with_context(context)?;
    for m in &report.methods {
        for (i, f) in m.per_frame.iter().enumerate() {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                m.name,
                i,
                f.frame_ms,
                f.cpu_ms,
                f.gpu_ms,
                f.wait_ms,
                f.queries,
                f.query_boxes,
                f.draw_calls,
                f.state_changes,
                f.triangles,
                f.fragments,
                f.visible_objects,
                f.traversal_steps,
                f.missing_pixels,
                f.wall_ms
            )
            .with_context(context)?;
        }
    }
    w.flush().with_context(context)
}
