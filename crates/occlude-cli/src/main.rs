//! The `occlude` command line: `bench` compares culling methods on a scene
//! and walkthrough, `view` flies through it in a window, `report` turns
//! bench JSON into an HTML (and Markdown) report, `scenes` lists the
//! procedural scenes.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use occlude_bench::config::{
    parse_frames, BackendKind, ALL_FRAMES, DEFAULT_FPS, DEFAULT_FRAMES, DEFAULT_METHODS, DEFAULT_RESOLUTION,
};
use occlude_bench::limits::{parse_fps, parse_frame_count, parse_repeats, parse_resolution, parse_threads};
use occlude_bench::paper::PAPERS;
use occlude_bench::{output, paper, table, BenchConfig, Progress};
use occlude_cli::bench::plot::{self, PlotKind};
use occlude_cli::bench::{dump, paper_figures};
use occlude_cli::output_path::check_distinct;
use occlude_cli::output_path::parse_output_path;
use occlude_cli::stdout::print;
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::{MethodOptions, METHOD_NAMES};
use occlude_core::{HierarchyKind, UpdatePolicy};
use occlude_scenes::import::SceneSource;
use occlude_scenes::{AutoPath, ImportOptions, Size};
use occlude_soft::{GpuModel, Shading};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "occlude", version, about = "Occlusion-culling methods compared on the same scene and camera path")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run culling methods over a walkthrough and print the comparison table.
    Bench(Box<BenchArgs>),
    /// Write a self-contained HTML report (tables and plots) of bench JSON files.
    Report(ReportArgs),
    /// Measure this GPU's costs through the wgpu backend and write a GPU model
    /// (TOML) for the soft backend's simulated clock.
    Calibrate(CalibrateArgs),
    /// Fly through a scene in a window with any method on the GPU, its
    /// statistics shown, and its query boxes on key V (CHC paper, Figure 4).
    View(Box<ViewArgs>),
    /// Measure the soft depth rasterizer on the field's workloads (fill rate of
    /// random right triangles, occlusion queries) and print MTris/s, GPix/s and
    /// queries/s.
    RasterBench(occlude_cli::raster_bench::RasterBenchArgs),
    /// List the procedural scenes with triangle, instance and node counts.
    Scenes {
        // Sizes to list.
        #[arg(long, default_value = "all", help = format!("Sizes to list: {}", one_of(&[&size_names()[..], &["all"]].concat())))]
        size: String,
        /// Generator seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

/// The scene, hierarchy and method parameters: options `bench` and `view`
/// share.
#[derive(clap::Args)]
struct SceneArgs {
    /// Scene: teapots, city, plant, figures, rooms, downtown or swarm, or a model file (.gltf, .glb, .obj;
    /// y-up, metres) [default: city]. With bench --paper: some of the paper's scenes, comma-separated
    /// [default: all of them].
    #[arg(long)]
    scene: Option<String>,
    /// Split imported meshes of more triangles than this into several objects
    /// (0: never).
    #[arg(long, default_value_t = ImportOptions::DEFAULT_SPLIT_TRIANGLES)]
    split_triangles: usize,
    /// Walkthrough of an imported model: orbit (around it) or walk (at eye
    /// height through its free space).
    #[arg(long, default_value = "orbit")]
    auto_path: AutoPath,
    /// Replay this walkthrough instead of the scene's: a JSON file
    /// {"keyframes":[{"time":0,"position":[x,y,z],"target":[x,y,z],"fov_y_deg":60}, ...]}.
    #[arg(long, value_name = "FILE")]
    camera_path: Option<PathBuf>,
    // Scene size.
    #[arg(long, help = format!("Scene size: {} [default: small; paper with bench --paper]", one_of(&size_names())))]
    size: Option<String>,
    /// Seed of the procedural generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Hierarchy: bvh or kdtree.
    #[arg(long, default_value = "bvh")]
    hierarchy: HierarchyKind,
    /// Most instances per hierarchy leaf.
    #[arg(long, default_value_t = BuildOptions::default().leaf_size)]
    leaf_size: usize,
    /// Method parameter, method.key=value (repeatable), e.g. chc.tav=2.
    #[arg(long = "method-opt", value_name = "METHOD.KEY=VALUE")]
    method_opt: Vec<String>,
    /// Share of the scene's instances that move, 0 to 1: each chosen one
    /// slides back and forth, one in eight also leaves and comes back
    /// (deterministic from --seed). A scene's own motion always plays (a
    /// glTF model's node animations, looped; the vehicles, people and doors
    /// of traffic and crowd); this then moves a share of the instances it
    /// does not.
    #[arg(long, value_name = "FRACTION", default_value_t = 0.0)]
    motion: f64,
    /// A moving scene's hierarchy is rebuilt when refits have made its SAH
    /// cost this many times its cost when built (1 or more; inf: never).
    #[arg(long, value_name = "RATIO", default_value_t = UpdatePolicy::default().max_cost_ratio)]
    rebuild_ratio: f32,
}

impl SceneArgs {
    /// The files these options read (the model, the camera path) and the
    /// `--gpu-model`, when given and not a preset, for
    /// [`check_distinct`].
    fn inputs<'a>(&'a self, gpu_model: Option<&'a str>) -> [(&'static str, Option<&'a Path>); 3] {
        let file = |name: &'a str| Some(Path::new(name)).filter(|p| p.is_file());
        [
            ("--scene", self.scene.as_deref().and_then(file)),
            ("--camera-path", self.camera_path.as_deref()),
            ("--gpu-model", gpu_model.and_then(file)),
        ]
    }

    /// A configuration with these settings checked and every other one at
    /// its default; a bad value is the user's (exit code 2). `--scene` is
    /// not read with `--paper` (`paper_scenes`).
    fn config(&self, paper: bool) -> Result<BenchConfig, Failure> {
        let usage = Failure::Usage;
        let scene = match &self.scene {
            Some(scene) if !paper => scene.clone(),
            _ => BenchConfig::default().scene,
        };
        SceneSource::resolve(&scene).map_err(|e| usage(e.into()))?;
        Ok(BenchConfig {
            scene,
            size: self.size.as_deref().unwrap_or("small").parse::<Size>().map_err(|e| usage(e.into()))?,
            seed: self.seed,
            hierarchy: self.hierarchy,
            build: BuildOptions { leaf_size: self.leaf_size, ..BuildOptions::default() },
            options: MethodOptions::parse(&self.method_opt).map_err(|e| usage(e.into()))?,
            import: ImportOptions { split_triangles: self.split_triangles, auto_path: self.auto_path },
            camera_path: self
                .camera_path
                .as_deref()
                .map(occlude_bench::camera_path::load)
                .transpose()
                .map_err(|e| usage(e.into()))?,
            motion: self.motion,
            update_policy: UpdatePolicy { max_cost_ratio: self.rebuild_ratio },
            ..BenchConfig::default()
        })
    }
}

