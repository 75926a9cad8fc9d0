//! The rule every measured or simulated figure keeps, on the way out (a
//! bench report before it is printed or written) and on the way in (a report
//! `occlude report` reads): a figure is a finite number within
//! ±[`MAX_FIGURE`]. A run whose figures break it is an error instead of a
//! table of `inf` and `NaN` and a JSON file of `null`s; a report file whose
//! figures break it is refused instead of plotted on an infinite axis.
//! Whole numbers (counts, seeds) are exact integers in JSON and are not
//! bounded here.

use crate::error::{Error, Result};
use serde::Serialize;
use serde_json::Value;

/// The largest magnitude of a figure: 1e15 ms is 30,000 years, far beyond
/// any frame, while sums of millions of such figures stay finite.
pub const MAX_FIGURE: f64 = 1e15;

/// Keys of a bench report whose `null` means "not measured", not a
/// non-finite figure (`ratio_to_opt` without `opt`).
const NULLABLE: [&str; 1] = ["ratio_to_opt"];

/// Checks every figure of `report` (any bench report, or a list of them) as
/// it will be written: serde writes a non-finite float as `null`, so a
/// `null` where a figure belongs is one.
pub fn check_output<T: Serialize + ?Sized>(report: &T) -> Result<()> {
    let value = serde_json::to_value(report)
        .map_err(|source| Error::Json { context: "cannot read the run's figures".into(), source })?;
    if let Some(at) = first_bad(&value, "", &|key, v| v.is_null() && !NULLABLE.contains(&key) || out_of_range(v)) {
        return Err(Error::Figures { at });
    }
    Ok(())
}

/// Checks every figure of a report read from a file, naming the first one
/// out of range by its place in the document.
pub fn check_input(value: &Value) -> std::result::Result<(), String> {
    match first_bad(value, "", &|_, v| out_of_range(v)) {
        Some(at) => Err(format!("{at} is not a figure within ±{MAX_FIGURE:e}")),
        None => Ok(()),
    }
}

/// Whether `v` is a non-integer number beyond ±[`MAX_FIGURE`].
fn out_of_range(v: &Value) -> bool {
    matches!(v, Value::Number(n) if n.is_f64() && n.as_f64().is_none_or(|x| !(-MAX_FIGURE..=MAX_FIGURE).contains(&x)))
}

/// The place (`methods[1].per_frame[3].gpu_ms`) of the first value under
/// `value`, itself at `at`, for which `bad(its key, it)` holds.
fn first_bad(value: &Value, at: &str, bad: &dyn Fn(&str, &Value) -> bool) -> Option<String> {
    match value {
        Value::Array(items) => items.iter().enumerate().find_map(|(i, v)| {
            let place = format!("{at}[{i}]");
            if bad("", v) {
                Some(place)
            } else {
                first_bad(v, &place, bad)
            }
        }),
        Value::Object(fields) => fields.iter().find_map(|(key, v)| {
            let place = if at.is_empty() { key.clone() } else { format!("{at}.{key}") };
            if bad(key, v) {
                Some(place)
            } else {
                first_bad(v, &place, bad)
            }
        }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_figure_that_is_not_finite_or_out_of_proportion_is_named_by_its_place() {
        check_output(
            &json!({"methods": [{"frame_ms": 1.5, "ratio_to_opt": null, "queries": 18446744073709551615u64}]}),
        )
        .unwrap();
        for (report, place) in [
            (
                json!({"methods": [{"frame_ms": 1.5}, {"per_frame": [{"gpu_ms": f64::INFINITY}]}]}),
                "methods[1].per_frame[0].gpu_ms",
            ),
            (json!({"speedup": f64::NAN}), "speedup"),
            (json!({"frame_ms": 1e300}), "frame_ms"),
        ] {
            let e = check_output(&report).unwrap_err().to_string();
            assert!(e.contains(&format!("({place} is not)")), "{e}");
        }
        check_input(&json!({"frame_ms": [1e15, -1e15, 3], "seed": 18446744073709551615u64})).unwrap();
        let e = check_input(&json!({"methods": [{"frame_ms": 1.7e308}]})).unwrap_err();
        assert!(e.contains("methods[0].frame_ms"), "{e}");
    }
}
