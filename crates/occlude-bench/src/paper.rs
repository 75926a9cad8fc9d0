//! `occlude bench --paper chc|chcpp|om|ioc|gvq`: a paper's experiments on our
//! teapots, city and plant scenes (`paper` size unless told otherwise, the
//! whole walkthrough at the frame rate), printed in the shape of its tables,
//! each of our rows beside the published figures (`published.toml`) with
//! whether the order of the methods agrees ([`crate::paper_tables`]).
//!
//! - `chc` (Bittner et al. 2004, section 6): kD-tree, `gpu-2004`; Table 1
//!   (VFC, S&W, CHC and the paper's ideal, `ideal`: S&W's draws replayed
//!   without queries ([`crate::ideal`]), with `opt`, the per-instance lower
//!   bound, beside them) and Table 2 (CHC with `tav` = 2, and with `tav` =
//!   2 and `nvp` = 25).
//! - `chcpp` (Mattausch et al. 2008, section 8): BVH, `modern`; the
//!   comparison of VFC, S&W, CHC, CHC++, NOHC, NOHC-OPT, the paper's OPT
//!   (`ideal-sorted`: S&W's visible nodes drawn without queries through
//!   the material-sorted render queue) and `opt`, an ablation of
//!   CHC++'s components, Figure 8 (the components added one at a time,
//!   plotted along the plant's walkthrough) and Figure 9 (`vfc`, `chcpp`
//!   and `nohc` on the plant's first 350 frames under each [`Shading`]).
//!
//! Each table of methods says under it which ideal it uses
//! (`Experiment::ideals`).
//! - `om` (Staneker, Bartz, Straßer): city and plant, BVH, `gpu-2004`, 800 x
//!   600 (the paper's); single queries (`sw`) against multiple queries
//!   without occupancy-map grouping and `om`.
//! - `ioc` (the IOC poster, section 3): rooms, downtown and figures, BVH with
//!   one object per leaf (the poster's node counts), the `--gpu-model` given
//!   (default `modern`; the result hangs on what a box test costs, which
//!   `occlude calibrate` measures); Table 1 (the
//!   occlusion test's and the occludees' GPU time of ROC and IOC, each beside
//!   the poster's figure, and of two-phase Hi-Z, `hiz`, which the poster does
//!   not have) and Figure 4 (frame time of NOCULL, VFC, ROC, IOC, `hiz`
//!   and the ideal set; the poster gives that one as a chart, without
//!   figures); each walkthrough's first 12 seconds, as the poster animates
//!   12-second sequences.
//! - `gvq` (granular visibility queries, sections 4.1 and 4.2): Tables 1
//!   to 3, in [`crate::gvq`], [`crate::gvq_shadows`] and
//!   [`crate::gvq_parts`].
//!
//! A run can be restricted to some of a paper's scenes (`--scene city,plant`,
//! [`check_scenes`]): a whole paper-size run of `chcpp` takes hours on two
//! cores, and a simulated table's rows do not depend on which other scenes
//! ran, so scenes run apart give the same rows as one whole run.

use crate::config::{BenchConfig, ALL_FRAMES};
use crate::error::{invalid, Result};
use crate::ideal::{IDEAL, IDEAL_SORTED};
use crate::paper_tables::{PaperTables, Row, Table};
use crate::progress::Progress;
use crate::published;
use crate::runner::{run_scene, run_scene_with_variants, Variant};
use crate::summary::{BenchReport, MethodSummary};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::MethodOptions;
use occlude_core::{HierarchyKind, Scene};
use occlude_scenes::{Inputs, Size};
use occlude_soft::{GpuModel, Shading};
use std::fmt::Write;

/// Papers whose experiments `--paper` can run.
pub const PAPERS: [&str; 5] = ["chc", "chcpp", "om", "ioc", "gvq"];

/// The scenes of the CHC papers' tables, in the CHC paper's order.
const CHC_SCENES: &[&str] = &["teapots", "city", "plant"];

/// One paper's setting.
struct Experiment {
    /// The paper, as `--paper` names it.
    paper: &'static str,
    title: &'static str,
    scenes: &'static [&'static str],
    /// The scene inputs the paper leaves unstated ([`Inputs`]).
    inputs: Inputs,
    hierarchy: HierarchyKind,
    gpu_model: fn() -> GpuModel,
    methods: &'static [&'static str],
    /// The name of the table of methods compared (as the paper names it
    /// where it published one).
    compared: &'static str,
    /// The method whose options the tables of variants vary.
    varied: &'static str,
    /// Which definition of the ideal the compared table uses, printed under
    /// it.
    ideals: &'static str,
    /// The tables of variants of `varied`.
    variant_tables: &'static [VariantTable],
    /// A figure whose runs vary the simulated GPU's shading, if any.
    shading_figure: Option<ShadingFigure>,
}

/// A figure of some methods' frames under each [`Shading`]: each setting
/// one run of its own, the GPU model's fragment cost changed, but the
/// model's own (FIX), which at a frame rate is the compared run's first
/// frames.
struct ShadingFigure {
    /// Its name in the paper.
    name: &'static str,
    /// Its plots' part of the file name.
    file: &'static str,
    scene: &'static str,
    methods: &'static [&'static str],
    /// Frames it covers from the walkthrough's start, when the run asks for
    /// the whole walkthrough.
    frames: usize,
}

