//! Plots of a [`BenchReport`] over the walkthrough, as SVG or PNG: frame times
//! per method (the CHC paper's Figures 5-7, the CHC++ paper's Figure 7) and
//! queries, state changes and material switches per frame (the CHC++
//! paper's Figure 10, whose state changes are switches between drawing and
//! querying).
//!
//! Text in PNGs is drawn with the DejaVu Sans font that the `dejavu` crate
//! embeds, so no system font library or installed font is needed.

use anyhow::{bail, ensure, Context};
use occlude_bench::summary::{BenchReport, MethodSummary};
use occlude_core::FrameStats;
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordusize;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// What to plot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotKind {
    /// Frame time over the walkthrough, one line per method.
    FrameTime,
    /// Occlusion queries, state changes and material switches per frame,
    /// one line per method in each of three stacked panels.
    QueriesAndStateChanges,
}

/// How a frame-time axis is scaled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimeScale {
    /// Logarithmic where the positive frame times spread over more than a
    /// factor of 30, linear otherwise: an ordinary run's plots.
    #[default]
    Auto,
    /// Linear from zero, whatever the spread (the CHC paper's Figures 5 and 6).
    Linear,
    /// Logarithmic, whatever the spread (the CHC paper's Figure 7).
    Log,
}

/// What a plot says on top and how it scales its times; the default is an
/// ordinary run's plot. `--paper` sets both to the paper's figure.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PlotStyle {
    /// The title, in place of the plot kind's own ("Frame times", "Queries
    /// and state changes"); the run's setup follows it either way.
    pub title: Option<String>,
    /// The frame-time axis (count axes are always linear).
    pub time_scale: TimeScale,
    /// Whether a frame-time plot also draws the triangles drawn per frame
    /// below it, as the occupancy-map paper's Figures 5-8 plot rendered
    /// polygons beside frame rates.
    pub triangles: bool,
}

/// Image size in pixels.
const SIZE: (u32, u32) = (1024, 600);

/// Above this ratio of the largest to the smallest positive frame time an
/// [`TimeScale::Auto`] axis is logarithmic, as in the CHC paper's Figure 7.
const LOG_RATIO: f64 = 30.0;

/// Width of the legend strip right of each chart, in pixels: beside the
/// lines, the legend never covers them.
const LEGEND_WIDTH: u32 = 110;

/// Font family every text element uses.
pub(crate) const FONT: &str = "sans-serif";

/// Line colours, one per method in report order (repeating past ten); public
/// so that tests of rendered reports can look for the lines' pixels.
pub const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Image formats a plot can be written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotFormat {
    /// Scalable vector graphics.
    Svg,
    /// Portable network graphics.
    Png,
}

/// The format `path`'s extension asks for (.svg or .png, any case); an error
/// naming the path otherwise. Checked before a run so a typo fails fast.
pub fn plot_format(path: &Path) -> anyhow::Result<PlotFormat> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("svg") => Ok(PlotFormat::Svg),
        Some("png") => Ok(PlotFormat::Png),
        _ => bail!("cannot plot to {}: the extension must be .svg or .png", path.display()),
    }
}

/// Writes a plot of `report` to `path` in the default style; the format
/// follows the extension (see [`plot_format`]).
pub fn write_plot(report: &BenchReport, kind: PlotKind, path: &Path) -> anyhow::Result<()> {
    write_styled_plot(report, kind, &PlotStyle::default(), path)
}

/// Writes a plot of `report` to `path` in `style` (a paper's figure's title
/// and axis); the format follows the extension (see [`plot_format`]).
pub fn write_styled_plot(report: &BenchReport, kind: PlotKind, style: &PlotStyle, path: &Path) -> anyhow::Result<()> {
    let format = plot_format(path)?;
    register_font()?;
    let written = match format {
        PlotFormat::Svg => styled_svg_string(report, kind, style).and_then(|svg| Ok(std::fs::write(path, svg)?)),
        PlotFormat::Png => {
            let root = BitMapBackend::new(path, SIZE).into_drawing_area();
            draw(report, kind, style, &root).and_then(|()| Ok(root.present()?))
        }
    };
    written.with_context(|| format!("writing plot {}", path.display()))
}

