//! Fuzzes the bench-report reader of `occlude report`. Any input may be
//! refused with an error; none may panic or hang (a plot axis made infinite
//! by a huge figure hung it once), and reports that are accepted must keep
//! the rule of what bench writes and render as HTML.

#![no_main]

use occlude_bench::figures::check_output;
use occlude_bench::output::parse;
use occlude_cli::report::html;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(reports) = parse(text, "fuzz.json") else { return };
    check_output(&reports).expect("what report reads is what bench may write");
    // Rendering plots every frame: keep it to inputs of a few frames.
    if text.len() <= 16 << 10 {
        html(&reports).expect("accepted reports render");
    }
});
