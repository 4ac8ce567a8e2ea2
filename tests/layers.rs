//! The module layout shows the data flow: no module imports a module that (through others)
//! imports it back, and no layer reaches up into a higher one (the serial transport below the
//! loop, estimation below the loop, the core below the front ends).
//!
//! Reads `src/` as text: every `crate::…`, `super::…` and (in a module file) child path outside
//! comments, strings and the `#[cfg(test)]` tests at the bottom of a file is an edge from the
//! file's module to the module the path names. Doc links and tests may point anywhere.
//!
//! And two different things never share a name: no type, enum or trait is declared in two
//! modules of `src/` (tests apart), so a name read anywhere means one thing.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// Reads the source tree from the file system: native only.
#![cfg(not(target_arch = "wasm32"))]

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The crate's top-level modules, lowest layer first: a module may use those before it (and
/// those on its own line), never one after it.
const LAYERS: &[&[&str]] = &[
    &["math", "input", "work", "sections", "truth_fields"],
    &["rng"],
    &["machine"],
    &["signal"],
    &["plant"],
    &["estimation"],
    &["control"],
    &["safety"],
    &["protocol"],
    &["closed_loop"],
    &["log"],
    &["tuning", "hardware", "lessons"],
    &["charts"],
    &["cli", "web"],
];

type Module = Vec<String>;

/// Every module file under `src/` (the binaries apart), by module path.
fn modules(src: &Path) -> BTreeMap<Module, String> {
    let mut found = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                if path.file_name().is_some_and(|n| n != "bin") {
                    stack.push(path);
                }
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let relative = path.strip_prefix(src).unwrap().with_extension("");
            let mut module: Module = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if module.last().is_some_and(|m| m == "mod" || m == "lib") {
                module.pop();
            }
            found.insert(module, std::fs::read_to_string(&path).unwrap());
        }
    }
    found
}

