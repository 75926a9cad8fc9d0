//! The allowed range of every number a command takes, one place per kind
//! (threads, image sizes, frame counts, repeats, triangle counts, seconds,
//! frame rates), each checked by one parser whose error names the value and
//! its range. The command-line options parse with these (clap then names the
//! option), and [`crate::config::BenchConfig::validate`] checks a
//! configuration built in code against the same bounds.
//!
//! The bounds keep every run's time and memory bounded by what was asked
//! for: a thread count, an image size or a frame count large enough to hang
//! the machine or exhaust its memory is refused before any work starts.

use std::fmt::Display;
use std::ops::RangeInclusive;
use std::str::FromStr;

/// The most worker threads a command starts (`--threads`).
pub const MAX_THREADS: usize = 256;

/// The longest side of an image, pixels (`--resolution`).
pub const MAX_SIDE: u32 = 16384;

/// The most pixels of an image (4096x4096; 7680x2160 fits): the depth and
/// colour buffers of every method's lane stay within a few hundred MB each.
pub const MAX_PIXELS: u64 = 4096 * 4096;

/// The most frames a run renders (`--frames N`, and `--frames all` on a
/// long walkthrough): 55 minutes of walkthrough at 30 fps. Every frame's
/// statistics are kept for the report, so a run's memory grows with it.
pub const MAX_FRAMES: usize = 100_000;

/// The most repeats of a calibration measurement (`calibrate --repeats`).
pub const MAX_REPEATS: usize = 1000;

/// The most triangles a `raster-bench` fill-rate call draws
/// (`--triangles-per-size`, and the default's two screens of pixels at small
/// sizes): about 200 MB of vertices.
pub const MAX_TRIANGLES_PER_CALL: u64 = 4_000_000;

/// The longest a `raster-bench` row is measured for, seconds
/// (`--seconds-per-row`).
pub const MAX_SECONDS_PER_ROW: f64 = 600.0;

/// The highest walkthrough frame rate, frames per second (`--fps`).
pub const MAX_FPS: f32 = 1000.0;

/// Parses `s` as `what` (a phrase such as "a thread count") within `range`;
/// the error names the value and the range.
pub fn parse_in<T>(s: &str, what: &str, range: RangeInclusive<T>) -> Result<T, String>
where
    T: FromStr + PartialOrd + Display,
{
    let value = s.trim().parse::<T>().map_err(|_| out_of_range(s, what, &range))?;
    check_in(value, what, range)
}

/// Checks that `value`, `what` (a phrase such as "a thread count"), lies
/// within `range`; the error names the value and the range.
pub fn check_in<T: PartialOrd + Display>(value: T, what: &str, range: RangeInclusive<T>) -> Result<T, String> {
    if range.contains(&value) {
        Ok(value)
    } else {
        Err(out_of_range(&value.to_string(), what, &range))
    }
}

fn out_of_range<T: Display>(value: &str, what: &str, range: &RangeInclusive<T>) -> String {
    format!("'{value}' is not {what} from {} to {}", range.start(), range.end())
}

/// Parses a thread count, 1 to [`MAX_THREADS`].
pub fn parse_threads(s: &str) -> Result<usize, String> {
    parse_in(s, "a thread count", 1..=MAX_THREADS)
}

/// Parses a frame count, 1 to [`MAX_FRAMES`].
pub fn parse_frame_count(s: &str) -> Result<usize, String> {
    parse_in(s, FRAME_COUNT, 1..=MAX_FRAMES)
}

/// Checks a frame count, 1 to [`MAX_FRAMES`].
pub fn check_frame_count(frames: usize) -> Result<usize, String> {
    check_in(frames, FRAME_COUNT, 1..=MAX_FRAMES)
}

const FRAME_COUNT: &str = "a frame count";

/// Parses a repeat count, 1 to [`MAX_REPEATS`].
pub fn parse_repeats(s: &str) -> Result<usize, String> {
    parse_in(s, REPEAT_COUNT, 1..=MAX_REPEATS)
}

/// Checks a repeat count, 1 to [`MAX_REPEATS`].
pub fn check_repeats(repeats: usize) -> Result<usize, String> {
    check_in(repeats, REPEAT_COUNT, 1..=MAX_REPEATS)
}

