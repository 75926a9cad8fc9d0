//! The papers' plots along the walkthrough, written by `occlude bench --paper
//! P --plot PATH` (frame times) and `--plot-queries PATH` (queries and
//! state changes): one file per scene, `PATH`'s name with the scene's put
//! before the extension (`--plot out/chc.svg` writes `out/chc-teapots.svg`,
//! `out/chc-city.svg`, `out/chc-plant.svg`), one line per method of the
//! paper's compared table (the variants of its other tables are not lines),
//! titled with the paper's figure where it has one: the CHC paper's Figures
//! 5, 6 and 7 (Figure 7 on a logarithmic axis, as the paper's), the CHC++
//! paper's Figure 1 (the power plant's frame times) and Figure 10 (the
//! city's queries, state changes and frame times), the occupancy-map
//! paper's Figure 7 (the city; the paper plots frame rates, and rendered
//! polygons, drawn here as triangles per frame below the frame times) and
//! the IOC poster's Figure 4.

use super::plot::{write_styled_plot, PlotKind, PlotStyle, TimeScale};
use anyhow::{Context, Result};
use occlude_bench::paper::{check_walkthroughs, PaperResult};
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
    },
    SceneFigures {
        paper: "chc",
        scene: "city",
        frame_time: Some("Figure 6"),
        queries: None,
        time_scale: TimeScale::Linear,
    },
    SceneFigures {
        paper: "chc",
        scene: "plant",
        frame_time: Some("Figure 7"),
        queries: None,
        time_scale: TimeScale::Log,
    },
    SceneFigures {
        paper: "chcpp",
        scene: "city",
        frame_time: Some("Figure 10"),
        queries: Some("Figure 10"),
        time_scale: TimeScale::Linear,
    },
    SceneFigures {
        paper: "chcpp",
        scene: "plant",
        frame_time: Some("Figure 1"),
        queries: None,
        time_scale: TimeScale::Linear,
    },
    SceneFigures {
        paper: "om",
        scene: "city",
        frame_time: Some("Figure 7"),
        queries: None,
        time_scale: TimeScale::Linear,
    },
    SceneFigures {
        paper: "ioc",
        scene: "rooms",
        frame_time: Some("Figure 4"),
        queries: None,
        time_scale: TimeScale::Linear,
    },
    SceneFigures {
        paper: "ioc",
        scene: "downtown",
        frame_time: Some("Figure 4"),
        queries: None,
        time_scale: TimeScale::Linear,
    },
    SceneFigures {
        paper: "ioc",
        scene: "figures",
        frame_time: Some("Figure 4"),
        queries: None,
        time_scale: TimeScale::Linear,
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
    let figures = FIGURES.iter().find(|f| f.paper == paper && f.scene == scene);
    let (figure, what) = match kind {
        PlotKind::FrameTime if paper == "om" => (figures.and_then(|f| f.frame_time), "frame times and triangles drawn"),
        PlotKind::FrameTime => (figures.and_then(|f| f.frame_time), "frame times"),
        PlotKind::QueriesAndStateChanges => (figures.and_then(|f| f.queries), "queries and state changes"),
    };
    let name = paper_name(paper);
    let title = match figure {
        Some(figure) => format!("{name}, {figure}: {what}"),
        None => format!("{name}'s setting, {what} (no figure in the paper)"),
    };
    let time_scale = figures.filter(|_| figure.is_some()).map_or(TimeScale::Auto, |f| f.time_scale);
    let triangles = paper == "om" && kind == PlotKind::FrameTime;
    PlotStyle { title: Some(title), time_scale, triangles }
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
        write_styled_plot(report, kind, &style(paper, &report.scene, kind), &file)?;
        written.push(file);
    }
    // A figure's own runs plot frame times only.
    for run in result.figure_runs.iter().filter(|_| kind == PlotKind::FrameTime) {
        let report = result.tables.reports.get(run.report).context("a figure's report is missing")?;
        let file = scene_path(path, &run.tag);
        let title = format!("{}, {}: frame times", paper_name(paper), run.figure);
        write_styled_plot(report, kind, &PlotStyle { title: Some(title), ..PlotStyle::default() }, &file)?;
        written.push(file);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
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
    fn gvq_is_not_plotted() {
        assert!(check_walkthroughs("chc", "--plot").is_ok());
        let err = check_walkthroughs("gvq", "--plot").unwrap_err().to_string();
        assert!(err.contains("--plot") && err.contains("--paper gvq"), "{err}");
    }
}