#[derive(clap::Args)]
struct BenchArgs {
    #[command(flatten)]
    scene: SceneArgs,
    // Comma-separated methods, in table order.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_METHODS.map(String::from),
          help = format!("Comma-separated methods, in table order, of {}", METHOD_NAMES.join(", ")))]
    methods: Vec<String>,
    /// Frames: the first N of the walkthrough sampled at --fps, or all
    /// [default: 300, the first 10 s at 30 fps; with --paper: all].
    #[arg(long, value_name = "N|all", value_parser = parse_frames)]
    frames: Option<usize>,
    /// Frame rate the walkthrough is sampled at, frames per second of
    /// walkthrough time.
    #[arg(long, default_value_t = DEFAULT_FPS, value_parser = parse_fps)]
    fps: f32,
    /// Image size, WIDTHxHEIGHT [default: 1024x768; 800x600 with --paper
    /// om, the paper's].
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Backend: soft (exact CPU rasterizer, simulated GPU clock) or wgpu (a
    /// real GPU; times measured).
    #[arg(long, default_value = "soft")]
    backend: BackendKind,
    /// How occlusion queries are counted: hardware (one occlusion query
    /// each) or hib (the queries of a submission counted in one pass with
    /// atomics, as the hierarchical item buffer counts; exact on any GPU).
    #[arg(long, default_value = "hardware")]
    queries: occlude_core::QueryMode,
    /// Simulated GPU: a preset (gpu-2004, modern) or a TOML file.
    #[arg(long, default_value = "modern")]
    gpu_model: String,
    /// How the simulated GPU shades drawn fragments, as the CHC++ paper's
    /// Figure 9 tests: dp (depth only), fix (the model as it is), sh (a
    /// shader of 40 texture lookups). Soft backend only.
    #[arg(long, default_value = "fix")]
    shading: Shading,
    /// Write the full report as JSON.
    #[arg(long, value_parser = parse_output_path)]
    json: Option<PathBuf>,
    /// Write one CSV row per method and frame (with --paper, of every run
    /// behind the tables, each row led by its run, scene and parameters).
    #[arg(long, value_parser = parse_output_path)]
    csv: Option<PathBuf>,
    /// Plot frame time over the walkthrough, one line per method (.svg or
    /// .png). With --paper, one plot per scene, the scene's name put before
    /// the extension (chc.svg: chc-teapots.svg, chc-city.svg, chc-plant.svg),
    /// titled with the paper's figure.
    #[arg(long, value_parser = parse_output_path)]
    plot: Option<PathBuf>,
    /// Plot queries, state changes and material switches per frame (.svg or .png; with --paper,
    /// one per scene, named as --plot's).
    #[arg(long, value_parser = parse_output_path)]
    plot_queries: Option<PathBuf>,
    // Run a paper's experiments instead.
    #[arg(long, help = format!("Run a paper's experiments instead (scenes, methods, hierarchy and GPU \
        model as in the paper, except ioc, which takes --gpu-model; size, frames, resolution, seed and \
        backend from the other options): {}", one_of(&PAPERS)))]
    paper: Option<String>,
    /// Worker threads for the rasterizer, 1 to 256 (default: all cores).
    #[arg(long, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Render a frame's methods one after another on the soft backend
    /// instead of side by side on the thread pool: each method's wall ms is
    /// then its own, not shared with the others running beside it (the
    /// simulated figures are the same either way).
    #[arg(long)]
    serial_lanes: bool,
    /// Write PNGs of what frame K (0-based) decided, for each method that
    /// records it (om): its occupancy map and its nodes' screen rectangles.
    #[arg(long, value_name = "K")]
    dump_frame: Option<usize>,
    /// Folder for the --dump-frame PNGs (created if missing).
    #[arg(long, value_name = "DIR", default_value = ".")]
    dump_dir: PathBuf,
}

