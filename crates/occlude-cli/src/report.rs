//! `occlude report`: bench JSON files (one [`BenchReport`] each, an array of
//! them, or a paper's tables with their reports as `occlude bench --paper
//! --json` writes, read by [`occlude_bench::output::load`]) turned into one
//! self-contained HTML page, and optionally the same content as Markdown.
//!
//! Each report gets a heading with its setup, the scene statistics, the
//! comparison table of `occlude bench`, for the GPU-driven methods (`roc`,
//! `ioc`, `hiz`: compute dispatches) their culling passes, and two plots
//! over the walkthrough:
//! frame times, and queries, state changes and material switches (the CHC++
//! paper's Figure 10).
//! The HTML page needs nothing beside it (inline CSS, inline SVG), so it can be
//! mailed or attached to an issue as one file. Both renderings are made from
//! the same list of `Block`s, so they cannot drift apart.

use crate::bench::plot::{self, PlotKind};
use anyhow::{Context, Result};
use occlude_bench::summary::BenchReport;
use occlude_bench::table;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Title of the page and of the Markdown document.
const TITLE: &str = "occlude benchmark report";

/// The SVG namespace declaration plotters writes. An HTML parser puts an
/// inline `<svg>` in that namespace by itself, so the page leaves the
/// declaration out and holds no `http://` address at all.
const SVG_XMLNS: &str = r#" xmlns="http://www.w3.org/2000/svg""#;

