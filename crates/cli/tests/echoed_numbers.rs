//! A number the user gave comes back in a message or a header by its shortest
//! round-trip digits: `1e300`, never a 1 and three hundred zeros (`f64`'s
//! `Display`), whichever flag, parameter or check echoes it.

use crate::common::{run, scratch};

/// Each command with a number of the user's as `{}`: flags, `--set` values
/// that a check refuses, grid values.
const COMMANDS: [&[&str]; 17] = [
    &["simulate", "{free}", "--until", "{}", "--samples", "3"],
    &["simulate", "{free}", "--until", "1", "--rtol", "{}"],
    &["simulate", "{free}", "--until", "1", "--atol", "{}"],
    &["simulate", "{free}", "--until", "1", "--dt", "{}"],
    &["simulate", "{free}", "--until", "{}", "--dt", "1"],
    &["report", "{free}", "--until", "{}", "--samples", "3", "-o", "{page}"],
    &["report", "{free}", "--until", "1", "--rtol", "{}", "-o", "{page}"],
    &["sweep", "{free}", "--until", "-{}", "--grid", "k=1:2:2"],
    &["sweep", "{free}", "--until", "1", "--atol", "-{}", "--grid", "k=1:2:2"],
    &["sweep", "{free}", "--until", "1", "--grid", "k={}:1:2"],
    &["simulate", "examples/tops/heavy_top.toml", "--until", "1", "--set", "M=-{}"],
    &["simulate", "examples/tops/heavy_top.toml", "--until", "1", "--set", "I={}"],
    &["simulate", "examples/tops/heavy_top.toml", "--until", "1", "--set", "I=-{}"],
    &["top", "examples/tops/heavy_top.toml", "--set", "I3={}"],
    &["top", "examples/tops/heavy_top.toml", "--set", "I3=-{}"],
    &["modes", "examples/coupled_oscillators.toml", "--set", "m=-{}"],
    &["simulate", "examples/pendulum.toml", "--until", "{}", "--samples", "3"],
];

#[test]
fn numbers_in_messages_are_written_by_their_shortest_digits() {
    let free = scratch("echoed", "free.toml");
    std::fs::write(
        &free,
        "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\n[parameters]\nk = 1\n[initial]\nx = 0\n\"x'\" = 0\n",
    )
    .unwrap();
    let page = free.with_extension("html");
    let mut echoed = 0;
    for value in ["1e300", "1e-300", "2.5e17"] {
        for command in COMMANDS {
            let args: Vec<String> = command
                .iter()
                .map(|a| {
                    a.replace("{free}", free.to_str().unwrap())
                        .replace("{page}", page.to_str().unwrap())
                        .replace("{}", value)
                })
                .collect();
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let r = run(&args);
            let text = format!("{}{}", r.stdout, r.stderr);
            let longest = text.split(|c: char| !c.is_ascii_digit()).map(str::len).max().unwrap_or(0);
            assert!(longest < 20, "a number of {longest} digits: {}", r.describe());
            echoed += usize::from(text.contains(value));
        }
    }
    // The messages do name the numbers (the check above is not vacuous).
    assert!(echoed >= 20, "only {echoed} outputs name the number given");
}
