//! The papers' plots along the walkthrough, written by `occlude bench --paper
//! P --plot PATH` (frame times) and `--plot-queries PATH` (queries and
//! state changes): one file per scene, `PATH`'s name with the scene's put
//! before the extension (`--plot out/chc.svg` writes `out/chc-teapots.svg`,
//! `out/chc-city.svg`, `out/chc-plant.svg`), one line per method of the
//! paper's compared table, or only those its figure draws. Each is titled
//! with the paper's figure where it has one:
//!
//! - the CHC paper's Figures 5, 6 and 7 (Figure 7 on a logarithmic axis,
//!   as the paper's);
//! - the CHC++ paper's Figure 1 (the power plant), Figure 7 (frame times in
//!   Pompeii, which we lack: the teapots stand in, and the title says so),
//!   Figure 10 (the city's queries, state changes and frame times), and
//!   the figures with runs of their own: Figure 8 (the plant, CHC++'s
//!   optimisations added one at a time, a line per step) and Figure 9 (a
//!   plot per shading);
//! - the occupancy-map paper's Figure 7 (the city; the paper plots frame
//!   rates, and rendered polygons, drawn here as triangles per frame below
//!   the frame times);
//! - the IOC poster's Figure 4.

use super::plot::{write_styled_plot, PlotKind, PlotStyle, TimeScale};
use anyhow::{Context, Result};
use occlude_bench::paper::{check_walkthroughs, PaperResult};
use occlude_bench::summary::BenchReport;
use std::path::{Path, PathBuf};

/// One scene's figures in a paper.
struct SceneFigures {
    paper: &'static str,
    scene: &'static str,
    /// The paper's figure of frame times along this walkthrough, if any.
    frame_time: Option<&'static str>,
    /// The paper's figure of queries and state changes, if any.
    queries: Option<&'static str>,
    /// The frame-time axis: the paper's where it has a figure.
    time_scale: TimeScale,
    /// The paper's own scene, where it plots the figure on one we lack.
    paper_scene: Option<&'static str>,
    /// The methods the paper's figure draws, in its order (empty: every
    /// method of the compared table).
    lines: &'static [&'static str],
}

