//! The user guide's examples, run: every ```` ```console ```` block in `docs/src/*.md` and
//! `README.md` is executed with the `lagrange` binary of this build and its output compared
//! with the text the guide shows, so the guide cannot drift from the program.
//!
//! Enter at [`guide_examples_match_the_program`]. A console block holds commands and what
//! they print:
//!
//! ```text
//! $ lagrange derive examples/pendulum.toml --set g=1.62
//! planar pendulum
//! ...
//! $ lagrange derive crates/cli/tests/bad/unknown_name.toml
//! ? 2
//! error: crates/cli/tests/bad/unknown_name.toml:4:28: in the Lagrangian: unknown name 'y'
//! ...
//! ```
//!
//! - `$ lagrange ARGS` runs the binary (`$ head -n N FILE` prints a file's first lines); the
//!   arguments are split as a POSIX shell does for quotes and backslashes, and a line ending
//!   in ` \` continues on the next.
//! - `? CODE` right after the command is the expected exit code (default 0).
//! - The lines up to the next `$` or the end of the block are what the command prints:
//!   stdout, then stderr, as a terminal shows them when nothing interleaves. Trailing
//!   whitespace and trailing empty lines are ignored.
//! - Two wildcards, as `trycmd` spells them: `[..]` in a line matches any characters within
//!   that line, and `...` alone on a line matches any number of lines (none included). Use
//!   them for what differs between machines (timings, thread counts) and to cut long output.
//!
//! The commands run in a scratch directory that mirrors the repository root (a symbolic link
//! to every top-level entry but `target` and `.git`), so relative paths read as in the root
//! while files a command writes (`--out run.csv`) land in the scratch directory, which is
//! removed afterwards. (A path into a linked directory, `--out examples/run.csv`, would write
//! into the repository: the guide writes plain file names.) The blocks of all files share it and run in order, so a later block
//! may read what an earlier one wrote.
//!
//! A ```` ```toml ```` block whose first line is `# examples/NAME.toml` (any `.toml` path in
//! the repository) shows that file: its other lines must match the file's lines with the same
//! wildcards, and some console block must run the file, so models shown in the guide are
//! checked too. Other blocks (```` ```sh ````, ```` ```text ````) are not run.
//!
//! Why not `trycmd`, which reads the same format: it runs the commands of a Markdown file in
//! that file's directory or in a `NAME.in/` directory beside it, not in the repository root,
//! and it compares a Markdown example's stdout and stderr merged, so it needs a `.in/` copy of
//! the examples per chapter. This runner is small and keeps trycmd's two wildcards, so the
//! guide would move to trycmd unchanged if that changes.

use crate::common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One command of a console block and what the guide says it prints.
struct Example {
    /// `file:line` of the `$` line, for failure messages.
    place: String,
    /// The command line as the guide shows it, without `$ `.
    command: String,
    words: Vec<String>,
    code: i32,
    expected: Vec<String>,
}

/// A `toml` block that shows (part of) a file of the repository.
struct ShownFile {
    place: String,
    path: String,
    lines: Vec<String>,
}

/// What the guide's Markdown files hold that this test checks.
#[derive(Default)]
struct Guide {
    examples: Vec<Example>,
    shown: Vec<ShownFile>,
}

/// The Markdown files whose blocks are checked: the guide's chapters and the README.
fn guide_files(root: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("docs/src"))
        .expect("docs/src exists")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|ext| ext == "md"))
        .collect();
    files.sort();
    files.push(root.join("README.md"));
    files
}