#[derive(clap::Args)]
struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    // The method shown first.
    #[arg(long, default_value = occlude_cli::view::DEFAULT_METHOD, help = format!(
        "The method shown first: {} (keys 1-9 and 0 switch to them in that order, M to the next)",
        one_of(&METHOD_NAMES)))]
    method: String,
    /// Window size, WIDTHxHEIGHT (the screenshot's size).
    #[arg(long, default_value = "1024x768", value_parser = parse_resolution)]
    resolution: (u32, u32),
    /// Play the walkthrough from the start (key P).
    #[arg(long)]
    play: bool,
    /// Show the query boxes, green visible and red occluded, from the first
    /// frame (key V).
    #[arg(long)]
    figure4: bool,
    /// Show the box tests' boxes coloured by the depth-pyramid level each
    /// was tested at (hiz; hidden ones filled), from the first frame (key Z).
    #[arg(long)]
    pyramid_levels: bool,
    /// Render --frames frames (along the walkthrough with --play, else of the
    /// first view), save the last as this PNG and exit.
    #[arg(long, value_name = "FILE.png", value_parser = parse_output_path)]
    screenshot: Option<PathBuf>,
    /// Frames rendered before --screenshot.
    #[arg(long, default_value_t = 60, value_parser = parse_frame_count)]
    frames: usize,
    /// Where key R writes the recorded camera path (JSON for
    /// `bench --camera-path`).
    #[arg(long, value_name = "FILE", default_value = occlude_cli::view::DEFAULT_RECORD_FILE, value_parser = parse_output_path)]
    record: PathBuf,
}