/// A plot of `report` as an SVG document in memory, so that a report page can
/// embed it; [`write_plot`] writes the same document to an .svg file.
pub fn svg_string(report: &BenchReport, kind: PlotKind) -> anyhow::Result<String> {
    styled_svg_string(report, kind, &PlotStyle::default())
}

/// [`svg_string`] in `style`.
fn styled_svg_string(report: &BenchReport, kind: PlotKind, style: &PlotStyle) -> anyhow::Result<String> {
    register_font()?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(report, kind, style, &root)?;
        root.present()?;
    }
    Ok(svg)
}

/// Makes DejaVu Sans the `sans-serif` font (once per process).
pub(crate) fn register_font() -> anyhow::Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok());
    ensure!(ok, "the embedded DejaVu Sans font could not be loaded");
    Ok(())
}

/// Draws the whole plot on `root`.
fn draw<DB>(
    report: &BenchReport,
    kind: PlotKind,
    style: &PlotStyle,
    root: &DrawingArea<DB, Shift>,
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let setup = format!(
        "{} ({}), {} hierarchy, {} GPU model, {} backend",
        report.scene, report.size, report.hierarchy, report.gpu_model, report.backend
    );
    // The papers plot over the frame index, the frames at the run's rate.
    let x_desc = report.fps.map_or_else(|| "frame".to_string(), |fps| format!("frame (at {fps} fps)"));
    let title = |own: &str| format!("{}: {setup}", style.title.as_deref().unwrap_or(own));
    match kind {
        PlotKind::FrameTime => {
            let y_desc = if report.backend == "soft" { "simulated frame time (ms)" } else { "frame time (ms)" };
            let panel = Panel {
                caption: title("Frame times"),
                x_desc: &x_desc,
                y_desc,
                counts: false,
                scale: style.time_scale,
                series: series(&report.methods, |f| f.frame_ms),
            };
            if !style.triangles {
                return panel.draw(root);
            }
            let (top, bottom) = root.split_vertically(root.dim_in_pixel().1 / 2);
            panel.draw(&top)?;
            let triangles = Panel {
                caption: "triangles drawn per frame".into(),
                x_desc: &x_desc,
                y_desc: "triangles",
                counts: true,
                scale: TimeScale::Linear,
                series: series(&report.methods, |f| f.triangles as f64),
            };
            triangles.draw(&bottom)
        }
        PlotKind::QueriesAndStateChanges => {
            let root = root.titled(&title("Queries and state changes"), (FONT, 20))?;
            let third = root.dim_in_pixel().1 / 3;
            let (top, rest) = root.split_vertically(third);
            let (middle, bottom) = rest.split_vertically(third);
            // Three panels of counts per frame, one line per method each.
            let counts = |caption: &str, y_desc: &'static str, value: fn(&FrameStats) -> f64| Panel {
                caption: caption.into(),
                x_desc: &x_desc,
                y_desc,
                counts: true,
                scale: TimeScale::Linear,
                series: series(&report.methods, value),
            };
            counts("occlusion queries per frame", "queries", |f| f.queries as f64).draw(&top)?;
            let changes = "state changes per frame (switches between drawing and querying)";
            counts(changes, "state changes", |f| f.state_changes as f64).draw(&middle)?;
            counts("material switches per frame", "material switches", |f| f.material_switches as f64).draw(&bottom)
        }
    }
}

/// One method's line: its name and a value per frame.
struct Series<'a> {
    name: &'a str,
    values: Vec<f64>,
}

/// `value` of every frame of every method.
fn series(methods: &[MethodSummary], value: impl Fn(&FrameStats) -> f64) -> Vec<Series<'_>> {
    methods.iter().map(|m| Series { name: &m.name, values: m.per_frame.iter().map(&value).collect() }).collect()
}

