//! Writing a report as JSON (the schema in `docs/design.md`) or CSV (one row per method and
//! frame, for spreadsheets and plotting tools).

use crate::error::{Error, Result};
use crate::summary::{BenchReport, MethodSummary};
use std::io::Write;
use std::path::Path;

/// Writes a report (or, for `--paper`, a list of them) as pretty JSON.
pub fn write_json<T: serde::Serialize + ?Sized>(report: &T, path: &Path) -> Result<()> {
    let file = create(path)?;
    serde_json::to_writer_pretty(std::io::BufWriter::new(file), report)
        .map_err(|source| Error::Json { context: format!("cannot write {}", path.display()), source })
}

/// The CSV header row.
pub const CSV_HEADER: &str = "method,frame,frame_ms,cpu_ms,gpu_ms,wait_ms,queries,query_boxes,draw_calls,state_changes,triangles,fragments,visible_objects,traversal_steps,missing_pixels,wall_ms,material_switches";

/// Writes one row per method and frame.
pub fn write_csv(report: &BenchReport, path: &Path) -> Result<()> {
    write_rows(path, CSV_HEADER, |w| report.methods.iter().try_for_each(|m| write_method_rows(w, "", m)))
}

/// The CSV header row of a `--paper` run: [`CSV_HEADER`] led by the run
/// (its index in the JSON's `reports`), the scene and the method's
/// parameters (`name=value` joined by `;`), which tell a table's variants
/// apart.
pub fn paper_csv_header() -> String {
    format!("run,scene,params,{CSV_HEADER}")
}

/// Writes one row per method and frame of every report of a `--paper` run.
pub fn write_paper_csv(reports: &[BenchReport], path: &Path) -> Result<()> {
    write_rows(path, &paper_csv_header(), |w| {
        for (run, report) in reports.iter().enumerate() {
            for m in &report.methods {
                let params: Vec<String> = m.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
                let lead = format!("{run},{},{},", report.scene, params.join(";"));
                write_method_rows(w, &lead, m)?;
            }
        }
        Ok(())
    })
}

/// Creates `path`, writes `header` and what `rows` writes, with the path
/// named in any error.
fn write_rows(path: &Path, header: &str, rows: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    let mut w = std::io::BufWriter::new(create(path)?);
    let written = writeln!(w, "{header}").and_then(|()| rows(&mut w)).and_then(|()| w.flush());
    written.map_err(|source| Error::Io { context: format!("cannot write {}", path.display()), source })
}

/// Creates `path`, named in the error.
fn create(path: &Path) -> Result<std::fs::File> {
    std::fs::File::create(path)
        .map_err(|source| Error::Io { context: format!("cannot create {}", path.display()), source })
}

/// One row per frame of `m`, each led by `lead`.
fn write_method_rows(w: &mut dyn Write, lead: &str, m: &MethodSummary) -> std::io::Result<()> {
    for (i, f) in m.per_frame.iter().enumerate() {
        writeln!(
            w,
            "{lead}{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
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
            f.wall_ms,
            f.material_switches
        )?;
    }
    Ok(())
}