/// Every paper's figures along its walkthroughs. A scene a paper plots
/// nothing of has no entry; its plots say so in the title.
const FIGURES: &[SceneFigures] = &[
    SceneFigures {
        paper: "chc",
        scene: "teapots",
        frame_time: Some("Figure 5"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &[],
    },
    SceneFigures {
        paper: "chc",
        scene: "city",
        frame_time: Some("Figure 6"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &[],
    },
    SceneFigures {
        paper: "chc",
        scene: "plant",
        frame_time: Some("Figure 7"),
        queries: None,
        time_scale: TimeScale::Log,
        paper_scene: None,
        lines: &[],
    },
    SceneFigures {
        paper: "chcpp",
        scene: "teapots",
        frame_time: Some("Figure 7"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: Some("Pompeii"),
        lines: &["nohc", "nohc-opt", "chcpp", "ideal-sorted"],
    },
    SceneFigures {
        paper: "chcpp",
        scene: "city",
        frame_time: Some("Figure 10"),
        queries: Some("Figure 10"),
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &["vfc", "chc", "nohc", "chcpp"],
    },
    SceneFigures {
        paper: "chcpp",
        scene: "plant",
        frame_time: Some("Figure 1"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &["vfc", "chc", "nohc", "chcpp"],
    },
    SceneFigures {
        paper: "om",
        scene: "city",
        frame_time: Some("Figure 7"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &[],
    },
    SceneFigures {
        paper: "ioc",
        scene: "rooms",
        frame_time: Some("Figure 4"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &[],
    },
    SceneFigures {
        paper: "ioc",
        scene: "downtown",
        frame_time: Some("Figure 4"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &[],
    },
    SceneFigures {
        paper: "ioc",
        scene: "figures",
        frame_time: Some("Figure 4"),
        queries: None,
        time_scale: TimeScale::Linear,
        paper_scene: None,
        lines: &[],
    },
];

/// The paper's name in a title.
fn paper_name(paper: &str) -> &str {
    match paper {
        "chc" => "CHC paper",
        "chcpp" => "CHC++ paper",
        "om" => "Occupancy-map paper",
        "ioc" => "IOC poster",
        other => other,
    }
}

/// The title and axis of `paper`'s `kind` plot of `scene`.
pub fn style(paper: &str, scene: &str, kind: PlotKind) -> PlotStyle {
    let what = match kind {
        PlotKind::FrameTime if paper == "om" => "frame times and triangles drawn",
        PlotKind::FrameTime => "frame times",
        PlotKind::QueriesAndStateChanges => "queries and state changes",
    };
    let found = figure(paper, scene, kind);
    let name = paper_name(paper);
    let title = match found {
        Some((f, figure)) => match f.paper_scene {
            Some(theirs) => format!("{name}, {figure} (the paper's on {theirs}): {what}"),
            None => format!("{name}, {figure}: {what}"),
        },
        None => format!("{name}'s setting, {what} (no figure in the paper)"),
    };
    let time_scale = found.map_or(TimeScale::Auto, |(f, _)| f.time_scale);
    let triangles = paper == "om" && kind == PlotKind::FrameTime;
    PlotStyle { title: Some(title), time_scale, triangles }
}

/// `paper`'s `kind` figure of `scene`, if the paper has one: its scene's
/// entry and the figure's name.
fn figure(paper: &str, scene: &str, kind: PlotKind) -> Option<(&'static SceneFigures, &'static str)> {
    let f = FIGURES.iter().find(|f| f.paper == paper && f.scene == scene)?;
    let figure = match kind {
        PlotKind::FrameTime => f.frame_time,
        PlotKind::QueriesAndStateChanges => f.queries,
    }?;
    Some((f, figure))
}

/// `report` with only the methods `paper`'s `kind` figure of its scene
/// draws (all of them where the figure names none, or where the paper has
/// no such figure).
fn paper_lines(report: &BenchReport, paper: &str, kind: PlotKind) -> BenchReport {
    let lines = figure(paper, &report.scene, kind).map_or(&[][..], |(f, _)| f.lines);
    let drawn = |name: &str| lines.is_empty() || lines.contains(&name);
    let mut methods: Vec<_> = report.methods.iter().filter(|m| drawn(&m.name)).cloned().collect();
    methods.sort_by_key(|m| lines.iter().position(|&l| l == m.name));
    BenchReport { methods, ..report.clone() }
}

/// The file of `scene`'s plot: `path` with `-SCENE` put before its extension.
pub fn scene_path(path: &Path, scene: &str) -> PathBuf {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let name = match path.extension() {
        Some(ext) => format!("{stem}-{scene}.{}", ext.to_string_lossy()),
        None => format!("{stem}-{scene}"),
    };
    path.with_file_name(name)
}

/// Writes `kind` plots of each scene of `result` (the run of the compared
/// methods), and frame-time plots of its figures' own runs (CHC++'s Figure
/// 9: `chcpp-plant-fig9-dp.svg` and so on), to the files [`scene_path`]
/// names after `path`; returns them.
pub fn write(result: &PaperResult, kind: PlotKind, path: &Path) -> Result<Vec<PathBuf>> {
    let paper = &result.tables.paper;
    check_walkthroughs(paper, "--plot")?;
    let mut written = Vec::new();
    for &i in &result.compared_runs {
        let report = result.tables.reports.get(i).context("a compared run's report is missing")?;
        let file = scene_path(path, &report.scene);
        let style = style(paper, &report.scene, kind);
        write_styled_plot(&paper_lines(report, paper, kind), kind, &style, &file)?;
        written.push(file);
    }
    // A figure's own runs plot frame times only.
    for run in result.figure_runs.iter().filter(|_| kind == PlotKind::FrameTime) {
        let report = result.figure_report(run).context("a figure's report is missing")?;
        let file = scene_path(path, &run.tag);
        let title = format!("{}, {}: frame times", paper_name(paper), run.figure);
        write_styled_plot(&report, kind, &PlotStyle { title: Some(title), ..PlotStyle::default() }, &file)?;
        written.push(file);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::super::plot::tests::method;
    use super::*;

    #[test]
    fn scene_files_are_named_after_the_path() {
        assert_eq!(scene_path(Path::new("out/chc.svg"), "city"), Path::new("out/chc-city.svg"));
        assert_eq!(scene_path(Path::new("chc.PNG"), "plant"), Path::new("chc-plant.PNG"));
        assert_eq!(scene_path(Path::new("/tmp/a.b.png"), "teapots"), Path::new("/tmp/a.b-teapots.png"));
    }

    #[test]
    fn figures_carry_the_papers_numbers_and_axes() {
        let plant = style("chc", "plant", PlotKind::FrameTime);
        assert_eq!(plant.title.as_deref(), Some("CHC paper, Figure 7: frame times"));
        assert_eq!(plant.time_scale, TimeScale::Log);
        assert_eq!(style("chc", "city", PlotKind::FrameTime).time_scale, TimeScale::Linear);
        let queries = style("chcpp", "city", PlotKind::QueriesAndStateChanges);
        assert_eq!(queries.title.as_deref(), Some("CHC++ paper, Figure 10: queries and state changes"));
        let om = style("om", "city", PlotKind::FrameTime);
        assert_eq!(om.title.as_deref(), Some("Occupancy-map paper, Figure 7: frame times and triangles drawn"));
        assert!(om.triangles && !plant.triangles);
        let none = style("chc", "city", PlotKind::QueriesAndStateChanges);
        assert_eq!(
            none.title.as_deref(),
            Some("CHC paper's setting, queries and state changes (no figure in the paper)")
        );
        assert_eq!(none.time_scale, TimeScale::Auto);
        // Every figure's paper is one `--paper` runs.
        for f in FIGURES {
            assert!(occlude_bench::paper::PAPERS.contains(&f.paper), "{}", f.paper);
        }
    }

    #[test]
    fn chcpp_figures_draw_the_papers_lines_and_name_a_stand_in_scene() {
        let teapots = style("chcpp", "teapots", PlotKind::FrameTime);
        assert_eq!(teapots.title.as_deref(), Some("CHC++ paper, Figure 7 (the paper's on Pompeii): frame times"));
        let names = ["vfc", "sw", "chc", "chcpp", "nohc", "nohc-opt", "ideal-sorted", "opt"];
        let mut plant = super::super::plot::tests::report(names.iter().map(|n| method(n, &[(1.0, 0, 0)])).collect());
        plant.scene = "plant".into();
        let drawn = |r: &BenchReport| r.methods.iter().map(|m| m.name.clone()).collect::<Vec<_>>();
        // Figure 1 draws four of the eight, in the paper's legend order.
        assert_eq!(drawn(&paper_lines(&plant, "chcpp", PlotKind::FrameTime)), ["vfc", "chc", "nohc", "chcpp"]);
        // The plant has no figure of queries: every method is drawn.
        assert_eq!(drawn(&paper_lines(&plant, "chcpp", PlotKind::QueriesAndStateChanges)), names);
        let mut teapots = BenchReport { scene: "teapots".into(), ..plant.clone() };
        assert_eq!(
            drawn(&paper_lines(&teapots, "chcpp", PlotKind::FrameTime)),
            ["nohc", "nohc-opt", "chcpp", "ideal-sorted"]
        );
        // A figure that names no lines draws them all.
        teapots.methods.truncate(5);
        assert_eq!(drawn(&paper_lines(&teapots, "chc", PlotKind::FrameTime)), names[..5]);
    }

    #[test]
    fn gvq_is_not_plotted() {
        assert!(check_walkthroughs("chc", "--plot").is_ok());
        let err = check_walkthroughs("gvq", "--plot").unwrap_err().to_string();
        assert!(err.contains("--plot") && err.contains("--paper gvq"), "{err}");
    }
}