const REPEAT_COUNT: &str = "a repeat count";

/// Parses a triangle count per call, 1 to [`MAX_TRIANGLES_PER_CALL`].
pub fn parse_triangles_per_call(s: &str) -> Result<u64, String> {
    parse_in(s, "a triangle count", 1..=MAX_TRIANGLES_PER_CALL)
}

/// Parses a frame rate: above 0, at most [`MAX_FPS`].
pub fn parse_fps(s: &str) -> Result<f32, String> {
    s.trim().parse::<f32>().ok().filter(|&fps| check_fps(fps).is_ok()).ok_or_else(|| fps_range(s))
}

/// Checks a frame rate: above 0, at most [`MAX_FPS`].
pub fn check_fps(fps: f32) -> Result<(), String> {
    if fps > 0.0 && fps <= MAX_FPS {
        Ok(())
    } else {
        Err(fps_range(&fps.to_string()))
    }
}

fn fps_range(s: &str) -> String {
    format!("'{s}' is not a frame rate above 0 and at most {MAX_FPS}")
}

/// Parses a number of seconds: above 0, at most [`MAX_SECONDS_PER_ROW`].
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= MAX_SECONDS_PER_ROW => Ok(v),
        _ => Err(format!("'{s}' is not a number of seconds above 0 and at most {MAX_SECONDS_PER_ROW}")),
    }
}

/// Parses `WIDTHxHEIGHT` and checks it with [`check_resolution`].
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let not = || format!("'{s}' is not WIDTHxHEIGHT (e.g. 1024x768)");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(not)?;
    let parse = |v: &str| v.trim().parse::<u32>().map_err(|_| not());
    let resolution = (parse(w)?, parse(h)?);
    check_resolution(resolution)?;
    Ok(resolution)
}

/// Checks an image size: each side 1 to [`MAX_SIDE`] pixels, at most
/// [`MAX_PIXELS`] pixels in all.
pub fn check_resolution((w, h): (u32, u32)) -> Result<(), String> {
    let pixels = u64::from(w) * u64::from(h);
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE || pixels > MAX_PIXELS {
        return Err(format!(
            "resolution {w}x{h} is out of range: each side must be 1 to {MAX_SIDE} pixels and the image at most \
             {MAX_PIXELS} pixels (4096x4096)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every parser takes its range's ends and refuses what lies past them
    /// (or is not a number), naming the value and the range.
    #[test]
    fn each_kind_takes_its_range_and_names_it_otherwise() {
        type Parser = fn(&str) -> Result<f64, String>;
        let kinds: [(Parser, &str, &str, &[&str]); 6] = [
            (|s| parse_threads(s).map(|v| v as f64), "1", "256", &["0", "257", "100000", "-1", "x"]),
            (|s| parse_frame_count(s).map(|v| v as f64), "1", "100000", &["0", "100001", "1e9"]),
            (|s| parse_repeats(s).map(|v| v as f64), "1", "1000", &["0", "1001"]),
            (|s| parse_triangles_per_call(s).map(|v| v as f64), "1", "4000000", &["0", "1000000000"]),
            (|s| parse_fps(s).map(f64::from), "0.5", "1000", &["0", "-1", "1001", "inf", "NaN"]),
            (parse_seconds, "0.01", "600", &["0", "601", "1e300", "inf", "NaN"]),
        ];
        for (parse, low, high, bad) in kinds {
            parse(low).unwrap();
            parse(high).unwrap();
            for b in bad {
                let e = parse(b).unwrap_err();
                assert!(e.contains(&format!("'{b}'")) && e.contains(high), "{e}");
            }
        }
        assert_eq!(parse_resolution("7680x2160"), Ok((7680, 2160)));
        for bad in ["0x0", "0x10", "100000x100000", "16384x16384", "16385x1"] {
            let e = parse_resolution(bad).unwrap_err();
            assert!(e.contains(bad) && e.contains("16384") && e.contains("16777216"), "{e}");
        }
        assert!(parse_resolution("640").unwrap_err().contains("WIDTHxHEIGHT"));
    }
}
