//! Writing a report as JSON (the schema in `docs/design.md`) or CSV (one row per method and
//! frame, for spreadsheets and plotting tools), and reading JSON reports back.

use crate::error::{invalid, Error, Result};
use crate::summary::{BenchReport, MethodSummary};
use serde_json::Value;
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

/// The largest bench JSON file read, bytes.
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// Reads the reports of one bench JSON file (a regular file of at most
/// [`MAX_FILE_BYTES`]) as [`parse`] does.
pub fn load(path: &Path) -> Result<Vec<BenchReport>> {
    let text = occlude_core::input_file::read_text(path, MAX_FILE_BYTES)
        .map_err(|source| Error::Io { context: format!("cannot read {}", path.display()), source })?;
    parse(&text, &path.display().to_string())
}

/// Parses the reports of one bench JSON document: one [`BenchReport`]
/// object or a non-empty array of them (a leading byte-order mark is
/// ignored), every figure finite and within
/// ±[`crate::figures::MAX_FIGURE`]. Anything else is an error naming the
/// file `name` and saying what is wrong (not JSON, not an object, a missing
/// key, a figure out of range, ...).
pub fn parse(text: &str, name: &str) -> Result<Vec<BenchReport>> {
    let value: Value = serde_json::from_str(occlude_core::input_file::strip_bom(text))
        .map_err(|source| Error::Json { context: format!("{name} is not valid JSON"), source })?;
    crate::figures::check_input(&value).map_err(|e| Error::Invalid(format!("{name}: {e}")))?;
    let (items, in_array) = match value {
        Value::Array(items) => (items, true),
        Value::Object(mut tables) if tables.contains_key("tables") => match tables.remove("reports") {
            Some(Value::Array(items)) => (items, true),
            _ => invalid!("{name}: a paper's tables without the array of their reports (\"reports\")"),
        },
        object @ Value::Object(_) => (vec![object], false),
        other => {
            invalid!("{name}: expected a bench report (a JSON object) or an array of them, found {}", json_kind(&other))
        }
    };
    if items.is_empty() {
        invalid!("{name}: the array holds no bench reports");
    }
    items
        .into_iter()
        .enumerate()
        .map(|(i, item)| {
            serde_json::from_value(item).map_err(|source| {
                let context = if in_array {
                    format!("{name}: item {i} of the array is not a bench report")
                } else {
                    format!("{name} is not a bench report")
                };
                Error::Json { context, source }
            })
        })
        .collect()
}

/// What kind of JSON value `v` is, for error messages.
fn json_kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}
