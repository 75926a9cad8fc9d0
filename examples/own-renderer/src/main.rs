//! Runs the example renderer off-screen: a walk past the walls, culling off
//! or with occlude methods (several in one run, one after the other:
//! query-driven or GPU-driven),
//! printing what each frame drew and how long it took until the GPU was
//! idle (with `--gpu-time`, a GPU-driven method's culling passes and
//! drawing passes timed on the GPU), and writes the last frame as a PNG.
//!
//! `cargo run --release -p own-renderer -- [--culling off,chcpp,chc,om,sw,vfc,hiz,roc,ioc,auto]
//! [--frames N] [--grid N] [--meshes N] [--msaa SAMPLES] [--viewport X,Y,W,H] [--size PIXELS] [--reverse-z] [--depth24]
//! [--gpu-time] [--out FILE.png]`

use occlude::wgpu::embed::Viewport;
use own_renderer::{open_device, Options, Renderer};
use std::error::Error;
use std::path::PathBuf;
use std::time::Instant;

fn main() {
    if let Err(e) = run() {
        eprintln!("own-renderer: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn Error>> {
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let mut options =
        Options { size: 512, grid: 60, reverse_z: false, depth_format, meshes: 4, samples: 1, viewport: None };
    let (mut culling, mut frames, mut out) = (String::from("chcpp"), 8u32, PathBuf::from("own-renderer.png"));
    let mut gpu_time = false;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{arg} needs a value"));
        match arg.as_str() {
            "--culling" => culling = value()?,
            "--frames" => frames = value()?.parse()?,
            "--grid" => options.grid = value()?.parse()?,
            "--meshes" => options.meshes = value()?.parse()?,
            "--msaa" => options.samples = value()?.parse()?,
            "--viewport" => options.viewport = Some(viewport(&value()?)?),
            "--size" => options.size = value()?.parse()?,
            "--out" => out = value()?.into(),
            "--reverse-z" => options.reverse_z = true,
            "--depth24" => options.depth_format = wgpu::TextureFormat::Depth24Plus,
            "--gpu-time" => gpu_time = true,
            _ => return Err(format!("unknown argument '{arg}' (see the README)").into()),
        }
    }
    if frames == 0 || options.size == 0 || options.grid == 0 || options.meshes == 0 {
        return Err("--frames, --size, --grid and --meshes must be at least 1".into());
    }
    if ![1, 4].contains(&options.samples) {
        return Err("--msaa takes 1 or 4 (the counts every adapter has)".into());
    }
    let (device, queue) = open_device()?;
    let mut renderer = Renderer::new(device, queue, options);
    renderer.time_gpu(gpu_time)?;
    for mode in culling.split(',') {
        renderer.set_culling((mode != "off").then(|| mode.parse()).transpose()?)?;
        let (mut total_ms, mut total_drawn, mut total_gpu) = (0.0, 0, (0.0, 0.0));
        for frame in 0..frames {
            let t = if frames > 1 { frame as f32 / (frames - 1) as f32 } else { 0.0 };
            let start = Instant::now();
            let drawn = renderer.render(t)?;
            renderer.wait_idle()?;
            let ms = start.elapsed().as_secs_f64() * 1e3;
            total_ms += ms;
            total_drawn += drawn;
            let n = renderer.instance_count();
            let mut line = format!("frame {frame}: culling {mode}, drew {drawn} of {n} instances in {ms:.2} ms");
            if let Some(p) = renderer.pass_counts() {
                let (compute, render, dispatches) = (p.compute_passes, p.render_passes, p.dispatches);
                line += &format!("; {compute} compute and {render} render passes, {dispatches} dispatches");
                if let Some((test, probe)) = renderer.late_test().filter(|_| mode == "auto") {
                    line += &format!("; late test {test}{}", if probe { " (probe)" } else { "" });
                }
                if let Some(gpu) = renderer.gpu_times()? {
                    line += &format!("; GPU: culling {:.2} ms, drawing {:.2} ms", gpu.culling_ms, gpu.drawing_ms);
                    total_gpu = (total_gpu.0 + gpu.culling_ms, total_gpu.1 + gpu.drawing_ms);
                }
            }
            println!("{line}");
        }
        let drawn = total_drawn as f64 / f64::from(frames);
        let mut line = format!(
            "culling {mode}: {drawn:.0} instances drawn and {:.2} ms per frame on average",
            total_ms / f64::from(frames)
        );
        if total_gpu.0 > 0.0 {
            let per_frame = |ms: f64| ms / f64::from(frames);
            line +=
                &format!("; GPU: culling {:.2} ms, drawing {:.2} ms", per_frame(total_gpu.0), per_frame(total_gpu.1));
        }
        println!("{line}");
    }
    renderer.save_png(&out)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// A viewport from `X,Y,WIDTH,HEIGHT`.
fn viewport(text: &str) -> Result<Viewport, Box<dyn Error>> {
    let v: Vec<u32> = text.split(',').map(str::parse).collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, width, height] => Ok(Viewport { x, y, width, height }),
        _ => Err(format!("--viewport takes X,Y,WIDTH,HEIGHT, not '{text}'").into()),
    }
}