/// CHC++'s Figure 9 (section 8): CHC++ and NOHC on "a walkthrough in the
/// Powerplant" of about 350 frames, depth only, fixed-pipeline shading and
/// a shader of 40 texture lookups.
const FIGURE_9: ShadingFigure =
    ShadingFigure { name: "Figure 9", file: "fig9", scene: "plant", methods: &["vfc", "chcpp", "nohc"], frames: 350 };

/// A table of variants of one method.
struct VariantTable {
    /// Its name (the paper's, where it published one).
    name: &'static str,
    /// The variants, each a label and a list of `method.key=value`; the
    /// defaults (no options) are the compared table's row of the method.
    variants: &'static [(&'static str, &'static [&'static str])],
    /// Where the paper plots the variants along a walkthrough: the scene
    /// and the plot's file tag (`fig8`), one line per variant, named by
    /// its label.
    plotted: Option<(&'static str, &'static str)>,
}

/// CHC++'s Figure 8 (section 8, p. 229): "We start with CHC and add one
/// optimization at a time", B (batching of previously visible and
/// invisible nodes: `b`, the v-queue, and the material-sorted render queue
/// the batches are flushed through, which plain CHC lacks), R
/// (randomization), TB (tighter bounds), MQ (multiqueries). "CHC" is
/// `chcpp` with all of them off: CHC on the same BVH with a visible leaf
/// re-queried every `nav` = 10 frames, the interval R randomizes.
const FIGURE_8: VariantTable = VariantTable {
    name: "Figure 8",
    variants: &[
        (
            "CHC",
            &[
                "chcpp.b=1",
                "chcpp.vqueue=off",
                "chcpp.sort=off",
                "chcpp.random=off",
                "chcpp.tight=off",
                "chcpp.multiquery=off",
            ],
        ),
        ("CHC+B", &["chcpp.random=off", "chcpp.tight=off", "chcpp.multiquery=off"]),
        ("CHC+B+R", &["chcpp.tight=off", "chcpp.multiquery=off"]),
        ("CHC+B+R+TB", &["chcpp.multiquery=off"]),
        ("CHC+B+R+TB+MQ (CHC++)", &[]),
    ],
    plotted: Some(("plant", "fig8")),
};

const CHC: Experiment = Experiment {
    paper: "chc",
    title: "CHC paper (kD-tree, gpu-2004)",
    scenes: CHC_SCENES,
    inputs: Inputs::ChcTable1,
    hierarchy: HierarchyKind::KdTree,
    gpu_model: GpuModel::gpu_2004,
    methods: &["vfc", "sw", "chc", IDEAL, "opt"],
    compared: "Table 1",
    varied: "chc",
    ideals: "ideal: the CHC paper's (section 6.2), S&W's draws replayed without queries, in S&W's order; \
             opt (not in the paper): the per-instance lower bound, the instances owning a pixel, sorted by material",
    variant_tables: &[
        VariantTable {
            name: "Table 2",
            variants: &[("", &[]), ("", &["chc.tav=2"]), ("", &["chc.tav=2", "chc.nvp=25"])],
            plotted: None,
        },
        // Section 5.3, speculative rendering, for which the paper gives no
        // figure ("We did not find constants that could produce additional
        // speedup"): the cheapest waiting node drawn while a query is out,
        // up to three triangle counts a decade apart.
        VariantTable {
            name: "section 5.3",
            variants: &[("", &[]), ("", &["chc.spec=1000"]), ("", &["chc.spec=10000"]), ("", &["chc.spec=100000"])],
            plotted: None,
        },
    ],
    shading_figure: None,
};

const CHCPP: Experiment = Experiment {
    paper: "chcpp",
    title: "CHC++ paper (BVH, modern)",
    scenes: CHC_SCENES,
    inputs: Inputs::Own,
    hierarchy: HierarchyKind::Bvh,
    gpu_model: GpuModel::modern,
    methods: &["vfc", "sw", "chc", "chcpp", "nohc", "nohc-opt", IDEAL_SORTED, "opt"],
    compared: "methods compared",
    varied: "chcpp",
    ideals: "ideal-sorted: the CHC++ paper's OPT (section 8), the nodes S&W finds visible drawn without queries \
             through chcpp's material-sorted render queue; opt (not in the paper): the per-instance lower bound, \
             the instances owning a pixel, sorted by material",
    variant_tables: &[
        VariantTable {
            name: "ablation",
            variants: &[
                ("", &[]),
                ("", &["chcpp.multiquery=off"]),
                ("", &["chcpp.vqueue=off"]),
                ("", &["chcpp.sort=off"]),
                ("", &["chcpp.random=off"]),
                ("", &["chcpp.tight=off"]),
                ("", &["chcpp.b=1"]),
                ("", &["chcpp.nav=0"]),
                ("", &["chcpp.pkeep=measured"]),
            ],
            plotted: None,
        },
        FIGURE_8,
    ],
    shading_figure: Some(FIGURE_9),
};

const OM: Experiment = Experiment {
    paper: "om",
    title: "Occupancy-map paper (BVH, gpu-2004)",
    scenes: &["city", "plant"],
    inputs: Inputs::Own,
    hierarchy: HierarchyKind::Bvh,
    gpu_model: GpuModel::gpu_2004,
    methods: &["vfc", "sw", "om", "opt"],
    compared: "Table 2",
    varied: "om",
    ideals: "opt (not in the paper): the per-instance lower bound, the instances owning a pixel, sorted by material",
    variant_tables: &[VariantTable {
        name: "variants",
        variants: &[
            ("", &[]),
            ("", &["om.grouping=off"]),
            // Stage 2's rule and the queues' order other than the paper's.
            ("", &["om.overlap=off"]),
            ("", &["om.corner=off"]),
            ("", &["om.overlap=off", "om.corner=off"]),
        ],
        plotted: None,
    }],
    shading_figure: None,
};