/// Reads the console and toml blocks of one Markdown file into `guide`.
fn parse_file(name: &str, text: &str, guide: &mut Guide) {
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let trimmed = lines[i].trim_start();
        let Some(info) = trimmed.strip_prefix("```") else {
            i += 1;
            continue;
        };
        let indent = lines[i].len() - trimmed.len();
        let lang = info.split([',', ' ', '{']).next().unwrap_or("").to_string();
        let start = i + 1;
        let mut end = start;
        while end < lines.len() && !lines[end].trim_start().starts_with("```") {
            end += 1;
        }
        // Lines of a block inside a list item carry the item's indentation.
        let body: Vec<&str> = lines[start..end].iter().map(|l| l.get(indent..).unwrap_or(l.trim_start())).collect();
        match lang.as_str() {
            "console" => parse_console(name, start, &body, guide),
            "toml" => {
                if let Some(path) = body.first().and_then(|l| l.strip_prefix("# ")).filter(|p| is_shown_path(p)) {
                    guide.shown.push(ShownFile {
                        place: format!("{name}:{start}"),
                        path: path.to_string(),
                        lines: body[1..].iter().map(|l| l.to_string()).collect(),
                    });
                }
            }
            _ => {}
        }
        i = end + 1;
    }
}

/// Whether a toml block's first comment names a file it shows (`# examples/pendulum.toml`).
fn is_shown_path(text: &str) -> bool {
    text.ends_with(".toml") && !text.contains(' ')
}

/// Reads the commands of one console block; `first` is the index of its first line.
fn parse_console(name: &str, first: usize, body: &[&str], guide: &mut Guide) {
    let mut i = 0;
    while i < body.len() {
        let Some(command) = body[i].strip_prefix("$ ") else {
            panic!("{name}:{}: a console block must start each command with `$ `: {:?}", first + i + 1, body[i]);
        };
        let place = format!("{name}:{}", first + i + 1);
        let mut command = command.to_string();
        while command.ends_with('\\') && i + 1 < body.len() {
            command.pop();
            i += 1;
            command.push_str(body[i].trim_start());
        }
        i += 1;
        let mut code = 0;
        if let Some(status) = body.get(i).and_then(|l| l.strip_prefix("? ")) {
            code = status.trim().parse().unwrap_or_else(|_| panic!("{place}: `? {status}` is not an exit code"));
            i += 1;
        }
        let mut expected = Vec::new();
        while i < body.len() && !body[i].starts_with("$ ") {
            expected.push(body[i].to_string());
            i += 1;
        }
        let words = split_words(&command).unwrap_or_else(|e| panic!("{place}: {e}: {command}"));
        guide.examples.push(Example { place, command, words, code, expected });
    }
}

/// Splits a command line into words as a POSIX shell does for quotes and backslashes
/// (no variables, globs or pipes: the guide's commands need none).
fn split_words(line: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        match c {
            ' ' | '\t' => {
                if let Some(w) = word.take() {
                    words.push(w);
                }
            }
            '\'' => {
                let w = word.get_or_insert_with(String::new);
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(c) => w.push(c),
                        None => return Err("unclosed single quote".into()),
                    }
                }
            }
            '"' => {
                let w = word.get_or_insert_with(String::new);
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => match chars.next() {
                            Some(c @ ('"' | '\\' | '$' | '`')) => w.push(c),
                            Some(c) => {
                                w.push('\\');
                                w.push(c);
                            }
                            None => return Err("unclosed double quote".into()),
                        },
                        Some(c) => w.push(c),
                        None => return Err("unclosed double quote".into()),
                    }
                }
            }
            '\\' => word.get_or_insert_with(String::new).extend(chars.next()),
            '|' | '>' | '<' | ';' | '&' | '*' | '$' | '`' => {
                return Err(format!("`{c}` needs a shell; the guide runs commands without one"));
            }
            c => word.get_or_insert_with(String::new).push(c),
        }
    }
    words.extend(word);
    Ok(words)
}

/// Whether `actual` matches `expected`, where `...` alone on a line matches any number of lines.
fn lines_match(expected: &[&str], actual: &[&str]) -> bool {
    match expected.split_first() {
        None => actual.is_empty(),
        Some((&"...", rest)) => (0..=actual.len()).any(|skip| lines_match(rest, &actual[skip..])),
        Some((line, rest)) => {
            actual.split_first().is_some_and(|(first, others)| line_matches(line, first) && lines_match(rest, others))
        }
    }
}

