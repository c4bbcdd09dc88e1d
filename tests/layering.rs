//! The layering DESIGN.md promises, checked on the source: which module
//! imports which, read from every `crate::`, `super::` and (in the binary)
//! `ridgeline::` path in `src/`.
//!
//! - No top-level module imports a module that imports it, directly or
//!   through others.
//! - No module imports one of a later layer (the list in DESIGN.md's
//!   "Layout"): the core never reaches up into the GL layer or the display.
//! - Inside a module, no two sibling files import each other (through any
//!   chain of siblings).
//!
//! `cargo test --test layering -- --nocapture` prints the module graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// DESIGN.md's layers, lowest first. A module may import modules of its own
/// layer or of earlier ones.
const LAYERS: &[&[&str]] = &[
    &["geo", "earth", "node", "allocator", "camera", "spill", "hash"],
    &["mesh", "dem", "pyramid", "procedural"],
    &["clipmap", "lod", "tiles", "meshes", "dataset"],
    &["render", "clusters", "symbology"],
    &["scene", "pipeline"],
    &["accuracy", "flight", "input"],
    &["gl"],
    &["display"],
    &["cli"],
];

type Graph = BTreeMap<String, BTreeSet<String>>;

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut entries: Vec<_> =
        std::fs::read_dir(dir).expect("read src").map(|e| e.expect("dir entry").path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files
}

/// The module path of a file: `src/a/b.rs` is `[a, b]`, `src/a/mod.rs` is
/// `[a]`; `lib.rs` and `main.rs` are the root. `src/main.rs`'s `cli` module
/// counts as a top-level module of its own.
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let relative = file.strip_prefix(src).expect("file under src");
    let mut parts: Vec<String> =
        relative.iter().map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// The code of a file without comments (doc links are not imports).