/// Tables and the reports behind them.
pub struct PaperResult {
    /// The printed tables.
    pub text: String,
    /// The tables and every run's report, for `--json`.
    pub tables: PaperTables,
    /// `--paper gvq`'s tables, whose rows have columns of their own;
    /// `--json` writes them instead of `tables` (which is then empty).
    pub gvq: Option<PaperTables<crate::gvq::GvqRows>>,
    /// Indices into `tables.reports` of each scene's run of the compared
    /// methods (not of a table's variants), in scene order: what
    /// the command line's `--plot` draws (`occlude_cli::bench::paper_figures`).
    pub compared_runs: Vec<usize>,
    /// The runs of a figure beyond the compared methods' (CHC++'s Figure 8,
    /// its variants' lanes as one run; Figure 9, a run per shading), which
    /// `--plot` draws too.
    pub figure_runs: Vec<FigureRun>,
}

/// A plot of one of a paper's figures, its lines methods of the tables'
/// reports.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureRun {
    /// Its part of the plot's file name (`plant-fig9-dp`).
    pub tag: String,
    /// The figure, as the paper names it, and the setting (`Figure 9, DP`).
    pub figure: String,
    /// Its lines, in legend order.
    pub lines: Vec<FigureLine>,
}

/// One line of a [`FigureRun`]: a method of one of the tables' reports.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureLine {
    /// Its name in the legend (Figure 8's `CHC+B`).
    pub label: String,
    /// Its report's index into the tables' reports.
    pub report: usize,
    /// Its index into that report's methods.
    pub method: usize,
}

impl PaperResult {
    /// `figure`'s lines as one report: the first line's run, with the
    /// lines as its methods, each named by its label.
    pub fn figure_report(&self, figure: &FigureRun) -> Option<BenchReport> {
        let reports = &self.tables.reports;
        let first = reports.get(figure.lines.first()?.report)?;
        let methods = figure.lines.iter().map(|l| {
            let method = reports.get(l.report)?.methods.get(l.method)?;
            Some(MethodSummary { name: l.label.clone(), ..method.clone() })
        });
        Some(BenchReport { methods: methods.collect::<Option<_>>()?, ..first.clone() })
    }
}

/// Papers whose tables come from no walkthrough runs (`gvq`'s are counts
/// over its own frames): `--plot`, `--plot-queries` and `--csv`, which
/// write a paper run's walkthroughs frame by frame, are usage errors with
/// them.
pub const NO_WALKTHROUGHS: [&str; 1] = ["gvq"];

/// An error unless `paper`'s runs have walkthroughs for `option` to write.
pub fn check_walkthroughs(paper: &str, option: &str) -> Result<()> {
    if NO_WALKTHROUGHS.contains(&paper) {
        invalid!("{option} cannot be combined with --paper {paper}: its tables have no walkthrough runs");
    }
    Ok(())
}

/// The setting of `paper` if its tables are [`run_experiment`]'s (not
/// `ioc`'s or `gvq`'s own).
fn experiment(paper: &str) -> Option<&'static Experiment> {
    match paper {
        "chc" => Some(&CHC),
        "chcpp" => Some(&CHCPP),
        "om" => Some(&OM),
        _ => None,
    }
}

/// The scenes `paper`'s tables run, in the paper's order; `None` for
/// `gvq`, whose tables generate scenes of their own.
pub fn paper_scenes(paper: &str) -> Option<Vec<&'static str>> {
    match experiment(paper) {
        Some(e) => Some(e.scenes.to_vec()),
        None if paper == "ioc" => Some(IOC_SCENES.iter().map(|&(scene, _)| scene).collect()),
        None => None,
    }
}

/// An error unless `only` names some of `paper`'s scenes and nothing else
/// (and `paper` has scenes to choose from).
pub fn check_scenes(paper: &str, only: &[String]) -> Result<()> {
    let Some(scenes) = paper_scenes(paper) else {
        invalid!("--scene cannot be combined with --paper {paper}: its tables generate their own scenes");
    };
    if only.is_empty() {
        invalid!("--scene names no scene: --paper {paper}'s are {}", scenes.join(", "));
    }
    for scene in only {
        if !scenes.contains(&scene.as_str()) {
            invalid!("--paper {paper} has no scene '{scene}': its scenes are {}", scenes.join(", "));
        }
    }
    Ok(())
}

/// Whether `scene` is run when `only` lists the scenes to run (empty: all).
fn chosen(only: &[String], scene: &str) -> bool {
    only.is_empty() || only.iter().any(|s| s == scene)
}

/// The size `--paper` runs at unless told otherwise: the papers' scenes
/// have millions of triangles.
pub const DEFAULT_SIZE: Size = Size::Paper;

/// The image size of `paper`'s runs unless told otherwise: the occupancy-map
/// paper's 800 x 600 (its section 5), the granular-visibility-queries
/// paper's 512 x 512 query target; the CHC papers state none, so the
/// default 1024 x 768 stays.
pub fn default_resolution(paper: &str) -> Option<(u32, u32)> {
    match paper {
        "om" => Some((800, 600)),
        "gvq" => Some(crate::gvq::RESOLUTION),
        _ => None,
    }
}