/// One chart: a line per method over the frame index.
struct Panel<'a> {
    caption: String,
    x_desc: &'a str,
    y_desc: &'a str,
    /// Whole numbers per frame, labelled without decimals.
    counts: bool,
    /// The y-axis's scale.
    scale: TimeScale,
    series: Vec<Series<'a>>,
}

/// The most powers of ten a logarithmic axis spans.
const MAX_DECADES: i32 = 12;

/// The y-axis a panel's values call for.
#[derive(Debug, PartialEq)]
enum YAxis {
    /// Linear from 0 to the given top.
    Linear(f64),
    /// Logarithmic between the given bounds (both positive).
    Log(f64, f64),
}

/// Logarithmic around the finite positive values if `scale` is `Log`, or
/// `Auto` and they span more than [`LOG_RATIO`], from the power of ten
/// below them to the one above, so that at least two labels (which a log
/// axis puts at powers of ten) show; linear from 0 otherwise. A plot with
/// no positive value gets the linear range 0 to 1. The axis is finite
/// whatever the values: it spans at most [`MAX_DECADES`] powers of ten below
/// the largest value, and values near `f64::MAX` are cut at
/// [`occlude_bench::figures::MAX_FIGURE`], so that no axis has infinitely many ticks.
fn y_axis(values: impl Iterator<Item = f64>, scale: TimeScale) -> YAxis {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(|v| v.min(occlude_bench::figures::MAX_FIGURE))
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let lo = lo.max(hi / 10f64.powi(MAX_DECADES));
    if hi <= 0.0 {
        YAxis::Linear(1.0)
    } else if scale == TimeScale::Log || (scale == TimeScale::Auto && hi / lo > LOG_RATIO) {
        YAxis::Log(10f64.powf((lo / 1.25).log10().floor()), 10f64.powf((hi * 1.25).log10().ceil()))
    } else {
        YAxis::Linear(hi * 1.05)
    }
}

impl Panel<'_> {
    /// Draws the panel on `area`.
    fn draw<DB>(&self, area: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB: DrawingBackend,
        DB::ErrorType: 'static,
    {
        let frames = self.series.iter().map(|s| s.values.len()).max().unwrap_or(0);
        let x_range = 0..frames.saturating_sub(1).max(1);
        let body = area.titled(&self.caption, (FONT, 18))?;
        // The legend widens to its longest name (Figure 8's steps are long).
        let mut legend_width = LEGEND_WIDTH;
        for s in &self.series {
            legend_width = legend_width.max(40 + body.estimate_text_size(s.name, &(FONT, 15).into())?.0);
        }
        let (plot, legend) = body.split_horizontally(body.dim_in_pixel().0.saturating_sub(legend_width));
        self.legend(&legend)?;
        let mut builder = ChartBuilder::on(&plot);
        builder.margin(12).x_label_area_size(40).y_label_area_size(70);
        match y_axis(self.series.iter().flat_map(|s| s.values.iter().copied()), self.scale) {
            YAxis::Linear(top) => {
                let chart = builder.build_cartesian_2d(x_range, 0.0..top)?;
                self.lines(chart, |v| v.is_finite())
            }
            YAxis::Log(lo, hi) => {
                let chart = builder.build_cartesian_2d(x_range, (lo..hi).log_scale())?;
                // A log axis has no place for zero: such frames are left out.
                self.lines(chart, |v| v.is_finite() && v > 0.0)
            }
        }
    }

    /// Draws each method's colour and name, one under another, on `area`.
    fn legend<DB>(&self, area: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB: DrawingBackend,
        DB::ErrorType: 'static,
    {
        for (i, s) in self.series.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let y = 20 + 22 * i as i32;
            area.draw(&PathElement::new(vec![(0, y), (24, y)], colour.stroke_width(3)))?;
            area.draw(&Text::new(s.name, (30, y - 8), (FONT, 15)))?;
        }
        Ok(())
    }

    /// Draws the mesh and one line per method (of the values `keep`
    /// accepts).
    fn lines<'a, DB, Y>(
        &self,
        mut chart: ChartContext<'a, DB, Cartesian2d<RangedCoordusize, Y>>,
        keep: impl Fn(f64) -> bool,
    ) -> anyhow::Result<()>
    where
        DB: DrawingBackend + 'a,
        DB::ErrorType: 'static,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(self.x_desc)
            .y_desc(self.y_desc)
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 16))
            .light_line_style(WHITE.mix(0.0));
        if self.counts {
            mesh.y_label_formatter(&count_label);
        }
        mesh.draw()?;
        for (i, s) in self.series.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points = s.values.iter().copied().enumerate().filter(|&(_, v)| keep(v));
            chart.draw_series(LineSeries::new(points, colour.stroke_width(2)))?;
        }
        Ok(())
    }
}