/// Styles of the HTML page.
const CSS: &str = "body { font-family: sans-serif; margin: 2em; color: #222; background: #fff; }
h2 { border-bottom: 2px solid #888; padding-bottom: 0.2em; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.5em 0; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
th { background: #eee; }
td:first-child { text-align: left; }
p.note { color: #555; font-size: 0.9em; }
figure { margin: 0.5em 0; }
figure svg { max-width: 100%; height: auto; }
";

/// One piece of a report's section, rendered alike as HTML and Markdown. Text
/// is plain (unescaped); each rendering escapes it.
#[derive(Debug)]
enum Block {
    /// A heading of the given level (2 for a report, 3 within it).
    Heading(u8, String),
    /// A paragraph.
    Text(String),
    /// A remark in smaller print.
    Note(String),
    /// A table: header cells and rows of cells.
    Table(Vec<String>, Vec<Vec<String>>),
    /// A plot of the report.
    Plot(PlotKind),
}

/// Heading of a plot and the suffix of its file beside a Markdown report.
fn plot_names(kind: PlotKind) -> (&'static str, &'static str) {
    match kind {
        PlotKind::FrameTime => ("Frame time over the walkthrough", "frame-time"),
        PlotKind::QueriesAndStateChanges => ("Queries and state changes per frame", "queries"),
    }
}

/// The blocks of one report's section.
fn section(report: &BenchReport) -> Vec<Block> {
    let (headers, rows) = table::cells(report);
    let (scene_headers, scene_row) = table::scene_cells(report);
    let mut blocks = vec![
        Block::Heading(
            2,
            format!(
                "{} ({}): {} hierarchy, {} backend, GPU model {}",
                report.scene, report.size, report.hierarchy, report.backend, report.gpu_model
            ),
        ),
        Block::Text(format!(
            "{} frames at {}x{}, seed {}",
            report.frames, report.resolution[0], report.resolution[1], report.seed
        )),
        Block::Heading(3, "Scene statistics".into()),
        Block::Table(scene_headers, vec![scene_row]),
        Block::Heading(3, "Comparison".into()),
        Block::Table(headers.to_vec(), rows.into_iter().map(Vec::from).collect()),
        Block::Note(table::note(report)),
    ];
    if let Some((headers, rows)) = table::gpu_driven_cells(report) {
        blocks.push(Block::Heading(3, "GPU-driven culling passes".into()));
        blocks.push(Block::Table(headers, rows));
        blocks.push(Block::Note(table::GPU_DRIVEN_NOTE.into()));
    }
    for kind in [PlotKind::FrameTime, PlotKind::QueriesAndStateChanges] {
        blocks.push(Block::Heading(3, plot_names(kind).0.into()));
        blocks.push(Block::Plot(kind));
    }
    blocks
}

/// `s` with the characters HTML gives a meaning escaped.
fn escape_html(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `s` with the characters Markdown gives a meaning (tables' `|` included)
/// escaped by a backslash, and HTML's `<`, `>` and `&` as entities.
fn escape_markdown(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\\' | '`' | '*' | '_' | '[' | ']' | '#' | '|' => {
                out.push('\\');
                out.push(c);
            }
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            c => out.push(c),
        }
    }
    out
}

/// The whole report of `reports` as one self-contained HTML page.
pub fn html(reports: &[BenchReport]) -> Result<String> {
    let mut out = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{TITLE}</title>\n<style>\n{CSS}</style>\n</head>\n<body>\n<h1>{TITLE}</h1>\n"
    );
    for report in reports {
        out.push_str("<section>\n");
        for block in section(report) {
            match block {
                Block::Heading(level, text) => {
                    let _ = writeln!(out, "<h{level}>{}</h{level}>", escape_html(&text));
                }
                Block::Text(text) => {
                    let _ = writeln!(out, "<p>{}</p>", escape_html(&text));
                }
                Block::Note(text) => {
                    let _ = writeln!(out, "<p class=\"note\">{}</p>", escape_html(&text));
                }
                Block::Table(headers, rows) => {
                    let row = |tag: &str, cells: &[String]| {
                        let cells: String =
                            cells.iter().map(|c| format!("<{tag}>{}</{tag}>", escape_html(c))).collect();
                        format!("<tr>{cells}</tr>\n")
                    };
                    out.push_str("<table>\n<thead>\n");
                    out.push_str(&row("th", &headers));
                    out.push_str("</thead>\n<tbody>\n");
                    for r in &rows {
                        out.push_str(&row("td", r));
                    }
                    out.push_str("</tbody>\n</table>\n");
                }
                Block::Plot(kind) => {
                    // plotters escapes the text it writes into the SVG.
                    let svg = plot::svg_string(report, kind)?;
                    let _ = writeln!(out, "<figure>\n{}</figure>", svg.replacen(SVG_XMLNS, "", 1));
                }
            }
        }
        out.push_str("</section>\n");
    }
    out.push_str("</body>\n</html>\n");
    Ok(out)
}

/// Writes [`html`] of `reports` to `path`.
pub fn write_html(reports: &[BenchReport], path: &Path) -> Result<()> {
    let page = html(reports)?;
    std::fs::write(path, page).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes the report of `reports` as Markdown to `path`, its plots as SVG
/// files beside it (named after it: `NAME-1-frame-time.svg`, ...) and linked
/// by relative paths. Returns the paths written, the Markdown file last.
pub fn write_markdown(reports: &[BenchReport], path: &Path) -> Result<Vec<PathBuf>> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let stem = path.file_stem().map_or("report".into(), |s| s.to_string_lossy());
    let mut written = Vec::new();
    let mut out = format!("# {TITLE}\n");
    for (i, report) in reports.iter().enumerate() {
        for block in section(report) {
            match block {
                Block::Heading(level, text) => {
                    let _ = write!(out, "\n{} {}\n", "#".repeat(level.into()), escape_markdown(&text));
                }
                Block::Text(text) => {
                    let _ = write!(out, "\n{}\n", escape_markdown(&text));
                }
                Block::Note(text) => {
                    let _ = write!(out, "\n*{}*\n", escape_markdown(&text));
                }
                Block::Table(headers, rows) => {
                    let row = |cells: &[String]| {
                        let cells: Vec<String> = cells.iter().map(|c| escape_markdown(c)).collect();
                        format!("| {} |\n", cells.join(" | "))
                    };
                    out.push('\n');
                    out.push_str(&row(&headers));
                    let rule: Vec<String> =
                        (0..headers.len()).map(|c| if c == 0 { ":--".into() } else { "--:".into() }).collect();
                    out.push_str(&row(&rule));
                    for r in &rows {
                        out.push_str(&row(r));
                    }
                }
                Block::Plot(kind) => {
                    let (title, suffix) = plot_names(kind);
                    let file = format!("{stem}-{}-{suffix}.svg", i + 1);
                    let svg_path = dir.join(&file);
                    plot::write_plot(report, kind, &svg_path)?;
                    written.push(svg_path);
                    let _ = write!(out, "\n![{}](<{file}>)\n", escape_markdown(title));
                }
            }
        }
    }
    std::fs::write(path, out).with_context(|| format!("cannot write {}", path.display()))?;
    written.push(path.to_path_buf());
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use occlude_bench::output::load;
    use occlude_bench::summary::{MethodSummary, SceneStats};
    use occlude_core::FrameStats;
    use std::collections::BTreeMap;

    /// A method over ten frames whose frame times and queries grow with `base`.
    fn method(name: &str, base: f64) -> MethodSummary {
        let per_frame: Vec<FrameStats> = (0..10u64)
            .map(|i| FrameStats {
                frame_ms: base + i as f64 * 0.5,
                queries: (base as u64) * (i % 3 + 1),
                state_changes: 5 + i,
                ..Default::default()
            })
            .collect();
        MethodSummary {
            name: name.into(),
            params: BTreeMap::new(),
            mean_frame_ms: base,
            p95_frame_ms: base * 1.5,
            queries_per_frame: base,
            wait_ms_per_frame: 0.1,
            draw_calls_per_frame: 40.0,
            state_changes_per_frame: 9.5,
            material_switches_per_frame: 3.5,
            triangles_per_frame: 12345.0,
            visible_objects_per_frame: 30.0,
            missing_pixels: 0,
            speedup_vs_vfc: 20.0 / base,
            ratio_to_opt: None,
            cpu_ms_per_frame: 1.0,
            gpu_ms_per_frame: base,
            wall_ms: 2.0,
            counters_per_frame: BTreeMap::new(),
            per_frame,
            ..Default::default()
        }
    }

    /// A soft-backend report of `scene` with three methods.
    fn report(scene: &str) -> BenchReport {
        BenchReport {
            scene: scene.into(),
            size: "small".into(),
            frames: 10,
            fps: None,
            resolution: [160, 120],
            backend: "soft".into(),
            queries: "hardware".into(),
            adapter: None,
            aborted: None,
            gpu_model: "modern".into(),
            hierarchy: "bvh".into(),
            seed: 7,
            scene_stats: SceneStats {
                triangles: 98765,
                unique_triangles: 4321,
                instances: 250,
                materials: 6,
                nodes: 99,
                leaves: 50,
                depth: 8,
                frames: 10,
                build_wall_ms: 1.25,
            },
            methods: vec![method("vfc", 20.0), method("chc", 8.0), method("chcpp", 6.0)],
        }
    }

    #[test]
    fn html_holds_every_method_stat_and_plot_and_nothing_external() {
        let reports = [report("city"), report("plant")];
        let page = html(&reports).unwrap();
        assert!(page.starts_with("<!DOCTYPE html>"));
        for m in &reports[0].methods {
            assert!(page.contains(&format!("<td>{}</td>", m.name)), "no table row for {}", m.name);
        }
        // Two plots per report, each inline.
        assert_eq!(page.matches("<svg").count(), 4);
        assert_eq!(page.matches("</svg>").count(), 4);
        assert!(!page.contains("http://") && !page.contains("https://"), "the page refers to something outside it");
        assert!(!page.contains("<link") && !page.contains("<script") && !page.contains("<img"));
        assert!(page.contains("<h2>city (small): bvh hierarchy, soft backend, GPU model modern</h2>"));
        assert!(page.contains("10 frames at 160x120, seed 7"));
        assert!(page.contains("<td>98765</td>") && page.contains("<td>4321</td>"), "scene statistics missing");
        // The simulated times are labelled so, as in the text table.
        assert!(page.contains("<th>sim ms</th>") && page.contains("sim = simulated GPU clock"));
        assert!(page.contains("<td>3.33</td>"), "chcpp's speedup over vfc (20 / 6) is missing");
        // State changes and material switches, each in a column of its own.
        assert!(page.contains("<th>states</th><th>materials</th>"), "{page}");
        assert!(page.contains("<td>9.5</td><td>3.5</td>"), "state changes and material switches missing");
    }

    /// A GPU-driven method's passes get their own table (early = GPU
    /// time before the pyramid build), and a report without one has none.
    #[test]
    fn gpu_driven_methods_get_a_table_of_their_passes() {
        let mut r = report("city");
        assert!(!html(std::slice::from_ref(&r)).unwrap().contains("GPU-driven culling passes"));
        r.methods.push(MethodSummary {
            dispatches_per_frame: 17.0,
            indirect_draws_per_frame: 2.0,
            cull_ms_per_frame: 0.07,
            render_ms_per_frame: 0.2,
            pyramid_ms_per_frame: 0.04,
            late_ms_per_frame: 0.125,
            ..method("hiz", 0.25)
        });
        let page = html(&[r]).unwrap();
        assert!(page.contains("<h3>GPU-driven culling passes</h3>"));
        assert!(page.contains("<th>sim early ms</th>"));
        let row = "<tr><td>hiz</td><td>17.0</td><td>2.0</td><td>0.070</td><td>0.200</td><td>0.085</td><td>0.040</td><td>0.125</td></tr>";
        assert!(page.contains(row), "{page}");
    }

    #[test]
    fn hardware_times_are_not_labelled_simulated() {
        let mut r = report("city");
        r.backend = "wgpu".into();
        let page = html(&[r]).unwrap();
        assert!(page.contains("<th>ms</th>"));
        assert!(!page.contains("sim ms"));
    }

    #[test]
    fn strings_from_the_json_are_escaped() {
        let mut r = report("<b>x</b> & \"y\"");
        r.methods[0].name = "<script>alert(1)</script>".into();
        let page = html(&[r]).unwrap();
        assert!(!page.contains("<b>x</b>"), "scene name not escaped");
        assert!(page.contains("&lt;b&gt;x&lt;/b&gt; &amp; &quot;y&quot;"));
        assert!(!page.contains("<script>"), "method name not escaped");
        assert!(page.contains("&lt;script&gt;alert(1)&lt;/script&gt;"));
    }

    #[test]
    fn markdown_has_tables_and_links_plots_written_beside_it() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let mut r = report("a|b");
        r.methods[1].name = "chc_x".into();
        let path = dir.join("out.md");
        let written = write_markdown(&[r, report("plant")], &path).unwrap();
        let names: Vec<String> =
            written.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(
            names,
            ["out-1-frame-time.svg", "out-1-queries.svg", "out-2-frame-time.svg", "out-2-queries.svg", "out.md"]
        );
        let md = std::fs::read_to_string(&path).unwrap();
        assert!(md.starts_with("# occlude benchmark report\n"));
        assert!(md.contains("\n## a\\|b (small): bvh hierarchy"), "{md}");
        assert!(md.contains("\n| method | sim ms | sim p95 ms |"), "{md}");
        assert!(md.contains("\n| :-- | --: |"));
        assert!(md.contains("\n| chc\\_x | 8.000 |"), "{md}");
        assert!(md.contains("\n| vfc | 20.000 |"));
        assert!(md.contains("![Frame time over the walkthrough](<out-1-frame-time.svg>)"));
        assert!(md.contains("![Queries and state changes per frame](<out-2-queries.svg>)"));
        for svg in &written[..4] {
            assert!(std::fs::read_to_string(svg).unwrap().starts_with("<svg"), "{}", svg.display());
        }
    }

    #[test]
    fn load_reads_an_object_or_an_array_and_names_the_file_otherwise() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let one = dir.join("one.json");
        std::fs::write(&one, serde_json::to_string(&report("city")).unwrap()).unwrap();
        assert_eq!(load(&one).unwrap(), vec![report("city")]);
        // A report from before `--queries` loads as counted by hardware.
        let mut old = serde_json::to_value(report("city")).unwrap();
        old.as_object_mut().unwrap().remove("queries");
        let before = dir.join("before.json");
        std::fs::write(&before, old.to_string()).unwrap();
        assert_eq!(load(&before).unwrap()[0].queries, "hardware");
        let many = dir.join("many.json");
        std::fs::write(&many, serde_json::to_string(&[report("city"), report("plant")]).unwrap()).unwrap();
        assert_eq!(load(&many).unwrap().len(), 2);

        let error = |name: &str, text: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            format!("{:#}", anyhow::Error::from(load(&path).unwrap_err()))
        };
        let e = error("missing.json", r#"{"scene": "city"}"#);
        assert!(e.contains("missing.json is not a bench report") && e.contains("missing field `size`"), "{e}");
        let mut broken = serde_json::to_value(report("city")).unwrap();
        broken.as_object_mut().unwrap().remove("methods");
        let e =
            error("item.json", &serde_json::to_string(&[serde_json::to_value(report("a")).unwrap(), broken]).unwrap());
        assert!(e.contains("item.json: item 1 of the array") && e.contains("missing field `methods`"), "{e}");
        let e = error("number.json", "42");
        assert!(e.contains("number.json: expected a bench report") && e.contains("found a number"), "{e}");
        let tables = dir.join("tables.json");
        let paper: occlude_bench::paper_tables::PaperTables = occlude_bench::paper_tables::PaperTables {
            paper: "chc".into(),
            tables: Vec::new(),
            reports: vec![report("city"), report("plant")],
        };
        std::fs::write(&tables, serde_json::to_string(&paper).unwrap()).unwrap();
        assert_eq!(load(&tables).unwrap(), paper.reports, "a paper's tables are read as their reports");
        let e = error("bare.json", r#"{"paper": "chc", "tables": []}"#);
        assert!(e.contains("bare.json: a paper's tables without"), "{e}");
        let e = error("empty.json", "[]");
        assert!(e.contains("empty.json: the array holds no bench reports"), "{e}");
        let e = error("text.json", "scene: city");
        assert!(e.contains("text.json is not valid JSON"), "{e}");
        let e = format!("{:#}", anyhow::Error::from(load(&dir.join("absent.json")).unwrap_err()));
        assert!(e.contains("cannot read") && e.contains("absent.json"), "{e}");
    }
}