fn code_of(text: &str) -> String {
    text.lines().map(|line| line.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The paths a `use`-style tail names: `a::b`, `a::{b, c::d}`, `{a, b::c}`.
/// Only the first two segments of each matter here.
fn paths_in(tail: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    collect_paths(tail.trim_start(), Vec::new(), &mut out);
    out
}

fn collect_paths(text: &str, prefix: Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let mut path = prefix.clone();
    let mut at = 0;
    let bytes: Vec<char> = text.chars().collect();
    loop {
        while at < bytes.len() && bytes[at].is_whitespace() {
            at += 1;
        }
        if at < bytes.len() && bytes[at] == '{' {
            at += 1;
            loop {
                at += collect_paths(&bytes[at..].iter().collect::<String>(), path.clone(), out);
                while at < bytes.len() && bytes[at].is_whitespace() {
                    at += 1;
                }
                match bytes.get(at) {
                    Some(',') => at += 1,
                    Some('}') => return at + 1,
                    _ => return at,
                }
                while at < bytes.len() && bytes[at].is_whitespace() {
                    at += 1;
                }
                if bytes.get(at) == Some(&'}') {
                    return at + 1;
                }
            }
        }
        let start = at;
        while at < bytes.len() && is_ident(bytes[at]) {
            at += 1;
        }
        if at == start {
            break;
        }
        path.push(bytes[start..at].iter().collect());
        if bytes.get(at) == Some(&':') && bytes.get(at + 1) == Some(&':') {
            at += 2;
        } else {
            break;
        }
    }
    if path.len() > prefix.len() {
        out.push(path);
    }
    at
}

/// Every module path a file refers to, resolved from the crate root.
fn references(module: &[String], code: &str, in_binary: bool) -> Vec<Vec<String>> {
    let mut refs = Vec::new();
    let roots: &[&str] = if in_binary { &["crate::", "ridgeline::"] } else { &["crate::"] };
    for root in roots.iter().copied().chain(["super::"]) {
        let mut from = 0;
        while let Some(found) = code[from..].find(root) {
            let at = from + found;
            from = at + root.len();
            if code[..at].chars().next_back().is_some_and(is_ident) {
                continue; // e.g. `mycrate::`
            }
            let base: Vec<String> = match root {
                "super::" => module[..module.len().saturating_sub(1)].to_vec(),
                "ridgeline::" => Vec::new(),
                _ if in_binary => vec!["cli".to_string()], // the binary's crate:: is main.rs
                _ => Vec::new(),
            };
            for tail in paths_in(&code[from..]) {
                let tail: Vec<String> = tail.into_iter().filter(|s| s != "super").collect();
                let mut path = base.clone();
                path.extend(tail);
                refs.push(path);
            }
        }
    }
    refs
}

struct Graphs {
    /// Top-level module -> top-level modules it imports.
    top: Graph,
    /// (Top-level module, submodule) -> sibling submodules it imports.
    siblings: BTreeMap<String, Graph>,
}

fn graphs() -> Graphs {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = rust_files(&src);
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_path(&src, f)).collect();
    let mut top = Graph::new();
    let mut siblings: BTreeMap<String, Graph> = BTreeMap::new();
    for file in &files {
        let in_binary = file.starts_with(src.join("cli")) || file.ends_with("main.rs");
        let mut module = module_path(&src, file);
        if in_binary && module.first().map(String::as_str) != Some("cli") {
            module.insert(0, "cli".to_string());
        }
        let Some(own) = module.first().cloned() else { continue };
        top.entry(own.clone()).or_default();
        let code = code_of(&std::fs::read_to_string(file).expect("read source"));
        for reference in references(&module, &code, in_binary) {
            let Some(target) = reference.first() else { continue };
            let is_module = modules.contains(&reference[..1]) || target == "cli";
            if target != &own && is_module {
                top.entry(own.clone()).or_default().insert(target.clone());
            }
            // Sibling files: module [own, a, ..] naming [own, b, ..], b != a.
            if target == &own && module.len() >= 2 && reference.len() >= 2 {
                let (from, to) = (&module[1], &reference[1]);
                if from != to && modules.contains(&[own.clone(), to.clone()][..]) {
                    let graph = siblings.entry(own.clone()).or_default();
                    graph.entry(from.clone()).or_default().insert(to.clone());
                }
            }
        }
    }
    Graphs { top, siblings }
}

/// A cycle through `start`, if there is one.
fn cycle_from(graph: &Graph, start: &str) -> Option<Vec<String>> {
    fn walk(graph: &Graph, at: &str, start: &str, path: &mut Vec<String>) -> bool {
        for next in graph.get(at).into_iter().flatten() {
            if next == start {
                return true;
            }
            if !path.contains(next) {
                path.push(next.clone());
                if walk(graph, next, start, path) {
                    return true;
                }
                path.pop();
            }
        }
        false
    }
    let mut path = vec![start.to_string()];
    walk(graph, start, start, &mut path).then(|| {
        path.push(start.to_string());
        path
    })
}

fn cycles(graph: &Graph) -> Vec<String> {
    graph.keys().filter_map(|m| cycle_from(graph, m)).map(|c| c.join(" -> ")).collect()
}

#[test]
fn the_module_graph_is_printed_and_has_every_module() {
    let graphs = graphs();
    for (module, imports) in &graphs.top {
        let list: Vec<&str> = imports.iter().map(String::as_str).collect();
        println!("{module:>10} -> {}", list.join(", "));
    }
    let unplaced: Vec<&String> = graphs.top.keys().filter(|m| layer_of(m).is_none()).collect();
    assert!(unplaced.is_empty(), "modules missing from LAYERS (and DESIGN.md): {unplaced:?}");
    // The parser must see the imports that certainly exist.
    assert!(graphs.top["pipeline"].contains("scene"), "{:?}", graphs.top["pipeline"]);
    assert!(graphs.top["gl"].contains("render"), "{:?}", graphs.top["gl"]);
    assert!(graphs.top["cli"].contains("display"), "{:?}", graphs.top["cli"]);
}

#[test]
fn no_top_level_module_imports_a_module_that_imports_it() {
    let found = cycles(&graphs().top);
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

#[test]
fn no_module_imports_a_later_layer() {
    let mut wrong = Vec::new();
    for (module, imports) in &graphs().top {
        let Some(own) = layer_of(module) else { continue };
        for import in imports {
            if layer_of(import).is_some_and(|layer| layer > own) {
                wrong.push(format!("{module} (layer {}) imports {import}", own + 1));
            }
        }
    }
    assert!(wrong.is_empty(), "imports against the layering:\n{}", wrong.join("\n"));
}

#[test]
fn no_sibling_files_import_each_other() {
    let mut found = Vec::new();
    for (module, graph) in &graphs().siblings {
        found.extend(cycles(graph).into_iter().map(|c| format!("{module}: {c}")));
    }
    assert!(found.is_empty(), "cycles between sibling files:\n{}", found.join("\n"));
}

#[test]
fn the_parser_reads_grouped_and_nested_imports() {
    let paths = paths_in("a::{b::C, d, e::{f, g::H}};");
    let want: Vec<Vec<&str>> =
        vec![vec!["a", "b", "C"], vec!["a", "d"], vec!["a", "e", "f"], vec!["a", "e", "g", "H"]];
    assert_eq!(paths, want);
    let module = vec!["pyramid".to_string(), "build".to_string()];
    let refs = references(&module, "use super::format::X; let y = crate::node::f();", false);
    assert!(refs.contains(&vec!["pyramid".into(), "format".into(), "X".into()]), "{refs:?}");
    assert!(refs.contains(&vec!["node".into(), "f".into()]), "{refs:?}");
    // A cycle is found, and only a cycle.
    let mut graph = Graph::new();
    graph.entry("a".into()).or_default().insert("b".into());
    graph.entry("b".into()).or_default().insert("c".into());
    assert!(cycles(&graph).is_empty());
    graph.entry("c".into()).or_default().insert("a".into());
    assert_eq!(cycle_from(&graph, "a").unwrap(), ["a", "b", "c", "a"]);
}