#[derive(clap::Args)]
struct CalibrateArgs {
    /// Backend to measure: only wgpu (a real GPU) can be measured.
    #[arg(long, default_value = "wgpu")]
    backend: BackendKind,
    /// The GPU model file to write (load it with `bench --gpu-model FILE`).
    #[arg(long, default_value = "calibrated.toml", value_parser = parse_output_path)]
    out: PathBuf,
    /// Image size of the measurements and of the check.
    #[arg(long, default_value = "1024x768", value_parser = parse_resolution)]
    resolution: (u32, u32),
    /// Repeats of each measurement (the median counts).
    #[arg(long, default_value_t = 5, value_parser = parse_repeats)]
    repeats: usize,
    /// Scene of the check: every method on the GPU and on the soft backend
    /// with the measured model, mean frame times compared.
    #[arg(long, default_value = "city")]
    check_scene: String,
    /// Size of the check's scene.
    #[arg(long, default_value = "small")]
    check_size: String,
    /// Frames of the check.
    #[arg(long, default_value_t = 60, value_parser = parse_frame_count)]
    check_frames: usize,
    /// Methods of the check.
    #[arg(long, value_delimiter = ',', default_value = "vfc,sw,chc,chcpp,om,opt")]
    check_methods: Vec<String>,
    /// Skip the check.
    #[arg(long)]
    no_check: bool,
}

#[derive(clap::Args)]
struct ReportArgs {
    /// JSON files of `occlude bench --json`: one report each, or an array of
    /// them (`--paper`).
    #[arg(required = true, value_name = "FILE.json")]
    files: Vec<PathBuf>,
    /// The HTML file to write.
    #[arg(long, value_name = "FILE.html", value_parser = parse_output_path)]
    out: PathBuf,
    /// Also write the report as Markdown, its plots as SVG files beside it.
    #[arg(long, value_name = "FILE.md", value_parser = parse_output_path)]
    markdown: Option<PathBuf>,
}

/// Why a command failed: what the user asked for is wrong (exit code 2), or
/// doing it failed (exit code 1).
enum Failure {
    Usage(anyhow::Error),
    Run(anyhow::Error),
}

/// A failed run is the user's input when a model file could not be imported
/// (the scene is loaded in the run, not in `configure`, so as to read a large
/// model once), its walkthrough cannot be run as asked (too many frames, a
/// camera on its target), `--backend wgpu`, `view` or `raster-bench --gpu required`
/// found no GPU adapter that can run the backend (or none with what a
/// GPU-driven method needs), or `view` found no display: exit code 2 like
/// any bad argument; anything else exit code 1. The harness's errors say
/// which they are by their kind ([`occlude_bench::Error`]).
fn run_failure(e: anyhow::Error) -> Failure {
    use occlude_bench::Error as Bench;
    let gpu_missing = |e: &occlude_wgpu::GpuError| {
        matches!(e, occlude_wgpu::GpuError::NoAdapter(_) | occlude_wgpu::GpuError::Unsuitable(_))
    };
    let no_adapter = |c: &(dyn std::error::Error + 'static)| {
        c.downcast_ref::<occlude_wgpu::GpuError>().is_some_and(gpu_missing)
            || matches!(bench(c), Some(Bench::Gpu(e)) if gpu_missing(e))
    };
    let input = |c: &(dyn std::error::Error + 'static)| {
        no_adapter(c)
            || c.is::<occlude_core::GpuCullingUnsupported>()
            || c.is::<occlude_core::methods::Unsupported>()
            || c.is::<occlude_cli::view::ViewError>()
            || match bench(c) {
                Some(Bench::Load(e)) => e.is_input_error(),
                Some(Bench::GpuCulling(_) | Bench::Unsupported(_) | Bench::Walkthrough(_)) => true,
                _ => false,
            }
    };
    if e.chain().any(no_adapter) {
        Failure::Usage(e.context("no GPU to run on: `occlude bench --backend soft` (the default) needs none"))
    } else if e.chain().any(input) {
        Failure::Usage(e)
    } else {
        Failure::Run(e)
    }
}