/// A count axis label: whole numbers without decimals (`500`, not `500.0`),
/// the fractional ticks of a small range with one.
fn count_label(v: &f64) -> String {
    if v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.1}")
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use occlude_bench::summary::SceneStats;
    use std::collections::BTreeMap;

    /// A method whose frames have the given frame times, queries and state changes.
    pub(in crate::bench) fn method(name: &str, frames: &[(f64, u64, u64)]) -> MethodSummary {
        let per_frame: Vec<FrameStats> = frames
            .iter()
            .map(|&(frame_ms, queries, state_changes)| FrameStats {
                frame_ms,
                queries,
                state_changes,
                ..Default::default()
            })
            .collect();
        MethodSummary {
            name: name.into(),
            params: BTreeMap::new(),
            mean_frame_ms: 0.0,
            p95_frame_ms: 0.0,
            queries_per_frame: 0.0,
            wait_ms_per_frame: 0.0,
            draw_calls_per_frame: 0.0,
            state_changes_per_frame: 0.0,
            material_switches_per_frame: 0.0,
            triangles_per_frame: 0.0,
            visible_objects_per_frame: 0.0,
            missing_pixels: 0,
            speedup_vs_vfc: 0.0,
            ratio_to_opt: None,
            cpu_ms_per_frame: 0.0,
            gpu_ms_per_frame: 0.0,
            wall_ms: 0.0,
            counters_per_frame: BTreeMap::new(),
            per_frame,
            ..Default::default()
        }
    }

    /// A report on the soft backend with the given methods.
    pub(in crate::bench) fn report(methods: Vec<MethodSummary>) -> BenchReport {
        let frames = methods.iter().map(|m| m.per_frame.len()).max().unwrap_or(0);
        BenchReport {
            scene: "city".into(),
            size: "small".into(),
            frames,
            fps: None,
            resolution: [64, 48],
            backend: "soft".into(),
            queries: "hardware".into(),
            adapter: None,
            aborted: None,
            gpu_model: "gf6800".into(),
            hierarchy: "bvh".into(),
            seed: 1,
            scene_stats: SceneStats {
                triangles: 0,
                unique_triangles: 0,
                instances: 0,
                materials: 0,
                nodes: 0,
                leaves: 0,
                depth: 0,
                frames,
                build_wall_ms: 0.0,
            },
            methods,
        }
    }

    /// Three methods over 40 frames; `vfc` issues no queries.
    fn sample() -> BenchReport {
        let frames = |base: f64, q: u64| -> Vec<(f64, u64, u64)> {
            (0..40u64).map(|i| (base + (i as f64 * 0.3).sin() * base * 0.5, q * (i % 7 + 1), q + i)).collect()
        };
        report(vec![method("vfc", &frames(20.0, 0)), method("sw", &frames(12.0, 30)), method("chc", &frames(6.0, 10))])
    }

    /// Pixels of the PNG at `path` that are not white, and whether any has
    /// exactly `colour`.
    fn png_ink(path: &Path, colour: RGBColor) -> (usize, bool) {
        let bytes = std::fs::read(path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{} is not a PNG", path.display());
        let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), SIZE);
        let ink = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
        let found = img.pixels().any(|p| p.0 == [colour.0, colour.1, colour.2]);
        (ink, found)
    }

    #[test]
    fn svg_plots_name_every_method_and_draw_lines() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let r = sample();
        for (kind, file, label) in [
            (PlotKind::FrameTime, "t.svg", "simulated frame time (ms)"),
            (
                PlotKind::QueriesAndStateChanges,
                "q.svg",
                "state changes per frame (switches between drawing and querying)",
            ),
            (PlotKind::QueriesAndStateChanges, "q.svg", "material switches per frame"),
        ] {
            let path = dir.join(file);
            write_plot(&r, kind, &path).unwrap();
            let svg = std::fs::read_to_string(&path).unwrap();
            assert!(svg.starts_with("<svg"), "{file}: {}", &svg[..svg.len().min(80)]);
            for m in &r.methods {
                assert!(svg.contains(&format!("\n{}\n</text>", m.name)), "{file} has no legend entry for {}", m.name);
            }
            assert!(svg.contains(label), "{file} lacks {label:?}");
            let lines = svg.matches("<polyline").count();
            // One line per method (per panel), plus its legend sample.
            let panels = if kind == PlotKind::FrameTime { 1 } else { 3 };
            assert!(lines >= 2 * r.methods.len() * panels, "{file}: only {lines} polylines");
        }
    }

    #[test]
    fn a_frame_time_plot_with_triangles_draws_them_below() {
        let r = sample();
        let style = PlotStyle { triangles: true, ..PlotStyle::default() };
        let with = styled_svg_string(&r, PlotKind::FrameTime, &style).unwrap();
        let without = styled_svg_string(&r, PlotKind::FrameTime, &PlotStyle::default()).unwrap();
        assert!(with.contains("triangles drawn per frame") && !without.contains("triangles drawn per frame"));
        let lines = |svg: &str| svg.matches("<polyline").count();
        // The second panel: a line and a legend sample per method.
        assert!(lines(&with) >= lines(&without) + 2 * r.methods.len(), "{} against {}", lines(&with), lines(&without));
    }

    #[test]
    fn wgpu_frame_times_are_not_called_simulated() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let mut r = sample();
        r.backend = "wgpu".into();
        let path = dir.join("t.svg");
        write_plot(&r, PlotKind::FrameTime, &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("\nframe time (ms)\n</text>"));
        assert!(!svg.contains("simulated"));
    }

    #[test]
    fn png_plots_are_drawn_in_method_colours() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let r = sample();
        for (kind, file) in [(PlotKind::FrameTime, "t.png"), (PlotKind::QueriesAndStateChanges, "q.PNG")] {
            let path = dir.join(file);
            write_plot(&r, kind, &path).unwrap();
            let (ink, has_last_colour) = png_ink(&path, COLOURS[2]);
            let total = (SIZE.0 * SIZE.1) as usize;
            assert!(ink > total / 100, "{file}: only {ink} of {total} pixels drawn");
            assert!(ink < total / 2, "{file}: {ink} of {total} pixels drawn");
            assert!(has_last_colour, "{file}: no pixel in the third method's colour");
        }
    }

    #[test]
    fn png_text_is_rendered() {
        // The same chart with and without a long title: the title's glyphs
        // must add ink, which they would not if text were silently dropped.
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let mut r = sample();
        write_plot(&r, PlotKind::FrameTime, &dir.join("a.png")).unwrap();
        r.scene = "a much longer scene name that takes a lot of room".into();
        write_plot(&r, PlotKind::FrameTime, &dir.join("b.png")).unwrap();
        let (short, _) = png_ink(&dir.join("a.png"), BLACK);
        let (long, _) = png_ink(&dir.join("b.png"), BLACK);
        assert!(long > short + 500, "title text added {} pixels", long as i64 - short as i64);
    }

    #[test]
    fn other_extensions_are_refused_by_name() {
        let path = Path::new("/nonexistent/plot.jpg");
        let err = write_plot(&sample(), PlotKind::FrameTime, path).unwrap_err().to_string();
        assert!(err.contains("/nonexistent/plot.jpg") && err.contains(".svg") && err.contains(".png"), "{err}");
        let err = write_plot(&sample(), PlotKind::FrameTime, Path::new("plot")).unwrap_err().to_string();
        assert!(err.contains("plot"), "{err}");
    }

    #[test]
    fn unwritable_path_is_an_error_naming_it() {
        let path = Path::new("/nonexistent-dir/for/plot.svg");
        let err = format!("{:#}", write_plot(&sample(), PlotKind::FrameTime, path).unwrap_err());
        assert!(err.contains("/nonexistent-dir/for/plot.svg"), "{err}");
    }

    #[test]
    fn empty_and_zero_reports_plot() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let zeros = [(0.0, 0, 0); 5];
        // Zero frames, zero-time frames, and zeros beside a wide spread (log axis).
        let reports = [
            report(vec![]),
            report(vec![method("vfc", &[])]),
            report(vec![method("vfc", &zeros), method("chc", &zeros)]),
            report(vec![method("vfc", &[(0.0, 0, 0), (100.0, 5, 5), (1.0, 1, 1)]), method("opt", &zeros)]),
            report(vec![method("vfc", &[(f64::NAN, 0, 0), (2.0, 1, 1)])]),
        ];
        for (i, r) in reports.iter().enumerate() {
            for kind in [PlotKind::FrameTime, PlotKind::QueriesAndStateChanges] {
                for ext in ["svg", "png"] {
                    let path = dir.join(format!("{i}-{kind:?}.{ext}"));
                    write_plot(r, kind, &path).unwrap();
                    assert!(std::fs::metadata(&path).unwrap().len() > 0);
                }
            }
        }
    }

    #[test]
    fn count_labels_drop_needless_decimals() {
        assert_eq!(count_label(&500.0), "500");
        assert_eq!(count_label(&0.0), "0");
        assert_eq!(count_label(&0.30000000000000004), "0.3");
    }

    #[test]
    fn log_axis_only_for_wide_positive_spreads() {
        use TimeScale::{Auto, Linear, Log};
        assert_eq!(y_axis([0.0, 1.0, 20.0].into_iter(), Auto), YAxis::Linear(21.0));
        assert_eq!(y_axis([0.0, 1.0, 40.0].into_iter(), Auto), YAxis::Log(0.1, 100.0));
        assert_eq!(y_axis([1.0, 40.0].into_iter(), Linear), YAxis::Linear(42.0));
        assert_eq!(y_axis([0.0, -3.0, f64::NAN].into_iter(), Auto), YAxis::Linear(1.0));
        assert_eq!(y_axis(std::iter::empty(), Auto), YAxis::Linear(1.0));
        // Forced: a narrow spread on a log axis, a wide one on a linear axis.
        assert_eq!(y_axis([0.0, 1.0, 2.0].into_iter(), Log), YAxis::Log(0.1, 10.0));
        assert_eq!(y_axis([20.0, 30.0].into_iter(), Log), YAxis::Log(10.0, 100.0));
        assert_eq!(y_axis([0.0, -3.0].into_iter(), Log), YAxis::Linear(1.0));
    }

    #[test]
    fn every_axis_is_finite_and_spans_a_bounded_number_of_decades() {
        let extremes = [f64::MAX, 5e-324, f64::MIN_POSITIVE, 1.0];
        for scale in [TimeScale::Auto, TimeScale::Linear, TimeScale::Log] {
            match y_axis(extremes.into_iter(), scale) {
                YAxis::Linear(top) => assert!(top.is_finite() && top > 0.0, "{top}"),
                YAxis::Log(lo, hi) => {
                    assert!(lo > 0.0 && hi.is_finite(), "{lo} {hi}");
                    assert!((hi / lo).log10() <= f64::from(MAX_DECADES) + 2.0, "{lo} {hi}");
                }
            }
        }
    }
}
