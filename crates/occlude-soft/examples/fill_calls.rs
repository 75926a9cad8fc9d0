//! A profiling harness for the rasterizer: a fixed number of calls of the field's
//! fill-rate workload (`workload::right_triangles`, two screens of pixels per call,
//! back to front), so that an instruction counter (`valgrind --tool=callgrind`) or a
//! sampling profiler (`perf record`) sees the same work on every run. Prints the
//! fastest call's time (the least disturbed on a shared machine).
//!
//! ```sh
//! cargo build --release -p occlude-soft --example fill_calls
//! target/release/examples/fill_calls --leg 25 --calls 20 --threads 1
//! RES=1024x768 target/release/examples/fill_calls --leg 100
//! ```

use std::time::Instant;

use occlude_soft::raster::{Command, CommandKind, DepthBuffer, Rasterizer};
use occlude_soft::workload;

/// The harness's settings, from `--leg N`, `--calls K`, `--threads T` and the
/// `RES=WIDTHxHEIGHT` environment variable.
struct Args {
    leg: u32,
    calls: usize,
    threads: usize,
    width: u32,
    height: u32,
}

fn parse() -> Result<Args, String> {
    let mut args = Args { leg: 25, calls: 10, threads: 1, width: 1920, height: 1080 };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or_else(|| format!("{flag} needs a value"))?;
        let number = |v: &str| v.parse::<usize>().map_err(|e| format!("{flag} {v}: {e}"));
        match flag.as_str() {
            "--leg" => args.leg = number(&value)?.max(1) as u32,
            "--calls" => args.calls = number(&value)?.max(1),
            "--threads" => args.threads = number(&value)?.max(1),
            _ => return Err(format!("unknown option {flag} (--leg N, --calls K, --threads T)")),
        }
    }
    if let Ok(res) = std::env::var("RES") {
        let (w, h) = res.split_once('x').ok_or_else(|| format!("RES={res}: expected WIDTHxHEIGHT"))?;
        let size = |v: &str| v.parse::<u32>().ok().filter(|&n| (1..=16384).contains(&n));
        match (size(w), size(h)) {
            (Some(w), Some(h)) => (args.width, args.height) = (w, h),
            _ => return Err(format!("RES={res}: sides must be 1 to 16384 pixels")),
        }
    }
    Ok(args)
}

fn main() {
    let args = parse().unwrap_or_else(|e| {
        eprintln!("fill_calls: {e}");
        std::process::exit(2);
    });
    let (w, h) = (args.width, args.height);
    let count = workload::triangles_for_screens(w, h, args.leg, 2.0);
    let tris = workload::right_triangles(w, h, args.leg as f32, count);
    let commands = [Command { kind: CommandKind::Draw, triangles: 0..count as u32, cull_back: false }];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.threads).build().expect("thread pool");
    let mut raster = Rasterizer::new();
    let mut depth = DepthBuffer::new(w, h);
    let mut fastest = f64::INFINITY;
    for _ in 0..args.calls {
        depth.clear();
        let start = Instant::now();
        pool.install(|| raster.execute(&mut depth, &tris, &commands));
        fastest = fastest.min(start.elapsed().as_secs_f64());
    }
    println!(
        "{w}x{h}, N = {}, {} threads, {count} triangles per call: fastest of {} calls {:.3} ms, {:.3} MTris/s",
        args.leg,
        args.threads,
        args.calls,
        fastest * 1e3,
        count as f64 / fastest / 1e6
    );
}