/// `c` as the harness's error, under any context it gave it.
fn bench<'a>(c: &'a (dyn std::error::Error + 'static)) -> Option<&'a occlude_bench::Error> {
    c.downcast_ref::<occlude_bench::Error>().map(occlude_bench::Error::innermost)
}

fn configure(args: &BenchArgs) -> Result<BenchConfig, Failure> {
    let usage = Failure::Usage;
    let config = BenchConfig {
        methods: args.methods.iter().map(|m| m.trim().to_string()).collect(),
        frames: args.frames.unwrap_or(if args.paper.is_some() { ALL_FRAMES } else { DEFAULT_FRAMES }),
        fps: Some(args.fps),
        resolution: args
            .resolution
            .or(args.paper.as_deref().and_then(paper::default_resolution))
            .unwrap_or(DEFAULT_RESOLUTION),
        backend: args.backend,
        queries: args.queries,
        gpu_model: GpuModel::load(&args.gpu_model).map_err(|e| usage(e.into()))?.with_shading(args.shading),
        dump_frame: args.dump_frame,
        parallel_lanes: !args.serial_lanes,
        ..args.scene.config(args.paper.is_some())?
    };
    let config = match (&args.paper, &args.scene.size) {
        (Some(_), None) => BenchConfig { size: paper::DEFAULT_SIZE, ..config },
        _ => config,
    };
    config.validate().map_err(|e| usage(e.into()))?;
    if args.shading != Shading::Fixed && (args.backend == BackendKind::Wgpu || args.paper.is_some()) {
        return Err(usage(anyhow::anyhow!(
            "--shading sets the soft backend's simulated fragment cost in a plain bench run (not with \
             --backend wgpu, which shades for real, nor with --paper, which uses the paper's GPU model)"
        )));
    }
    if let Some(paper) = &args.paper {
        if args.dump_frame.is_some() {
            return Err(usage(anyhow::anyhow!("--dump-frame cannot be combined with --paper")));
        }
        if !PAPERS.contains(&paper.as_str()) {
            return Err(usage(anyhow::anyhow!("unknown paper '{paper}': expected one of {}", PAPERS.join(", "))));
        }
        if args.scene.scene.is_some() {
            paper::check_scenes(paper, &paper_scenes(args)).map_err(|e| usage(e.into()))?;
        }
        let per_frame = [(&args.plot, "--plot"), (&args.plot_queries, "--plot-queries"), (&args.csv, "--csv")];
        for (_, option) in per_frame.iter().filter(|(path, _)| path.is_some()) {
            paper::check_walkthroughs(paper, option).map_err(|e| usage(e.into()))?;
        }
    }
    for path in args.plot.iter().chain(&args.plot_queries) {
        plot::plot_format(path).map_err(usage)?;
    }
    if args.dump_frame.is_some() && args.dump_dir.exists() && !args.dump_dir.is_dir() {
        return Err(usage(anyhow::anyhow!("--dump-dir {} is a file, not a folder", args.dump_dir.display())));
    }
    let outputs = [
        ("--json", args.json.as_deref()),
        ("--csv", args.csv.as_deref()),
        ("--plot", args.plot.as_deref()),
        ("--plot-queries", args.plot_queries.as_deref()),
    ];
    check_distinct(&outputs, &args.scene.inputs(Some(&args.gpu_model))).map_err(|e| usage(anyhow::anyhow!(e)))?;
    Ok(config)
}

/// The scenes `--scene` picks from a paper's (empty: all of them).
fn paper_scenes(args: &BenchArgs) -> Vec<String> {
    let list = args.scene.scene.as_deref().unwrap_or_default();
    list.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect()
}

/// `occlude bench`, on a pool of `--threads` threads (default: rayon's), whose
/// threads run the frames and the rasterizer (`occlude_bench::runner::run_scene`).
fn run_bench(args: &BenchArgs, config: &BenchConfig) -> Result<()> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the thread pool")?;
    pool.install(|| bench_on_pool(args, config))
}

