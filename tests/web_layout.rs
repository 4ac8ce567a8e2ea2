//! The browser app stays thin: a page is a short composition of panels (no file under
//! `src/web/pages/` over 600 lines, no component function in `src/web/` over 200), and no page
//! routes an error by searching its text (no `contains("…")`, `starts_with("…")` or
//! `ends_with("…")` on a literal anywhere in `src/web/`): an error carries the setting it belongs
//! to as data.
//!
//! Reads `src/web/` as text, as tests/layers.rs reads `src/`.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// Reads the source tree from the file system: native only.
#![cfg(not(target_arch = "wasm32"))]

use std::path::{Path, PathBuf};

/// The most lines a page file may have.
const MAX_PAGE_FILE_LINES: usize = 600;
/// The most lines a component function may have, from its `fn` line to its closing brace.
const MAX_COMPONENT_LINES: usize = 200;

/// Every `.rs` file below `dir`, with its text.
fn files(dir: &Path) -> Vec<(PathBuf, String)> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                found.push((path, text));
            }
        }
    }
    found.sort();
    found
}

fn web() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src")
        .join("web")
}

/// Each `#[component]` function of `text`: its name, first line (1-based) and length in lines,
/// from its `fn` line to the line closing its body at the indentation it opened at.
fn components(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if line.trim() != "#[component]" {
            continue;
        }
        let Some(offset) = lines[i..].iter().position(|l| {
            l.trim_start().starts_with("pub fn ") || l.trim_start().starts_with("fn ")
        }) else {
            continue;
        };
        let start = i + offset;
        let indent = lines[start].len() - lines[start].trim_start().len();
        let name: String = lines[start]
            .trim_start()
            .trim_start_matches("pub ")
            .trim_start_matches("fn ")
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let closing = format!("{}}}", " ".repeat(indent));
        let end = lines[start..]
            .iter()
            .position(|l| *l == closing)
            .map_or(lines.len(), |e| start + e);
        found.push((name, start + 1, end - start + 1));
    }
    found
}

#[test]
fn page_files_and_component_functions_stay_short() {
    let mut too_long = Vec::new();
    for (path, text) in files(&web()) {
        let relative = path.strip_prefix(web()).unwrap().display().to_string();
        let lines = text.lines().count();
        if path.starts_with(web().join("pages")) && lines > MAX_PAGE_FILE_LINES {
            too_long.push(format!(
                "{relative}: {lines} lines (a page file holds at most {MAX_PAGE_FILE_LINES}: \
                 split its panels into files of their own)"
            ));
        }
        for (name, line, length) in components(&text) {
            if length > MAX_COMPONENT_LINES {
                too_long.push(format!(
                    "{relative}:{line}: component {name} is {length} lines (at most \
                     {MAX_COMPONENT_LINES}: make its parts components of their own)"
                ));
            }
        }
    }
    assert!(too_long.is_empty(), "{}", too_long.join("\n"));
}

#[test]
fn no_page_reads_an_errors_text() {
    let mut matched = Vec::new();
    for (path, text) in files(&web()) {
        let relative = path.strip_prefix(web()).unwrap().display().to_string();
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or_default();
            for call in [".contains(\"", ".starts_with(\"", ".ends_with(\""] {
                if code.contains(call) {
                    matched.push(format!("{relative}:{}: {}", i + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        matched.is_empty(),
        "text matched where a typed value should say it (an error's setting, a kind):\n{}",
        matched.join("\n")
    );
}

#[test]
fn the_checks_find_what_they_are_meant_to() {
    let text = "#[component]\npub fn Short() -> impl IntoView {\n    x\n}\n\n    #[component]\n    fn Inner(a: u8) {\n        if a { y }\n    }\n";
    assert_eq!(
        components(text),
        [("Short".to_string(), 2, 3), ("Inner".to_string(), 7, 3)]
    );
}