/// The code of a file without its comments, the contents of its string and character literals,
/// and its `#[cfg(test)]` tests.
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < bytes.len() {
        let rest = &text[i..];
        if rest.starts_with("//") {
            i += rest.find('\n').unwrap_or(rest.len());
        } else if rest.starts_with("/*") {
            i += rest.find("*/").map_or(rest.len(), |e| e + 2);
        } else if rest.starts_with("r#\"") {
            i += rest.find("\"#").map_or(rest.len(), |e| e + 2);
            out.push_str("\"\"");
        } else if rest.starts_with('"') {
            // To the closing quote, past escaped ones.
            let mut j = 1;
            while j < rest.len() {
                match rest.as_bytes()[j] {
                    b'\\' => j += 2,
                    b'"' => break,
                    _ => j += 1,
                }
            }
            i += (j + 1).min(rest.len());
            out.push_str("\"\"");
        } else if rest.starts_with("'\"'") || rest.starts_with("'\\''") {
            i += if rest.starts_with("'\"'") { 3 } else { 4 };
        } else {
            let c = rest.chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths of a `use` tree or path expression starting at `text`: `a::b`, `a::{b, c::d}`.
fn paths_at(text: &str) -> Vec<Vec<String>> {
    let mut segments = Vec::new();
    let mut rest = text;
    loop {
        rest = rest.trim_start();
        if let Some(inner) = rest.strip_prefix('{') {
            // A group: each item is a path of its own below the prefix.
            let mut depth = 1;
            let end = inner
                .char_indices()
                .find(|&(_, c)| {
                    depth += match c {
                        '{' => 1,
                        '}' => -1,
                        _ => 0,
                    };
                    depth == 0
                })
                .map_or(inner.len(), |(i, _)| i);
            let mut items = Vec::new();
            let (mut level, mut start) = (0, 0);
            let group = &inner[..end];
            for (i, c) in group.char_indices() {
                match c {
                    '{' => level += 1,
                    '}' => level -= 1,
                    ',' if level == 0 => {
                        items.push(&group[start..i]);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            items.push(&group[start..]);
            return items
                .into_iter()
                .flat_map(paths_at)
                .map(|tail| segments.iter().cloned().chain(tail).collect())
                .collect();
        }
        let ident: String = rest.chars().take_while(|&c| is_ident(c)).collect();
        if ident.is_empty() {
            break;
        }
        rest = &rest[ident.len()..];
        segments.push(ident);
        match rest.trim_start().strip_prefix("::") {
            Some(after) => rest = after,
            None => break,
        }
    }
    if segments.is_empty() {
        Vec::new()
    } else {
        vec![segments]
    }
}

/// The module a path from `from` names: the longest known module its segments begin with.
fn resolve(
    known: &BTreeMap<Module, String>,
    from: &Module,
    is_module_file: bool,
    path: &[String],
) -> Option<Module> {
    let mut base: Module = Vec::new();
    let mut rest = path;
    match rest.first().map(String::as_str) {
        Some("crate") => rest = &rest[1..],
        Some("super") => {
            // `super` is the parent of the module, whether it is a file or a directory's mod.rs.
            let supers = path.iter().take_while(|s| *s == "super").count();
            base = from.clone();
            for _ in 0..supers {
                base.pop();
            }
            rest = &rest[supers..];
        }
        Some("self") => return None,
        Some(first) if is_module_file => {
            // A child of a module file, named without a prefix.
            let mut child = from.clone();
            child.push(first.to_string());
            if !known.contains_key(&child) {
                return None;
            }
            base = from.clone();
        }
        _ => return None,
    }
    let mut candidate = base;
    let mut best = None;
    if known.contains_key(&candidate) && !candidate.is_empty() {
        best = Some(candidate.clone());
    }
    for segment in rest {
        candidate.push(segment.clone());
        if known.contains_key(&candidate) {
            best = Some(candidate.clone());
        } else {
            break;
        }
    }
    best
}

/// Every module each module uses.
fn edges(known: &BTreeMap<Module, String>) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut graph = BTreeMap::new();
    for (module, text) in known {
        let is_module_file = known
            .keys()
            .any(|m| m.len() == module.len() + 1 && m.starts_with(module));
        let code = code_of(text);
        let mut targets = BTreeSet::new();
        let mut starts = Vec::new();
        for (i, _) in code.match_indices("crate::") {
            starts.push(i);
        }
        for (i, _) in code.match_indices("super::") {
            starts.push(i);
        }
        for (i, _) in code.match_indices("use ") {
            starts.push(i + 4);
        }
        for start in starts {
            // Only at the start of a path, not inside another identifier or path.
            let before = code[..start].chars().next_back();
            if before.is_some_and(|c| is_ident(c) || c == ':') {
                continue;
            }
            for path in paths_at(&code[start..]) {
                if let Some(target) = resolve(known, module, is_module_file, &path) {
                    if &target != module && !module.starts_with(&target) {
                        targets.insert(target);
                    }
                }
            }
        }
        graph.insert(module.clone(), targets);
    }
    graph
}

/// The cycles of `graph`: its strongly connected components of more than one module (Tarjan).
fn cycles(graph: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<Vec<Module>> {
    struct State<'a> {
        graph: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<&'a Module, usize>,
        low: BTreeMap<&'a Module, usize>,
        stack: Vec<&'a Module>,
        on_stack: BTreeSet<&'a Module>,
        found: Vec<Vec<Module>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a Module) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on_stack.insert(v);
        for w in s.graph.get(v).into_iter().flatten() {
            let Some((w, _)) = s.graph.get_key_value(w) else {
                continue;
            };
            if !s.index.contains_key(w) {
                visit(s, w);
                let low = s.low[v].min(s.low[w]);
                s.low.insert(v, low);
            } else if s.on_stack.contains(w) {
                let low = s.low[v].min(s.index[w]);
                s.low.insert(v, low);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                component.push(w.clone());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                s.found.push(component);
            }
        }
    }
    let mut state = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !state.index.contains_key(v) {
            visit(&mut state, v);
        }
    }
    state.found
}

fn name(module: &Module) -> String {
    module.join("::")
}

fn source() -> BTreeMap<Module, String> {
    modules(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"))
}

#[test]
fn no_module_imports_one_that_imports_it_back() {
    let graph = edges(&source());
    let found: Vec<String> = cycles(&graph)
        .iter()
        .map(|c| c.iter().map(name).collect::<Vec<_>>().join(" ↔ "))
        .collect();
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
    // The top-level modules too: each file may be acyclic while two directories use each other.
    let mut top: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (from, targets) in &graph {
        let Some(first) = from.first() else { continue };
        let entry = top.entry(vec![first.clone()]).or_default();
        for t in targets {
            if t[0] != *first {
                entry.insert(vec![t[0].clone()]);
            }
        }
    }
    let found: Vec<String> = cycles(&top)
        .iter()
        .map(|c| c.iter().map(name).collect::<Vec<_>>().join(" ↔ "))
        .collect();
    assert!(
        found.is_empty(),
        "cycles between top-level modules:\n{}",
        found.join("\n")
    );
}

#[test]
fn no_layer_reaches_up_into_a_higher_one() {
    let known = source();
    let rank = |m: &str| LAYERS.iter().position(|layer| layer.contains(&m));
    let mut upward = Vec::new();
    for (from, targets) in edges(&known) {
        let Some(first) = from.first() else { continue };
        let from_rank = rank(first).unwrap_or_else(|| panic!("{first} is in no layer of LAYERS"));
        for target in targets {
            let to_rank =
                rank(&target[0]).unwrap_or_else(|| panic!("{} is in no layer", target[0]));
            if to_rank > from_rank {
                upward.push(format!("{} uses {}", name(&from), name(&target)));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "imports from a lower layer into a higher one:\n{}",
        upward.join("\n")
    );
}

#[test]
fn the_checker_finds_what_it_is_meant_to() {
    // A planted cycle and an upward import, through every form of path the checker reads.
    let mut known = BTreeMap::new();
    let file = |t: &str| t.to_string();
    known.insert(
        vec!["a".to_string()],
        file("pub mod x;\npub mod y;\nuse x::X;\n"),
    );
    known.insert(
        vec!["a".to_string(), "x".to_string()],
        file("use super::{y::{Y, Z}};\n// use crate::b;\nfn f() { let s = \"crate::b\"; }\n"),
    );
    known.insert(
        vec!["a".to_string(), "y".to_string()],
        file("fn g() -> crate::a::x::X { todo!() }\n#[cfg(test)]\nmod tests { use crate::b; }\n"),
    );
    known.insert(vec!["b".to_string()], file(""));
    let graph = edges(&known);
    let x = vec!["a".to_string(), "x".to_string()];
    let y = vec!["a".to_string(), "y".to_string()];
    assert_eq!(graph[&x], BTreeSet::from([y.clone()]));
    assert_eq!(graph[&y], BTreeSet::from([x.clone()]));
    assert_eq!(graph[&vec!["a".to_string()]], BTreeSet::from([x.clone()]));
    assert_eq!(cycles(&graph).len(), 1);
}

#[test]
fn every_module_directory_lists_its_files() {
    // A directory's mod.rs opens with a table of its files, as src/lib.rs has for the crate: each
    // child module named in a `//! | …` row.
    let known = source();
    let mut missing = Vec::new();
    for (module, text) in &known {
        let children: Vec<&String> = known
            .keys()
            .filter(|m| m.len() == module.len() + 1 && m.starts_with(module))
            .map(|m| &m[module.len()])
            .collect();
        if module.is_empty() || children.is_empty() {
            continue;
        }
        let rows: Vec<&str> = text
            .lines()
            .take_while(|l| l.starts_with("//!"))
            .filter(|l| l.starts_with("//! |"))
            .collect();
        for child in children {
            let named = format!("`{child}`");
            if !rows.iter().any(|r| r.contains(&named)) {
                missing.push(format!("{}: no row for {child}", name(module)));
            }
        }
    }
    assert!(missing.is_empty(), "module tables:\n{}", missing.join("\n"));
}

/// The types, enums, traits and type aliases a file's code declares, with the line of each.
/// Associated types (`type Output = …` in an `impl`, `type Setting: Table` in a trait) are not
/// declarations of their own: a type alias counts only when public or at the file's top level.
fn declared_types(code: &str) -> Vec<(String, usize)> {
    let mut found = Vec::new();
    for (number, line) in code.lines().enumerate() {
        let trimmed = line.trim_start();
        let indented = trimmed.len() != line.len();
        let mut words = trimmed.split_whitespace().peekable();
        let mut public = false;
        while let Some(&word) = words.peek() {
            if word.starts_with("pub") {
                public = true;
                words.next();
            } else {
                break;
            }
        }
        let Some(keyword) = words.next() else {
            continue;
        };
        let counts = match keyword {
            "struct" | "enum" | "trait" | "union" => true,
            "type" => public || !indented,
            _ => false,
        };
        let Some(rest) = words.next() else { continue };
        let declared: String = rest.chars().take_while(|&c| is_ident(c)).collect();
        if counts && declared.starts_with(|c: char| c.is_ascii_uppercase()) {
            found.push((declared, number + 1));
        }
    }
    found
}

/// Each type name declared in more than one place, with the places.
fn shared_type_names(known: &BTreeMap<Module, String>) -> Vec<String> {
    let mut places: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for (module, text) in known {
        for (declared, line) in declared_types(&code_of(text)) {
            places
                .entry(declared)
                .or_default()
                .push(format!("{}:{line}", name(module)));
        }
    }
    places
        .into_iter()
        .filter(|(_, at)| at.len() > 1)
        .map(|(declared, at)| format!("{declared}: {}", at.join(", ")))
        .collect()
}

#[test]
fn no_two_types_share_a_name() {
    let shared = shared_type_names(&source());
    assert!(
        shared.is_empty(),
        "type names declared twice (rename one, or make them one type):\n{}",
        shared.join("\n")
    );
}

#[test]
fn the_name_checker_finds_a_shared_name() {
    let mut known = BTreeMap::new();
    known.insert(
        vec!["a".to_string()],
        "pub struct Fit;\nimpl Iterator for Fit {\n    type Item = u8;\n}\n".to_string(),
    );
    known.insert(
        vec!["b".to_string()],
        "pub(crate) enum Fit {}\ntrait T {\n    type Item;\n}\n#[cfg(test)]\nmod tests { struct T; }\n"
            .to_string(),
    );
    assert_eq!(shared_type_names(&known), vec!["Fit: a:1, b:1".to_string()]);
}
