//! The comparison table printed by `occlude bench`, shaped like Table 1 of the
//! CHC paper, and the report's other tables as cells for the HTML and
//! Markdown reports. Times from the soft backend are simulated and labelled
//! so.

use crate::summary::BenchReport;
use std::fmt::Write;

/// Renders the report as an aligned text table.
pub fn render(report: &BenchReport) -> String {
    let s = &report.scene_stats;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "scene {} ({}, seed {}): {} triangles, {} instances, {} {} nodes ({} leaves, built in {:.1} ms), {} frames{} at {}x{}, backend {}, queries {}, GPU model {}",
        report.scene,
        report.size,
        report.seed,
        s.triangles,
        s.instances,
        s.nodes,
        report.hierarchy,
        s.leaves,
        s.build_wall_ms,
        report.frames,
        report.fps.map_or(String::new(), |f| format!(" ({f} fps)")),
        report.resolution[0],
        report.resolution[1],
        report.backend,
        report.queries,
        report.gpu_model,
    );
    let (headers, rows) = cells(report);
    let widths: Vec<usize> = (0..headers.len())
        .map(|c| rows.iter().map(|r| r[c].len()).chain([headers[c].len()]).max().unwrap_or(0))
        .collect();
    let line = |cells: &[String]| {
        cells
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(i, (c, w))| if i == 0 { format!("{c:<w$}") } else { format!("{c:>w$}") })
            .collect::<Vec<_>>()
            .join("  ")
    };
    let _ = writeln!(out, "{}", line(&headers));
    for r in &rows {
        let _ = writeln!(out, "{}", line(r));
    }
    let _ = writeln!(out, "{}", note(report));
    out
}

/// Columns of the comparison table.
pub const COLUMNS: usize = 13;

/// The comparison table's header and one row per method, formatted but not
/// aligned, so that the text table and the HTML and Markdown reports show the
/// same columns. Times from the soft backend are headed "sim".
pub fn cells(report: &BenchReport) -> ([String; COLUMNS], Vec<[String; COLUMNS]>) {
    let sim = if report.backend == "soft" { "sim " } else { "" };
    let headers = [
        "method".to_string(),
        format!("{sim}ms"),
        format!("{sim}p95 ms"),
        "speedup".into(),
        "ratio opt".into(),
        "queries".into(),
        format!("{sim}wait ms"),
        "draws".into(),
        "states".into(),
        "materials".into(),
        "triangles".into(),
        "missing px".into(),
        "wall ms".into(),
    ];
    let rows: Vec<[String; COLUMNS]> = report
        .methods
        .iter()
        .map(|m| {
            [
                m.name.clone(),
                format!("{:.3}", m.mean_frame_ms),
                format!("{:.3}", m.p95_frame_ms),
                format!("{:.2}", m.speedup_vs_vfc),
                m.ratio_to_opt.map_or("-".into(), |r| format!("{r:.2}")),
                format!("{:.1}", m.queries_per_frame),
                format!("{:.3}", m.wait_ms_per_frame),
                format!("{:.1}", m.draw_calls_per_frame),
                format!("{:.1}", m.state_changes_per_frame),
                format!("{:.1}", m.material_switches_per_frame),
                format!("{:.0}", m.triangles_per_frame),
                m.missing_pixels.to_string(),
                format!("{:.1}", m.wall_ms),
            ]
        })
        .collect();
    (headers, rows)
}

/// The line under the table that says what its figures mean.
pub fn note(report: &BenchReport) -> String {
    format!(
        "per frame means; speedup = vfc time / method time; missing px summed over frames{}",
        if report.backend == "soft" { "; sim = simulated GPU clock, wall = real time on this machine" } else { "" }
    )
}

/// The scene statistics as header cells and a row.
pub fn scene_cells(report: &BenchReport) -> (Vec<String>, Vec<String>) {
    let s = &report.scene_stats;
    let headers =
        ["triangles", "unique triangles", "instances", "materials", "nodes", "leaves", "depth", "frames", "build ms"];
    let row = vec![
        s.triangles.to_string(),
        s.unique_triangles.to_string(),
        s.instances.to_string(),
        s.materials.to_string(),
        s.nodes.to_string(),
        s.leaves.to_string(),
        s.depth.to_string(),
        s.frames.to_string(),
        format!("{:.1}", s.build_wall_ms),
    ];
    (headers.map(String::from).to_vec(), row)
}

/// The culling passes of the methods that dispatch compute work (the
/// GPU-driven ones) as header cells and one row per method, or `None` when
/// no method does.
pub fn gpu_driven_cells(report: &BenchReport) -> Option<(Vec<String>, Vec<Vec<String>>)> {
    let sim = if report.backend == "soft" { "sim " } else { "" };
    let headers = ["method", "dispatches", "indirect draws", "cull", "render", "early", "pyramid", "late"]
        .iter()
        .enumerate()
        .map(|(i, h)| if i < 3 { h.to_string() } else { format!("{sim}{h} ms") })
        .collect();
    let ms = |v: f64| format!("{v:.3}");
    let rows: Vec<Vec<String>> = report
        .methods
        .iter()
        .filter(|m| m.dispatches_per_frame > 0.0)
        .map(|m| {
            let pyramid = m.pyramid_ms_per_frame > 0.0 || m.late_ms_per_frame > 0.0;
            let phase = |v: f64| if pyramid { ms(v) } else { "-".into() };
            vec![
                m.name.clone(),
                format!("{:.1}", m.dispatches_per_frame),
                format!("{:.1}", m.indirect_draws_per_frame),
                ms(m.cull_ms_per_frame),
                ms(m.render_ms_per_frame),
                phase(m.gpu_ms_per_frame - m.pyramid_ms_per_frame - m.late_ms_per_frame),
                phase(m.pyramid_ms_per_frame),
                phase(m.late_ms_per_frame),
            ]
        })
        .collect();
    (!rows.is_empty()).then_some((headers, rows))
}

/// What the columns of [`gpu_driven_cells`] are.
pub const GPU_DRIVEN_NOTE: &str = "per frame means, GPU ms; cull = occlusion tests and their compute passes, render = \
     drawing; for a depth pyramid (hiz), early = before its build, pyramid = the build, late = after it (box tests, \
     the late draw)";