/// Runs the experiments of `paper` with the size, seed, frames and
/// resolution of `base`; scenes, methods, hierarchy and GPU model are the
/// paper's. `only` names the paper's scenes to run (empty: all of them; see
/// [`check_scenes`]).
pub fn run(paper: &str, base: &BenchConfig, only: &[String], progress: &dyn Progress) -> Result<PaperResult> {
    if !only.is_empty() {
        check_scenes(paper, only)?;
    }
    if let Some(experiment) = experiment(paper) {
        return run_experiment(experiment, base, only, progress);
    }
    match paper {
        "ioc" => run_ioc(base, only, progress),
        "gvq" => {
            let (text, gvq) = crate::gvq::run(base, progress)?;
            Ok(PaperResult {
                text,
                tables: PaperTables { paper: "gvq".into(), ..PaperTables::default() },
                gvq: Some(gvq),
                compared_runs: Vec::new(),
                figure_runs: Vec::new(),
            })
        }
        _ => invalid!("unknown paper '{paper}': expected one of {}", PAPERS.join(", ")),
    }
}

fn run_experiment(e: &Experiment, base: &BenchConfig, only: &[String], progress: &dyn Progress) -> Result<PaperResult> {
    let published = published::table(e.paper, e.compared);
    let mut compared = Vec::new();
    let mut varied: Vec<Vec<Row>> = e.variant_tables.iter().map(|_| Vec::new()).collect();
    // Every variant other than the defaults, once, whichever tables list it.
    let mut lane_options: Vec<&[&str]> = Vec::new();
    for (_, opts) in e.variant_tables.iter().flat_map(|t| t.variants) {
        if !opts.is_empty() && !lane_options.contains(opts) {
            lane_options.push(opts);
        }
    }
    let mut reports = Vec::new();
    let mut compared_runs = Vec::new();
    let mut shaded = Vec::new();
    let mut figure_runs = Vec::new();
    for &scene_name in e.scenes.iter().filter(|s| chosen(only, s)) {
        let config = BenchConfig {
            scene: scene_name.into(),
            methods: e.methods.iter().map(|m| m.to_string()).collect(),
            hierarchy: e.hierarchy,
            gpu_model: (e.gpu_model)(),
            options: MethodOptions::default(),
            ..base.clone()
        };
        config.validate()?;
        let scene = occlude_scenes::generate_with(scene_name, config.size, config.seed, e.inputs)?;
        // The variants run as lanes of the same run: `vfc` renders once per
        // scene.
        let variants = lane_options
            .iter()
            .map(|opts| Ok(Variant { method: e.varied.into(), options: MethodOptions::parse(opts)? }))
            .collect::<Result<Vec<_>>>()?;
        progress.message(&format!("{scene_name} {}: methods and {} variants", config.size, variants.len()));
        let run = run_scene_with_variants(&scene, &config, &variants, progress)?;
        let report = run.report(&config);
        compared.extend(report.methods.iter().map(|m| Row::new(scene_name, m, "", published)));
        let defaults = report.methods.iter().position(|m| m.name == e.varied);
        let defaults = defaults.expect("every experiment's varied method is one of its methods");
        let compared_report = reports.len();
        compared_runs.push(compared_report);
        reports.push(report);
        let lanes: Vec<usize> = run
            .variants
            .iter()
            .map(|lane| {
                reports.push(BenchReport::with_methods(&run, std::slice::from_ref(lane), &config));
                reports.len() - 1
            })
            .collect();
        // A variant's lane, as a report and a method of it: its own, or the
        // compared run's for the defaults.
        let lane_of = |opts: &&[&str]| match lane_options.iter().position(|o| o == opts) {
            Some(lane) => (lanes[lane], 0),
            None => (compared_report, defaults),
        };
        for (table, rows) in e.variant_tables.iter().zip(&mut varied) {
            let table_published = published::table(e.paper, table.name);
            for (_, opts) in table.variants {
                let (report, method) = lane_of(opts);
                rows.push(Row::new(scene_name, &reports[report].methods[method], &opts.join(" "), table_published));
            }
            if let Some((_, file)) = table.plotted.filter(|(scene, _)| *scene == scene_name) {
                let lines = table.variants.iter().map(|(label, opts)| {
                    let (report, method) = lane_of(opts);
                    FigureLine { label: label.to_string(), report, method }
                });
                let tag = format!("{scene_name}-{file}");
                figure_runs.push(FigureRun { tag, figure: table.name.to_string(), lines: lines.collect() });
            }
        }
        if let Some(figure) = e.shading_figure.as_ref().filter(|f| f.scene == scene_name) {
            for shading in Shading::ALL {
                let config = BenchConfig {
                    methods: figure.methods.iter().map(|m| m.to_string()).collect(),
                    gpu_model: (e.gpu_model)().with_shading(shading),
                    frames: if base.frames == ALL_FRAMES { figure.frames } else { base.frames },
                    ..config.clone()
                };
                // The model's own shading is the compared run's: sampled at
                // a frame rate, its first frames, not rendered again.
                let report = match shading {
                    Shading::Fixed if config.fps.is_some() => {
                        run.first_frames(figure.methods, config.frames).report(&config)
                    }
                    _ => {
                        progress.message(&format!("{scene_name} {}: {}, shading {shading}", config.size, figure.name));
                        run_scene(&scene, &config, progress)?.report(&config)
                    }
                };
                shaded.extend(report.methods.iter().map(|m| Row::new(scene_name, m, shading.paper_name(), None)));
                let lines = report.methods.iter().enumerate().map(|(method, m)| FigureLine {
                    label: m.name.clone(),
                    report: reports.len(),
                    method,
                });
                figure_runs.push(FigureRun {
                    tag: format!("{scene_name}-{}-{shading}", figure.file),
                    figure: format!("{}, {}", figure.name, shading.paper_name()),
                    lines: lines.collect(),
                });
                reports.push(report);
            }
        }
    }
    let mut tables = vec![Table::new(e.compared, published, compared)];
    let mut text = tables[0].render(e.title);
    let _ = writeln!(text, "ideal rows: {}", e.ideals);
    if e.inputs == Inputs::ChcTable1 {
        let _ = writeln!(
            text,
            "scene inputs: walkthroughs, field of view and view distance set so that VFC's and S&W's triangles \
             per frame come out near Table 1's (occlude_scenes::Inputs::ChcTable1)"
        );
    }
    text.push_str(&published::claims_text(e.paper, &tables[0].rows));
    for (table, rows) in e.variant_tables.iter().zip(varied) {
        let t = Table::new(table.name, published::table(e.paper, table.name), rows);
        text.push('\n');
        text.push_str(&t.render(e.title));
        for (label, opts) in table.variants.iter().filter(|(label, _)| !label.is_empty()) {
            let opts = if opts.is_empty() { "(the defaults)".to_string() } else { opts.join(" ") };
            let _ = writeln!(text, "  {label}: {} {opts}", e.varied);
        }
        tables.push(t);
    }
    if let Some(figure) = e.shading_figure.as_ref().filter(|_| !shaded.is_empty()) {
        let t = Table::new(figure.name, None, shaded);
        text.push('\n');
        text.push_str(&t.render(e.title));
        let _ = writeln!(
            text,
            "  DP, FIX, SH: drawn fragments shaded depth only, as the model has them, by a shader of 40 texture \
             lookups (--shading dp, fix, sh)"
        );
        tables.push(t);
    }
    let tables = PaperTables { paper: e.paper.to_string(), tables, reports };
    Ok(PaperResult { text, tables, gvq: None, compared_runs, figure_runs })
}