/// Whether one line matches, where `[..]` matches any characters within the line.
fn line_matches(expected: &str, actual: &str) -> bool {
    let mut pieces = expected.split("[..]");
    let head = pieces.next().unwrap_or("");
    let Some(mut rest) = actual.strip_prefix(head) else { return false };
    let pieces: Vec<&str> = pieces.collect();
    let Some((tail, middle)) = pieces.split_last() else { return rest.is_empty() };
    for piece in middle {
        match rest.find(piece) {
            Some(at) => rest = &rest[at + piece.len()..],
            None => return false,
        }
    }
    rest.len() >= tail.len() && rest.ends_with(tail)
}

/// Where a greedy reading of `expected` first fails on `actual`, for failure messages.
fn first_mismatch(expected: &[&str], actual: &[&str]) -> String {
    let (mut e, mut a) = (0, 0);
    while e < expected.len() {
        if expected[e] == "..." {
            e += 1;
            let Some(next) = expected.get(e) else { return "the output matches".into() };
            match actual[a..].iter().position(|line| line_matches(next, line)) {
                Some(skip) => a += skip,
                None => return format!("no line of the output matches the guide's line {}: {next}", e + 1),
            }
            continue;
        }
        match actual.get(a) {
            Some(line) if line_matches(expected[e], line) => {
                e += 1;
                a += 1;
            }
            Some(line) => {
                return format!("the guide's line {}: {}\n  differs from line {}: {line}", e + 1, expected[e], a + 1)
            }
            None => return format!("the output ends before the guide's line {}: {}", e + 1, expected[e]),
        }
    }
    match actual.get(a) {
        Some(line) => format!("the output goes on after the guide's text, at line {}: {line}", a + 1),
        None => "the output matches".into(),
    }
}

/// Text as compared: lines without trailing whitespace, and no trailing empty lines.
fn normalized(text: &str) -> Vec<&str> {
    let mut lines: Vec<&str> = text.lines().map(str::trim_end).collect();
    while lines.last().is_some_and(|l| l.is_empty()) {
        lines.pop();
    }
    lines
}

/// A scratch directory that mirrors the repository root, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(root: &Path) -> Scratch {
        let dir = std::env::temp_dir().join(format!("lagrange-guide-{}", std::process::id()));
        // A directory left by an earlier run that had this process id goes first.
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create the scratch directory");
        let scratch = Scratch(dir);
        for entry in std::fs::read_dir(root).expect("list the repository root") {
            let entry = entry.expect("a directory entry");
            let name = entry.file_name();
            if name == "target" || name == ".git" {
                continue;
            }
            std::os::unix::fs::symlink(entry.path(), scratch.0.join(&name))
                .unwrap_or_else(|e| panic!("cannot link {name:?} into the scratch directory: {e}"));
        }
        scratch
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        // Removing the directory removes the links, never what they point to.
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs one example in `dir`: its exit code and what it printed (stdout, then stderr).
fn run(example: &Example, dir: &Path) -> Result<(i32, String), String> {
    let (program, args) = example.words.split_first().ok_or("an empty command")?;
    match program.as_str() {
        "lagrange" => {
            let out = Command::new(env!("CARGO_BIN_EXE_lagrange"))
                .args(args)
                .current_dir(dir)
                .output()
                .map_err(|e| format!("cannot start lagrange: {e}"))?;
            let mut printed = String::from_utf8_lossy(&out.stdout).into_owned();
            printed.push_str(&String::from_utf8_lossy(&out.stderr));
            Ok((out.status.code().unwrap_or(-1), printed))
        }
        "head" => {
            let (count, file) = match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
                ["-n", n, file] => (n, file),
                [flag, file] if flag.starts_with('-') => (&flag[1..], file),
                _ => return Err("the guide's `head` takes `-n N FILE` or `-N FILE`".into()),
            };
            let count: usize = count.parse().map_err(|_| format!("`head`: {count} is not a line count"))?;
            let text = std::fs::read_to_string(dir.join(file)).map_err(|e| format!("head: {file}: {e}"))?;
            Ok((0, text.lines().take(count).map(|l| format!("{l}\n")).collect()))
        }
        other => Err(format!("the guide runs `lagrange` and `head`, not `{other}`")),
    }
}