fn bench_on_pool(args: &BenchArgs, config: &BenchConfig) -> Result<()> {
    let progress = occlude_cli::progress::bar(0, "frames");
    if let Some(paper) = &args.paper {
        let result = paper::run(paper, config, &paper_scenes(args), &progress)?;
        progress.finish_and_clear();
        occlude_bench::figures::check_output(&result.tables.reports)?;
        if let Some(path) = &args.json {
            match &result.gvq {
                Some(gvq) => output::write_json(gvq, path)?,
                None => output::write_json(&result.tables, path)?,
            }
            eprintln!("wrote {}", path.display());
        }
        if let Some(path) = &args.csv {
            output::write_paper_csv(&result.tables.reports, path)?;
            eprintln!("wrote {}", path.display());
        }
        for (path, kind) in plots(args) {
            for written in paper_figures::write(&result, kind, path)? {
                eprintln!("wrote {}", written.display());
            }
        }
        return print(&result.text);
    }
    progress.message(&format!("{} {}: {}", config.scene, config.size, config.methods.join(", ")));
    let run = occlude_bench::run(config, &progress)?;
    progress.finish_and_clear();
    let report = run.report(config);
    occlude_bench::figures::check_output(&report)?;
    if let Some(path) = &args.json {
        output::write_json(&report, path)?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(path) = &args.csv {
        output::write_csv(&report, path)?;
        eprintln!("wrote {}", path.display());
    }
    for (path, kind) in plots(args) {
        plot::write_plot(&report, kind, path)?;
        eprintln!("wrote {}", path.display());
    }
    if config.dump_frame.is_some() && run.dumps.is_empty() {
        eprintln!("note: --dump-frame wrote nothing: none of the methods records its decisions (om does)");
    }
    for dump in &run.dumps {
        for path in dump::write(dump, &args.dump_dir)? {
            eprintln!("wrote {}", path.display());
        }
    }
    print(&table::render(&report))?;
    match &run.aborted {
        Some(why) => anyhow::bail!(
            "the run stopped early ({why}); the {} frames every method finished are reported above",
            run.scene.frames
        ),
        None => Ok(()),
    }
}

/// The plots asked for: `--plot`'s frame times, `--plot-queries`' queries
/// and state changes.
fn plots(args: &BenchArgs) -> impl Iterator<Item = (&PathBuf, PlotKind)> {
    let frame_time = args.plot.as_ref().map(|p| (p, PlotKind::FrameTime));
    frame_time.into_iter().chain(args.plot_queries.as_ref().map(|p| (p, PlotKind::QueriesAndStateChanges)))
}

/// `occlude calibrate`: a backend other than wgpu, a bad check scene or
/// method, or no adapter is the user's (exit code 2).
fn calibrate(args: &CalibrateArgs) -> Result<(), Failure> {
    let usage = Failure::Usage;
    if args.backend != BackendKind::Wgpu {
        return Err(usage(anyhow::anyhow!(
            "calibrate measures a real GPU: use --backend wgpu (the soft backend's costs are the model itself)"
        )));
    }
    let check_scene = Path::new(&args.check_scene);
    let check_input = (!args.no_check && check_scene.is_file()).then_some(check_scene);
    check_distinct(&[("--out", Some(&args.out))], &[("--check-scene", check_input)])
        .map_err(|e| usage(anyhow::anyhow!(e)))?;
    let check = (!args.no_check)
        .then(|| {
            SceneSource::resolve(&args.check_scene)?;
            let config = BenchConfig {
                scene: args.check_scene.clone(),
                size: args.check_size.parse::<Size>()?,
                methods: args.check_methods.iter().map(|m| m.trim().to_string()).collect(),
                frames: args.check_frames,
                resolution: args.resolution,
                ..BenchConfig::default()
            };
            config.validate()?;
            anyhow::Ok(config)
        })
        .transpose()
        .map_err(usage)?;
    let config =
        occlude_bench::calibrate::CalibrateConfig { resolution: args.resolution, repeats: args.repeats, check };
    let progress = occlude_cli::progress::Bar::spinner();
    let calibration = occlude_bench::calibrate::calibrate(&config, &progress).map_err(|e| run_failure(e.into()))?;
    progress.finish_and_clear();
    let text = calibration.to_toml().map_err(|e| Failure::Run(e.into()))?;
    std::fs::write(&args.out, &text)
        .with_context(|| format!("cannot write {}", args.out.display()))
        .map_err(Failure::Run)?;
    eprintln!("wrote {}", args.out.display());
    print(&text).map_err(Failure::Run)
}

/// `occlude view`: bad options, no display or no GPU adapter are the user's
/// (exit code 2).
fn view(args: &ViewArgs) -> Result<(), Failure> {
    let config = occlude_cli::view::ViewConfig {
        scene: BenchConfig {
            frames: args.frames,
            resolution: args.resolution,
            backend: BackendKind::Wgpu,
            ..args.scene.config(false)?
        },
        method: args.method.trim().to_string(),
        play: args.play,
        figure4: args.figure4,
        pyramid_levels: args.pyramid_levels,
        screenshot: args.screenshot.clone(),
        record: args.record.clone(),
    };
    config.validate().map_err(Failure::Usage)?;
    let outputs = [("--screenshot", args.screenshot.as_deref()), ("--record", Some(args.record.as_path()))];
    check_distinct(&outputs, &args.scene.inputs(None)).map_err(|e| Failure::Usage(anyhow::anyhow!(e)))?;
    occlude_cli::view::run(&config).map_err(run_failure)
}

/// `occlude report`: unreadable or malformed input is the user's (exit code
/// 2); failing to write the output is not (exit code 1).
fn report(args: &ReportArgs) -> Result<(), Failure> {
    let inputs: Vec<_> = args.files.iter().map(|f| ("FILE.json", Some(f.as_path()))).collect();
    check_distinct(&[("--out", Some(&args.out)), ("--markdown", args.markdown.as_deref())], &inputs)
        .map_err(|e| Failure::Usage(anyhow::anyhow!(e)))?;
    let mut reports = Vec::new();
    for path in &args.files {
        reports.extend(occlude_bench::output::load(path).map_err(|e| Failure::Usage(e.into()))?);
    }
    occlude_cli::report::write_html(&reports, &args.out).map_err(Failure::Run)?;
    eprintln!("wrote {}", args.out.display());
    if let Some(path) = &args.markdown {
        for written in occlude_cli::report::write_markdown(&reports, path).map_err(Failure::Run)? {
            eprintln!("wrote {}", written.display());
        }
    }
    Ok(())
}

/// Names as a help line lists them: "a, b or c".
fn one_of(names: &[&str]) -> String {
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.join(""),
    }
}

/// Every scene size's name, smallest first.
fn size_names() -> Vec<&'static str> {
    Size::ALL.map(Size::name).to_vec()
}

fn scenes(size: &str, seed: u64) -> Result<(), Failure> {
    let sizes = if size == "all" {
        Size::ALL.to_vec()
    } else {
        vec![size.parse::<Size>().map_err(|e| Failure::Usage(e.into()))?]
    };
    let rows: Vec<_> = sizes.into_iter().flat_map(|s| occlude_bench::scenes::rows(s, seed)).collect();
    print(&occlude_bench::scenes::render(&rows)).map_err(Failure::Run)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match &cli.command {
        Command::Bench(args) => configure(args).and_then(|config| run_bench(args, &config).map_err(run_failure)),
        Command::Report(args) => report(args),
        Command::Calibrate(args) => calibrate(args),
        Command::View(args) => view(args),
        Command::RasterBench(args) => occlude_cli::raster_bench::run(args).map_err(run_failure),
        Command::Scenes { size, seed } => scenes(size, *seed),
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