/// The IOC poster's scenes, as its tables name them.
const IOC_SCENES: [(&str, &str); 3] = [("rooms", "RM"), ("downtown", "DT"), ("figures", "GF")];

/// The poster's Table 1 (GTX 1080 Ti, 1920x1080): per scene, ROC's and IOC's
/// occlusion test and occludee rendering, ms.
const IOC_TABLE_1: [[(f64, f64); 2]; 3] =
    [[(0.41, 0.40), (0.61, 0.40)], [(3.47, 3.50), (0.78, 3.58)], [(7.96, 7.81), (1.05, 8.04)]];

/// The poster's walkthroughs: "animated camera sequences of 12s durations"
/// (section 3).
const IOC_SECONDS: f32 = 12.0;

/// Frames of each IOC walkthrough: the first [`IOC_SECONDS`] at `base`'s
/// frame rate, unless `base` asks for a number of frames or spreads them
/// over the whole walkthrough.
fn ioc_frames(base: &BenchConfig) -> usize {
    match (base.frames, base.fps) {
        (ALL_FRAMES, Some(fps)) => (IOC_SECONDS * fps).round() as usize,
        (frames, _) => frames,
    }
}

/// `--paper ioc` (module documentation).
fn run_ioc(base: &BenchConfig, only: &[String], progress: &dyn Progress) -> Result<PaperResult> {
    let times = match base.backend {
        crate::config::BackendKind::Soft => format!("GPU model {}, times simulated", base.gpu_model.name),
        crate::config::BackendKind::Wgpu => "times measured".to_string(),
    };
    let mut table = format!(
        "IOC poster (BVH, one object per leaf, {times}) — Table 1: GPU time per frame, ms\n\
         scene          method  occlusion test  (poster)  occludee rendering  (poster)  test vs roc  (poster)\n"
    );
    let mut figure = String::from(
        "IOC poster — Figure 4: frame time per frame, ms (the poster's chart gives no figures)\n\
         ideal row: opt, the per-instance lower bound (the instances owning a pixel, sorted by material; \
         not the poster's)\n\
         scene          method  frame ms  speedup vs vfc  rendered triangles  missing px\n",
    );
    let mut reports = Vec::new();
    let scenes = IOC_SCENES.iter().zip(IOC_TABLE_1).filter(|((scene, _), _)| chosen(only, scene));
    for (&(scene_name, label), published) in scenes {
        let config = BenchConfig {
            scene: scene_name.into(),
            methods: ["vfc", "nocull", "roc", "ioc", "hiz", "opt"].map(String::from).to_vec(),
            frames: ioc_frames(base),
            hierarchy: HierarchyKind::Bvh,
            build: BuildOptions { leaf_size: 1, ..base.build },
            // The user's model (default `modern`): the poster's result hangs
            // on what a box costs, which a calibrated model measures.
            gpu_model: base.gpu_model.clone(),
            options: MethodOptions::default(),
            ..base.clone()
        };
        config.validate()?;
        let scene = occlude_scenes::generate(scene_name, config.size, config.seed)?;
        let report = run_labelled(&scene, &config, progress, "vfc, nocull, roc, ioc, hiz, opt")?;
        let method = |name: &str| report.methods.iter().find(|m| m.name == name);
        let roc_test = method("roc").map_or(0.0, |m| m.cull_ms_per_frame);
        let shown = format!("{scene_name} ({label})");
        // `hiz` (two-phase Hi-Z, not in the poster) beside ROC and IOC, with
        // no published figure.
        let rows = [("roc", Some(published[0])), ("ioc", Some(published[1])), ("hiz", None)];
        for (name, poster) in rows {
            let Some(m) = method(name) else { continue };
            let figure = |f: Option<f64>| f.map_or("-".to_string(), |f| format!("{f:.2}"));
            let (test, render) = (figure(poster.map(|p| p.0)), figure(poster.map(|p| p.1)));
            let ratio = if name == "roc" || roc_test == 0.0 {
                format!("{:>11}  {:>8}", "", "")
            } else {
                let posters = figure(poster.map(|p| p.0 / published[0].0));
                format!("{:>11.2}  {posters:>8}", m.cull_ms_per_frame / roc_test)
            };
            let _ = writeln!(
                table,
                "{shown:<14} {name:<6} {:>15.3}  {test:>8}  {:>18.3}  {render:>8}  {ratio}",
                m.cull_ms_per_frame, m.render_ms_per_frame,
            );
        }
        for m in &report.methods {
            let _ = writeln!(
                figure,
                "{shown:<14} {:<6} {:>9.3} {:>15.2} {:>19.0} {:>11}",
                m.name, m.mean_frame_ms, m.speedup_vs_vfc, m.triangles_per_frame, m.missing_pixels,
            );
        }
        reports.push(report);
    }
    // The poster's tables stay text: their published figures are GPU times
    // of parts of the frame, not the rows of [`Table`].
    let compared_runs = (0..reports.len()).collect();
    let tables = PaperTables { paper: "ioc".into(), tables: Vec::new(), reports };
    Ok(PaperResult { text: format!("{table}\n{figure}"), tables, gvq: None, compared_runs, figure_runs: Vec::new() })
}