#[test]
fn guide_examples_match_the_program() {
    let root = common::repo_root();
    let mut guide = Guide::default();
    for file in guide_files(&root) {
        let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
        let name = file.strip_prefix(&root).unwrap_or(&file).display().to_string();
        parse_file(&name, &text, &mut guide);
    }
    assert!(guide.examples.len() >= 30, "found only {} console examples in the guide", guide.examples.len());

    let scratch = Scratch::new(&root);
    let mut failures = String::new();
    for example in &guide.examples {
        let expected = example.expected.join("\n");
        let expected = normalized(&expected);
        match run(example, &scratch.0) {
            Err(e) => writeln!(failures, "{}: $ {}\n  {e}\n", example.place, example.command).unwrap(),
            Ok((code, printed)) => {
                let actual = normalized(&printed);
                if code != example.code || !lines_match(&expected, &actual) {
                    writeln!(
                        failures,
                        "{}: $ {}\nexit code {code} (the guide says {}); {}\n--- it printed:\n{}\n",
                        example.place,
                        example.command,
                        example.code,
                        first_mismatch(&expected, &actual),
                        actual.join("\n")
                    )
                    .unwrap();
                }
            }
        }
    }

    for shown in &guide.shown {
        let text = match std::fs::read_to_string(root.join(&shown.path)) {
            Ok(text) => text,
            Err(e) => {
                writeln!(failures, "{}: shows {}, which cannot be read: {e}\n", shown.place, shown.path).unwrap();
                continue;
            }
        };
        let expected = shown.lines.join("\n");
        if !lines_match(&normalized(&expected), &normalized(&text)) {
            writeln!(failures, "{}: the block differs from {}:\n{}\n", shown.place, shown.path, expected).unwrap();
        }
        if !guide.examples.iter().any(|e| e.words.contains(&shown.path)) {
            writeln!(failures, "{}: no console example runs {}\n", shown.place, shown.path).unwrap();
        }
    }
    drop(scratch);
    assert!(failures.is_empty(), "the guide and the program disagree:\n\n{failures}");
}

#[test]
fn wildcards_match_as_documented() {
    assert!(line_matches("1000 steps, [..] s", "1000 steps, 0.026 s"));
    assert!(line_matches("a[..]b[..]c", "a-b-b-c"));
    assert!(line_matches("[..]", ""));
    assert!(!line_matches("1000 steps, [..] s", "1001 steps, 0.026 s"));
    assert!(!line_matches("exact", "exact but longer"));
    assert!(!line_matches("ab[..]ba", "aba"));
    assert!(lines_match(&["a", "...", "d"], &["a", "b", "c", "d"]));
    assert!(lines_match(&["a", "...", "b"], &["a", "b"]));
    assert!(lines_match(&["...", "c", "..."], &["a", "b", "c", "d"]));
    assert!(!lines_match(&["a", "...", "d"], &["a", "b", "c"]));
    assert!(!lines_match(&["a"], &["a", "b"]));
    assert_eq!(
        split_words(r#"sweep m.toml --grid "a=0:1:3,b'=0:1:2" 'x y' a\ b"#).unwrap(),
        ["sweep", "m.toml", "--grid", "a=0:1:3,b'=0:1:2", "x y", "a b"]
    );
    assert!(split_words("derive m.toml > out.txt").is_err());
}
