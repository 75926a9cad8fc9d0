//! `docs/cli.md` is the command line's reference, kept true here: it has a
//! section for every command `occlude --help` lists, names every flag each
//! command's `--help` lists, and its example command lines use only flags
//! their command has.

use std::collections::BTreeSet;
use std::process::Command;

/// The reference, as committed.
fn reference() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/cli.md");
    std::fs::read_to_string(path).expect("docs/cli.md is readable")
}

/// What `occlude <args>` prints.
fn occlude(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_occlude")).args(args).output().expect("occlude runs");
    assert!(out.status.success(), "occlude {args:?} failed");
    String::from_utf8(out.stdout).expect("UTF-8 help")
}

/// The commands `occlude --help` lists (`help` left out).
fn commands() -> Vec<String> {
    let help = occlude(&["--help"]);
    let listed = help.split("Commands:").nth(1).and_then(|rest| rest.split("Options:").next()).expect("a list");
    let names = listed.lines().filter_map(|line| line.split_whitespace().next());
    names.filter(|&name| name != "help").map(str::to_string).collect()
}

/// The long flags (`--name`) in `text`.
fn flags(text: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for (at, _) in text.match_indices("--") {
        let name: String = text[at + 2..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
        if name.starts_with(|c: char| c.is_ascii_lowercase()) {
            found.insert(format!("--{name}"));
        }
    }
    found
}

#[test]
fn every_command_and_flag_is_in_the_reference() {
    let reference = reference();
    let commands = commands();
    assert!(commands.len() >= 6, "{commands:?}");
    for command in &commands {
        assert!(reference.contains(&format!("## `occlude {command}`")), "docs/cli.md has no section for {command}");
        for flag in flags(&occlude(&[command, "--help"])) {
            assert!(reference.contains(&flag), "docs/cli.md does not name `occlude {command} {flag}`");
        }
    }
}

#[test]
fn the_reference_s_command_lines_use_flags_their_command_has() {
    let reference = reference();
    let known: Vec<(String, BTreeSet<String>)> =
        commands().into_iter().map(|c| (c.clone(), flags(&occlude(&[&c, "--help"])))).collect();
    let mut checked = 0;
    let mut in_code = false;
    let mut line_of_command: Option<(String, String)> = None;
    for line in reference.lines() {
        if line.starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if !in_code {
            continue;
        }
        // A command line and its continuation lines (ending in `\`).
        let text = line.trim();
        let (command, mut whole) = match line_of_command.take() {
            Some((command, so_far)) => (command, so_far + " " + text),
            None => match text.strip_prefix("occlude ").and_then(|rest| rest.split_whitespace().next()) {
                Some(command) => (command.to_string(), text.to_string()),
                None => continue,
            },
        };
        if whole.ends_with('\\') {
            whole.pop();
            line_of_command = Some((command, whole));
            continue;
        }
        let Some((_, allowed)) = known.iter().find(|(name, _)| *name == command) else { continue };
        for flag in flags(&whole) {
            assert!(allowed.contains(&flag), "docs/cli.md: `{whole}` uses {flag}, which `occlude {command}` lacks");
        }
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} command lines found in docs/cli.md");
}