fn run_labelled(scene: &Scene, config: &BenchConfig, progress: &dyn Progress, label: &str) -> Result<BenchReport> {
    progress.message(&format!("{} {}: {label}", config.scene, config.size));
    Ok(run_scene(scene, config, progress)?.report(config))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chc_tables_set_every_row_beside_the_papers_and_write_its_json_shape() {
        let base = BenchConfig { frames: 4, resolution: (96, 64), ..BenchConfig::default() };
        let result = run("chc", &base, &[], &()).unwrap();
        let [t1, t2, t3] = &result.tables.tables[..] else { panic!("three tables: {:?}", result.tables.tables) };
        assert_eq!((t1.name.as_str(), t1.rows.len()), ("Table 1", 15), "3 scenes x vfc, sw, chc, ideal, opt");
        assert_eq!((t2.name.as_str(), t2.rows.len()), ("Table 2", 9), "3 scenes x the paper's 3 rows");
        assert_eq!((t3.name.as_str(), t3.rows.len()), ("section 5.3", 12), "3 scenes x spec off and 3 constants");
        assert!(t3.rows.iter().all(|r| r.missing_pixels == 0), "speculation draws more, never less");
        assert!(result.text.contains("scene inputs: walkthroughs, field of view"), "{}", result.text);
        // Each of the paper's rows has its figure beside ours; opt has none.
        for r in &t1.rows {
            assert_eq!(r.published_frame_ms.is_some(), r.method != "opt", "{r:?}");
            assert!(r.frame_ms > 0.0 && r.speedup > 0.0 && r.speedup_of_means > 0.0, "{r:?}");
            assert_eq!(r.missing_pixels, 0, "{r:?}");
        }
        fn row<'t>(t: &'t Table, scene: &str, method: &str) -> Option<&'t Row> {
            t.rows.iter().find(|r| r.scene == scene && r.method == method)
        }
        // The ideal is S&W's visible set without queries: S&W's triangles.
        for scene in CHC_SCENES {
            let (sw, ideal) = (row(t1, scene, "sw").unwrap(), row(t1, scene, IDEAL).unwrap());
            assert_eq!(ideal.triangles, sw.triangles, "{scene}");
            assert_eq!(ideal.queries, 0.0, "{scene}");
        }
        assert_eq!(row(t1, "teapots", "chc").unwrap().published_speedup, Some(4.6));
        let combined = t2.rows.iter().find(|r| r.scene == "city" && r.options == "chc.tav=2 chc.nvp=25").unwrap();
        assert_eq!((combined.published_queries, combined.published_frame_ms), (Some(181.0), Some(6.11)));
        // The defaults' row of Table 2 is Table 1's CHC, not a second run.
        assert_eq!(t2.rows[0].frame_ms, row(t1, "teapots", "chc").unwrap().frame_ms);
        assert_eq!(result.tables.reports.len(), 3 * 6);
        // The plotted runs are each scene's run of Table 1's methods, not a lane.
        assert_eq!(result.compared_runs, [0, 6, 12]);
        for (&i, scene) in result.compared_runs.iter().zip(CHC_SCENES) {
            let report = &result.tables.reports[i];
            let names: Vec<&str> = report.methods.iter().map(|m| m.name.as_str()).collect();
            assert_eq!((report.scene.as_str(), &names[..]), (*scene, CHC.methods));
        }
        for t in [t1, t2] {
            assert!(t.ordering_agrees.flatten().is_some(), "{} has published figures to order", t.name);
            assert!(t.source.as_deref().is_some_and(|s| s.contains(&t.name)), "{:?}", t.source);
        }
        // A scene run apart gives the whole run's rows for it.
        let plant = run("chc", &base, &["plant".into()], &()).unwrap();
        assert_eq!((plant.tables.reports.len(), &plant.compared_runs[..]), (6, &[0][..]));
        for (alone, whole) in plant.tables.tables.iter().zip(&result.tables.tables) {
            let whole: Vec<&Row> = whole.rows.iter().filter(|r| r.scene == "plant").collect();
            assert_eq!(format!("{:?}", alone.rows.iter().collect::<Vec<_>>()), format!("{whole:?}"), "{}", alone.name);
        }
        assert!(result.text.contains("310.42") && result.text.contains("order of methods"), "{}", result.text);

        let v = serde_json::to_value(&result.tables).unwrap();
        assert_eq!(v["paper"], "chc");
        assert_eq!(v["tables"][0]["name"], "Table 1");
        assert!(v["tables"][1]["ordering_agrees"].is_boolean());
        let first = &v["tables"][0]["rows"][0];
        for key in ["scene", "method", "frame_ms", "published_frame_ms", "queries", "published_queries", "speedup"] {
            assert!(first.get(key).is_some(), "row lacks {key}: {first}");
        }
        assert_eq!((first["scene"].as_str(), first["method"].as_str()), (Some("teapots"), Some("vfc")));
        assert_eq!(first["published_frame_ms"], 310.42);
    }

    /// Figure 9's FIX run, at a frame rate, is the compared run's frames
    /// (`BenchRun::first_frames`, tested with fewer frames than the run's):
    /// its rows are the compared run's.
    #[test]
    fn figure_9_takes_its_fix_run_from_the_compared_run() {
        let experiment = Experiment { variant_tables: &[], ..CHCPP };
        let base = BenchConfig { frames: 4, fps: Some(30.0), resolution: (96, 64), ..BenchConfig::default() };
        let result = run_experiment(&experiment, &base, &["plant".to_string()], &()).unwrap();
        let compared = &result.tables.reports[result.compared_runs[0]];
        let fix = result.figure_runs.iter().find(|f| f.tag == "plant-fig9-fix").unwrap();
        let fix = &result.tables.reports[fix.lines[0].report];
        assert_eq!((fix.frames, fix.gpu_model.as_str(), fix.methods.len()), (4, "modern", 3));
        for m in &fix.methods {
            let whole = compared.methods.iter().find(|c| c.name == m.name).unwrap();
            let frame_ms = |f: &[occlude_core::FrameStats]| f.iter().map(|f| f.frame_ms).collect::<Vec<_>>();
            assert_eq!(frame_ms(&m.per_frame), frame_ms(&whole.per_frame), "{}", m.name);
            assert_eq!(
                (m.queries_per_frame, m.triangles_per_frame),
                (whole.queries_per_frame, whole.triangles_per_frame)
            );
        }
    }

    /// `--paper chcpp`: NOHC and NOHC-OPT beside CHC and CHC++, the
    /// ablation and Figure 8's optimisations added one at a time (its last
    /// row CHC++ itself), the claims of the paper's text beside our ratios.
    #[test]
    fn the_chcpp_tables_compare_nohc_and_add_the_optimisations_one_at_a_time() {
        let base = BenchConfig { frames: 3, resolution: (96, 64), ..BenchConfig::default() };
        let result = run("chcpp", &base, &[], &()).unwrap();
        let names: Vec<&str> = result.tables.tables.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, ["methods compared", "ablation", "Figure 8", "Figure 9"]);
        let [compared, ablation, figure8, figure9] = &result.tables.tables[..] else { unreachable!() };
        assert_eq!(compared.rows.len(), 3 * 8, "3 scenes x vfc, sw, chc, chcpp, nohc, nohc-opt, ideal-sorted, opt");
        // The paper's OPT: S&W's visible set, no query, so no state change,
        // and no more material switches than the materials it draws.
        for scene in CHC_SCENES {
            let row = |m: &str| compared.rows.iter().find(|r| r.scene == *scene && r.method == m).unwrap();
            let (sw, opt) = (row("sw"), row(IDEAL_SORTED));
            assert_eq!((opt.triangles, opt.queries, opt.state_changes), (sw.triangles, 0.0, 0.0), "{scene}");
            assert!(opt.material_switches <= sw.material_switches + sw.state_changes, "{scene}: {opt:?}");
            assert_eq!(row("vfc").state_changes, 0.0, "{scene}");
            assert!(row("chcpp").state_changes > 0.0, "{scene}");
        }
        assert!(result.text.contains("ideal rows: ideal-sorted: the CHC++ paper's OPT"), "{}", result.text);
        assert_eq!(ablation.rows.len(), 3 * 9);
        assert_eq!(figure8.rows.len(), 3 * 5);
        for t in [compared, ablation, figure8, figure9] {
            assert!(t.rows.iter().all(|r| r.missing_pixels == 0 && r.frame_ms > 0.0), "{}", t.name);
        }
        // Figure 9: the plant under each shading, DP and SH a run of their
        // own with the model's fragment cost changed, FIX the compared
        // run's frames; shading never makes a frame cheaper.
        assert_eq!(figure9.rows.len(), 3 * 3);
        assert!(figure9.rows.iter().all(|r| r.scene == "plant"));
        for method in ["vfc", "chcpp", "nohc"] {
            let ms: Vec<f64> = ["DP", "FIX", "SH"]
                .iter()
                .map(|s| figure9.rows.iter().find(|r| r.method == method && r.options == *s).unwrap().frame_ms)
                .collect();
            assert!(ms[0] <= ms[1] && ms[1] <= ms[2], "{method}: {ms:?}");
        }
        let models: Vec<&str> = result.tables.reports.iter().rev().take(3).map(|r| r.gpu_model.as_str()).collect();
        assert_eq!(models, ["modern+sh", "modern", "modern+dp"]);
        let tags: Vec<&str> = result.figure_runs.iter().map(|f| f.tag.as_str()).collect();
        assert_eq!(tags, ["plant-fig8", "plant-fig9-dp", "plant-fig9-fix", "plant-fig9-sh"]);
        let last = result.figure_runs.last().unwrap();
        assert_eq!((last.figure.as_str(), last.lines[0].report), ("Figure 9, SH", result.tables.reports.len() - 1));
        // Figure 8 starts from CHC (every optimisation off) and ends at
        // CHC++, the compared table's row; its rows cite the figure's page.
        assert!(figure8.rows[0].options.contains("chcpp.b=1") && figure8.rows[0].options.contains("chcpp.tight=off"));
        let chcpp = compared.rows.iter().find(|r| r.scene == "teapots" && r.method == "chcpp").unwrap();
        assert_eq!(figure8.rows[4].options, "");
        assert_eq!(figure8.rows[4].frame_ms, chcpp.frame_ms);
        assert!(figure8.source.as_deref().is_some_and(|s| s.contains("Figure 8 (p. 229)")));
        // The variant shared by the ablation and Figure 8 runs once.
        let lanes = ablation.rows.iter().chain(&figure8.rows).filter(|r| r.scene == "city" && !r.options.is_empty());
        let distinct: std::collections::HashSet<&str> = lanes.map(|r| r.options.as_str()).collect();
        assert_eq!(result.tables.reports.len(), 3 * (1 + distinct.len()) + 3);
        // Figure 8's plot: the plant's five lanes, each named by its label,
        // the last one the compared run's CHC++.
        let fig8 = result.figure_report(&result.figure_runs[0]).unwrap();
        let lines: Vec<&str> = fig8.methods.iter().map(|m| m.name.as_str()).collect();
        let labels: Vec<&str> = FIGURE_8.variants.iter().map(|(label, _)| *label).collect();
        assert_eq!((fig8.scene.as_str(), result.figure_runs[0].figure.as_str(), lines), ("plant", "Figure 8", labels));
        let plant = &result.tables.reports[result.compared_runs[2]];
        let chcpp = plant.methods.iter().find(|m| m.name == "chcpp").unwrap();
        assert_eq!(fig8.methods[4].per_frame, chcpp.per_frame);
        assert_ne!(fig8.methods[0].per_frame, chcpp.per_frame);
        assert!(
            result.text.contains("nohc / chcpp frame time") && result.text.contains("(paper 1.5)"),
            "{}",
            result.text
        );
        assert!(result.text.contains("CHC+B+R: chcpp chcpp.tight=off chcpp.multiquery=off"), "{}", result.text);
        let v = serde_json::to_value(&result.tables).unwrap();
        assert_eq!((v["paper"].as_str(), v["tables"][2]["name"].as_str()), (Some("chcpp"), Some("Figure 8")));
    }

    #[test]
    fn ioc_runs_the_posters_twelve_seconds_unless_told_otherwise() {
        let paper = BenchConfig { frames: ALL_FRAMES, fps: Some(30.0), ..BenchConfig::default() };
        assert_eq!(ioc_frames(&paper), 360);
        assert_eq!(ioc_frames(&BenchConfig { fps: Some(2.0), ..paper.clone() }), 24);
        assert_eq!(ioc_frames(&BenchConfig { frames: 60, ..paper.clone() }), 60);
        assert_eq!(ioc_frames(&BenchConfig { fps: None, ..paper }), ALL_FRAMES);
    }

    #[test]
    fn the_ioc_tables_set_every_scene_beside_the_posters_figures() {
        let base = BenchConfig { frames: 3, resolution: (96, 64), ..BenchConfig::default() };
        let result = run("ioc", &base, &[], &()).unwrap();
        assert_eq!(result.tables.reports.len(), 3);
        assert_eq!(result.compared_runs, [0, 1, 2]);
        for (report, (scene, label)) in result.tables.reports.iter().zip(IOC_SCENES) {
            assert_eq!(report.scene, scene);
            assert_eq!(report.hierarchy, "bvh");
            // One object per leaf: a binary tree of 2n - 1 nodes.
            let s = &report.scene_stats;
            assert_eq!(s.nodes, 2 * s.instances - 1, "{scene}: {s:?}");
            for m in &report.methods {
                assert_eq!(m.missing_pixels, 0, "{scene}/{}", m.name);
            }
            for method in ["roc", "ioc", "hiz"] {
                let row = format!("{scene} ({label})");
                let lines = result.text.lines().filter(|l| l.starts_with(&row) && l.contains(method)).count();
                assert_eq!(lines, 2, "{scene}/{method}: a Table 1 row and a Figure 4 row\n{}", result.text);
            }
            // NOCULL draws every instance, so at least what `vfc` draws.
            let triangles = |name: &str| report.methods.iter().find(|m| m.name == name).unwrap().triangles_per_frame;
            assert!(triangles("nocull") >= triangles("vfc"), "{scene}");
            assert_eq!(
                result
                    .text
                    .lines()
                    .filter(|l| l.starts_with(&format!("{scene} ({label})")) && l.contains("nocull"))
                    .count(),
                1
            );
        }
        // The poster's figures stand beside ours: DT's test times and ratio.
        assert!(
            result.text.contains("3.47") && result.text.contains("0.78") && result.text.contains("0.22"),
            "{}",
            result.text
        );
    }
}
